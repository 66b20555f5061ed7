"""How well a ``--path`` run walked its path, against the ground truth (``shc analyze``).

The follower steers by the odometry; these measures hold the **ground truth** (the simulator's body pose, or a
plan's ideal path) against the path, both in the odometry frame: the truth is placed so that where the follower
started (``summary.path_start_cycle``) it is where the odometry was (the origin, for a path given at the start).

* ``cross_track_rms_m`` — RMS over the cycles from the follower's start to the goal (the last waypoint left, else
  the run's end) of the body's distance to the segment it was walking (from the previous waypoint — for the first,
  where the follower started — to the current one; the distance to the segment's nearest point, so running past a
  waypoint counts too).
* ``waypoints_reached`` / ``waypoints_total`` — waypoints where, when the follower moved on from them, the truth
  was within the run's tolerance (``path_tolerance_m``) and, when a heading was asked, its heading within
  ``path_heading_tolerance_rad``.
* ``time_to_goal_s`` — from the follower's start to its leaving the last waypoint, when the follower reached it
  (by its odometry; ``None`` otherwise): how long the walk took, whatever its accuracy.
* ``waypoint_errors_m`` / ``waypoint_heading_errors_deg`` — per waypoint, the truth's distance and heading error
  when the follower moved on (``None``: it never did).

A run without ground truth (``run-hw``: ``x`` among the summary's ``unmeasured``) gives the follower's own counts
and no cross-track figure.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from shc_cli.record.runread import RunLog

PATH_KEYS = ("cross_track_rms_m", "waypoints_reached", "waypoints_total", "time_to_goal_s")
"""The path measures every ``shc analyze`` result has (``None`` for a run without a path)."""


def segment_distance(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Distance of each point ``(N, 2)`` to the segment ``start``–``end`` [m] (to ``start`` when they coincide)."""
    span = end - start
    length2 = float(span @ span)
    share = np.zeros(len(points)) if length2 == 0.0 else np.clip((points - start) @ span / length2, 0.0, 1.0)
    nearest = start + share[:, None] * span
    return np.asarray(np.linalg.norm(points - nearest, axis=1))


def truth_in_odometry_frame(run: RunLog, start_row: int) -> tuple[np.ndarray, np.ndarray]:
    """The body's ground-truth xy ``(N, 2)`` [m] and yaw ``(N,)`` [rad] in the odometry frame: placed so that its
    pose before the row ``start_row`` is the odometry's pose there (the origin for a run logged without odometry,
    or a path given at the run's start)."""
    before = max(start_row - 1, 0)
    origin, heading = run.position[before, :2], float(run.rpy[before, 2])
    c, s = math.cos(heading), math.sin(heading)
    shifted = run.position[:, :2] - origin
    xy = np.column_stack([c * shifted[:, 0] + s * shifted[:, 1], -s * shifted[:, 0] + c * shifted[:, 1]])
    yaw = np.unwrap(run.rpy[:, 2]) - heading
    if run.odometry is not None:
        ox, oy, oyaw = (float(v) for v in run.odometry[before])
        c, s = math.cos(oyaw), math.sin(oyaw)
        xy = np.column_stack([ox + c * xy[:, 0] - s * xy[:, 1], oy + s * xy[:, 0] + c * xy[:, 1]])
        yaw = yaw + oyaw
    return xy, yaw


def path_measures(run: RunLog) -> dict[str, Any]:
    """The path measures of ``run`` (module docstring); every key ``None`` for a run without a path."""
    out: dict[str, Any] = dict.fromkeys(PATH_KEYS)
    summary = run.summary
    waypoints = summary.waypoints
    if not waypoints or summary.path_start_cycle is None:
        return out
    out["waypoints_total"] = len(waypoints)
    tolerance = summary.path_tolerance_m or 0.05
    heading_tolerance = summary.path_heading_tolerance_rad or math.radians(3.0)
    start, dt, rows = summary.path_start_cycle, run.dt, len(run.t)
    if "x" in (summary.unmeasured or []) or start >= rows:  # no ground truth: the follower's own view
        out["waypoints_reached"] = sum(w.reached for w in waypoints)
        last = waypoints[-1]
        out["time_to_goal_s"] = last.left_s if last.reached else None
        out["measured_by"] = "odometry"
        return out
    xy, yaw = truth_in_odometry_frame(run, start)
    row_of = [None if w.left_s is None else min(start + round(w.left_s / dt), rows - 1) for w in waypoints]
    errors: list[float | None] = []
    heading_errors: list[float | None] = []
    reached = 0
    squares: list[np.ndarray] = []
    previous = run.odometry[max(start - 1, 0), :2] if run.odometry is not None else np.zeros(2)
    begin = start
    for waypoint, row in zip(waypoints, row_of, strict=True):
        target = np.array([waypoint.x, waypoint.y])
        end = rows - 1 if row is None else row
        if end >= begin:
            squares.append(segment_distance(xy[begin:end + 1], previous, target) ** 2)
        if row is None:
            errors.append(None)
            heading_errors.append(None)
            break
        error = float(np.linalg.norm(xy[row] - target))
        heading = None if waypoint.yaw is None else math.degrees(
            math.atan2(math.sin(waypoint.yaw - yaw[row]), math.cos(waypoint.yaw - yaw[row])))
        errors.append(error)
        heading_errors.append(heading)
        if waypoint.reached and error <= tolerance and (heading is None or
                                                       abs(math.radians(heading)) <= heading_tolerance):
            reached += 1
        previous, begin = target, row + 1
    errors += [None] * (len(waypoints) - len(errors))
    heading_errors += [None] * (len(waypoints) - len(heading_errors))
    walked = np.concatenate(squares) if squares else np.zeros(0)
    out["cross_track_rms_m"] = float(np.sqrt(walked.mean())) if len(walked) else None
    out["waypoints_reached"] = reached
    last = waypoints[-1]
    out["time_to_goal_s"] = last.left_s if last.reached else None
    out["waypoint_errors_m"] = errors
    out["waypoint_heading_errors_deg"] = heading_errors
    out["measured_by"] = "ground truth"
    return out
