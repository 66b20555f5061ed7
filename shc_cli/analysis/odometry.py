"""How far the controller's leg odometry drifts from the ground truth (``shc analyze``'s odometry measures).

Both paths are compared in the odom frame of the analysis window: each is re-expressed relative to its own pose
when the window began (the row before its first row), so start-up settling before the window does not count.

* ``odometry_drift_percent`` — horizontal distance between the odometry's and the truth's end positions, in % of
  the distance the body walked (length of the ground-truth path over the window);
* ``odometry_heading_error_deg`` — |odometry yaw − true yaw| at the end, wrapped to [0°, 180°].

The truth is the simulator's body pose (``simulate``), or the ideal body path (``plan``: the desired velocity
integrated). A run without a ground truth (``run-hw``: its body columns are unmeasured) or without odometry
columns (logged before they existed) gives ``None``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from shc_cli.record.runread import RunLog


@dataclass(frozen=True)
class Tracks:
    """The ground truth and the odometry over a window, in its odom frame (both start at the origin, heading 0).

    Attributes:
        truth: ground-truth planar pose (x, y [m], yaw [rad]) ``(K, 3)``.
        odometry: leg odometry's pose ``(K, 3)``.
    """

    truth: np.ndarray
    odometry: np.ndarray


def relative(poses: np.ndarray) -> np.ndarray:
    """Planar poses ``(K, 3)`` (x, y, yaw) expressed in the frame of the first one; yaw unwrapped."""
    x0, y0, yaw0 = poses[0]
    c, s = math.cos(yaw0), math.sin(yaw0)
    dx, dy = poses[:, 0] - x0, poses[:, 1] - y0
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy, np.unwrap(poses[:, 2]) - yaw0])


def has_ground_truth(run: RunLog) -> bool:
    """Whether the run's body pose is a ground truth (not the zeros of an unmeasured real robot)."""
    return not (run.summary.unmeasured and "x" in run.summary.unmeasured)


def tracks(run: RunLog, rows: np.ndarray) -> Tracks | None:
    """Truth and odometry over the window ``rows`` (ascending), from the row before it; None without both."""
    if run.odometry is None or len(rows) < 2 or not has_ground_truth(run):
        return None
    span = np.arange(max(rows[0] - 1, 0), rows[-1] + 1)
    truth = np.column_stack([run.position[span, :2], run.rpy[span, 2]])
    return Tracks(relative(truth), relative(run.odometry[span]))


def odometry_errors(found: Tracks) -> tuple[float | None, float]:
    """(drift in % of the distance walked — None when the body did not move, heading error [deg]) at the end."""
    walked = float(np.linalg.norm(np.diff(found.truth[:, :2], axis=0), axis=1).sum())
    error = float(np.linalg.norm(found.odometry[-1, :2] - found.truth[-1, :2]))
    heading = abs(math.remainder(float(found.odometry[-1, 2] - found.truth[-1, 2]), 2.0 * math.pi))
    return (100.0 * error / walked if walked > 1e-6 else None), math.degrees(heading)
