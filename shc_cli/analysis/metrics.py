"""The numbers legged-robotics papers report, from one run log.

* Cost of transport, OpenSHC paper eq. 22: ``CoT = P̄ / (m·g·Δx/Δt)`` — mean electrical power over the window
  divided by weight times the speed from the body's horizontal displacement over that window.
* Static stability margin: horizontal distance from the whole robot's centre of mass to the nearest edge of the
  support polygon (the convex hull of the feet in contact), positive inside.
* ZMP (ATHENA eq. 32): the normal-force weighted mean of the contact feet; its margin (eq. 33) is the distance to
  the nearest support-polygon edge, and its distance to the polygon's centroid is ATHENA Fig. 18a's measure.
* Per gait cycle (ATHENA §5.2): the RMS of body height, roll rate and pitch rate over each gait cycle, summarised
  by median and interquartile range over the cycles.

Distances to an edge are to the edge's line: exact for a point inside a convex polygon (the margin), a lower
bound of the true distance outside it (then negative).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from shc_cli.analysis.cot import cost_of_transport
from shc_cli.record.runread import RunLog
from shc_cli.spec.metric_names import ANALYZE_KEYS


@dataclass(frozen=True)
class Window:
    """Which cycles to analyse: RUNNING cycles, after ``skip_s`` seconds of running, and with ``steady`` only those
    where the controller's desired velocity has not changed for a whole gait cycle while moving."""

    skip_s: float = 0.0
    steady: bool = False


def body_speeds(xy: np.ndarray, span_s: float) -> tuple[float, float]:
    """The two mean speeds of a horizontal body path ``xy`` [m] ``(N, 2)`` (its first row where the window began)
    over ``span_s`` [s]: the **path speed** (length of the path travelled / time — what a speedometer shows) and the
    **displacement speed** (straight-line distance from start to end / time — what a turning path shortens; the
    speed in paper eq. 22's cost of transport). Both 0 for an empty span."""
    if span_s <= 0.0 or len(xy) < 2:
        return 0.0, 0.0
    path = float(np.linalg.norm(np.diff(xy, axis=0), axis=1).sum())
    displacement = float(np.linalg.norm(xy[-1] - xy[0]))
    return path / span_s, displacement / span_s


def window_path(xy: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The horizontal body path over the window ``rows`` (ascending row indices) of a logged path ``xy`` ``(N, 2)``
    [m] whose rows are positions after each cycle: it starts where the row before the window ended."""
    if len(rows) == 0:
        return np.zeros((0, 2))
    return np.vstack([xy[max(rows[0] - 1, 0)], xy[rows[0]:rows[-1] + 1]])


@dataclass(frozen=True)
class WalkFigures:
    """Speeds, power and cost of transport of a run over a window of its rows: what its ``summary.json`` and
    ``shc analyze`` report, computed once (:func:`walk_figures`).

    Attributes:
        span_s: the window's duration [s].
        distance_m: straight-line horizontal distance from where the window began to where it ended [m].
        forward_distance_m: the same along the world x axis [m].
        displacement_speed_mps: ``distance_m`` / ``span_s`` [m/s] (paper eq. 22's speed).
        path_speed_mps: length of the body's path / ``span_s`` [m/s].
        commanded_speed_mps: mean horizontal desired velocity after the limits [m/s].
        mean_power_w: mean total servo power [W]; ``None`` for a run without power (a plan).
        mass_kg: the simulated body's mass (:func:`shc_cli.model.body.body_mass`) [kg].
        walked_m: the distance walked: the length of the body's path sampled once per gait cycle
            (:func:`shc_cli.analysis.progress.cycle_path_length`: it follows a curve or a closed path, not the
            body's sway within a step) [m].
        cot: paper eq. 22 ``P̄ / (m·g·v)`` with ``v`` the distance walked over the window; ``None`` when not walking
            on the ground, without power, or the body hardly moved.
        cot_displacement: the same with ``v`` the displacement speed (start to end in a straight line: a path that
            returns to its start has none).
    """

    span_s: float
    distance_m: float
    forward_distance_m: float
    displacement_speed_mps: float
    path_speed_mps: float
    commanded_speed_mps: float
    mean_power_w: float | None
    mass_kg: float
    walked_m: float
    cot: float | None
    cot_displacement: float | None


def walk_figures(run: RunLog, rows: np.ndarray, walking: bool, period: int | None = None) -> WalkFigures:
    """:class:`WalkFigures` of ``run`` over ``rows`` (ascending row indices; the cost of transport only when
    ``walking``: scenario WG). Fewer than two rows are no walk: distances and speeds 0 (a robot thrown off the
    floor at start-up, caught by the fall check in its first RUNNING cycle, once had 7 m/s). ``period``: the gait
    period in cycles for the distance walked (default: the gait the summary names, :func:`_period`). A window that
    made no progress (:func:`shc_cli.analysis.progress.progress_fields`: the summary's NO PROGRESS) has no cost of
    transport either: its power over a speed near zero means nothing, and the summary line, ``summary.json`` and
    ``shc analyze`` say so alike."""
    from shc_cli.analysis.progress import cycle_path_length, progress_fields
    from shc_cli.model.body import body_mass

    dt = run.dt
    mass = body_mass(run.robot)
    commanded = float(np.linalg.norm(run.desired[rows, :2], axis=1).mean()) if len(rows) else 0.0
    power = float(run.power[rows].mean()) if run.power is not None and len(rows) else None
    if len(rows) < 2:
        return WalkFigures(len(rows) * dt, 0.0, 0.0, 0.0, 0.0, commanded, power, mass, 0.0, None, None)
    span = (rows[-1] - rows[0] + 1) * dt
    path = window_path(run.position[:, :2], rows)
    path_speed, speed = body_speeds(path, span)
    walked = cycle_path_length(path, _period(run) if period is None else period)
    measured = walking and power is not None
    cot = cost_of_transport(power, mass, walked / span) if measured and power is not None else None  # eq. 22
    cot_displacement = cost_of_transport(power, mass, speed) if measured and power is not None else None
    if cot is not None and progress_fields(walked, commanded, len(rows) * dt)["no_progress"]:
        cot = cot_displacement = None
    return WalkFigures(span, speed * span, float(path[-1, 0] - path[0, 0]), speed, path_speed, commanded, power,
                       mass, walked, cot, cot_displacement)


def window_mask(run: RunLog, window: Window) -> np.ndarray:
    """Boolean mask of the analysed cycles."""
    mask = run.running.copy()
    if not mask.any():
        return mask
    first = int(np.argmax(mask))
    skip = round(window.skip_s / run.dt)
    mask[first:first + skip] = False
    if window.steady:
        period = max(run.summary.step_period_cycles or 1, 1)
        same = np.zeros_like(mask)
        if period < len(mask):
            same[period:] = np.abs(run.desired[period:] - run.desired[:-period]).max(axis=1) < 1e-9
        mask &= same & (run.walk_state == "MOVING")
    return mask


def support_polygon(points: np.ndarray) -> np.ndarray:
    """Convex hull of 2-D points, counter-clockwise, ``(k, 2)`` (monotone chain; duplicates and collinear points
    dropped)."""
    pts = sorted({(float(x), float(y)) for x, y in points})
    if len(pts) <= 2:
        return np.array(pts).reshape(-1, 2)

    def cross(o: tuple[float, float], a: tuple[float, float], b: tuple[float, float]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, float]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 0:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, float]] = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 0:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def edge_margin(polygon: np.ndarray, point: np.ndarray) -> float:
    """Signed distance from ``point`` to the nearest edge line of a counter-clockwise convex polygon [m]: positive
    inside. With fewer than three vertices there is no area to be inside: minus the distance to the segment or
    point (``nan`` for no vertex)."""
    if len(polygon) == 0:
        return math.nan
    if len(polygon) < 3:
        a = polygon[0]
        b = polygon[-1]
        ab = b - a
        s = 0.0 if not ab.any() else float(np.clip(np.dot(point - a, ab) / np.dot(ab, ab), 0.0, 1.0))
        return -float(np.linalg.norm(point - (a + s * ab)))
    a = polygon
    edge = _following(polygon) - a
    length = np.sqrt(np.add.reduce(edge * edge, axis=1))  # np.linalg.norm(edge, axis=1) without its overhead
    real = length > 0.0  # a hull may repeat a vertex (points closer than float resolution): no edge there
    if not real.any():
        return -float(np.linalg.norm(point - a[0]))
    a, edge, length = a[real], edge[real], length[real]
    signed = (edge[:, 0] * (point[1] - a[:, 1]) - edge[:, 1] * (point[0] - a[:, 0])) / length
    return float(signed.min())


def _following(values: np.ndarray) -> np.ndarray:
    """Each row's next row, the last's the first: ``np.roll(values, -1, axis=0)`` (the same copy, a fifth of the
    cost; the margins run once per logged cycle)."""
    return np.concatenate((values[1:], values[:1]))


def polygon_centroid(polygon: np.ndarray) -> np.ndarray:
    """Area centroid of a convex polygon (the vertex mean below three vertices)."""
    if len(polygon) < 3:
        return np.asarray(polygon.mean(axis=0))
    x, y = polygon[:, 0], polygon[:, 1]
    xn, yn = _following(x), _following(y)
    cross = x * yn - xn * y
    area = cross.sum() / 2.0
    if abs(area) < 1e-12:
        return np.asarray(polygon.mean(axis=0))
    return np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / float(6.0 * area)


def rotation_rpy(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrices body → world from roll, pitch, yaw (``Rz·Ry·Rx``), ``(N, 3, 3)`` (scipy; off the hot
    path). The inverse is :func:`rpy_of`."""
    from scipy.spatial.transform import Rotation

    return np.asarray(Rotation.from_euler("xyz", np.asarray(rpy, dtype=float)).as_matrix())


def rpy_of(rotation: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw of ``Rz·Ry·Rx`` matrices ``(N, 3, 3)`` → ``(N, 3)`` [rad]."""
    from scipy.spatial.transform import Rotation

    return np.asarray(Rotation.from_matrix(np.asarray(rotation, dtype=float)).as_euler("xyz"))


def feet_and_com(run: RunLog, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """World positions of the feet ``(M, L, 3)`` and of the whole robot's centre of mass ``(M, 3)`` [m] at the
    given cycles, from the logged joints and body pose (link masses at segment midpoints, as in the generated
    URDF; feet at the DH tips)."""
    from shc_cli.model.body import FOOT_MASS, link_mass
    from shc_cli.model.chains import Chains

    robot = run.robot
    chains = Chains.from_robot(robot)
    legs = len(robot.legs)
    origins = chains.frames_in_base(run.joints[rows])[..., :3, 3]  # (rows, L, n + 1, 3) in base_link
    width = chains.joints
    masses = np.zeros((legs, width + 1))
    for i, leg in enumerate(robot.legs.values()):
        for k, joint in enumerate(leg.joints.values()):
            masses[i, k] = link_mass(joint)
        masses[i, width] = FOOT_MASS
    segment_mid = np.concatenate([(origins[:, :, :-1] + origins[:, :, 1:]) / 2.0, origins[:, :, -1:]], axis=2)
    weighted = (segment_mid * masses[None, :, :, None]).sum(axis=(1, 2))
    body_mass = robot.body.mass
    total = body_mass + masses.sum()
    com_body = (weighted + body_mass * np.asarray(robot.body.com)) / total
    tips = origins[:, :, -1]
    rotation = rotation_rpy(run.rpy[rows])
    position = run.position[rows]
    feet = np.einsum("mij,mlj->mli", rotation, tips) + position[:, None, :]
    com = np.einsum("mij,mj->mi", rotation, com_body) + position
    return feet, com


def foot_slip(feet: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Per foot, how far it moved horizontally between consecutive samples both in contact [m] (``feet``: (N, legs,
    3) world positions, ``contact``: (N, legs))."""
    both = contact[1:] & contact[:-1]
    moved = np.linalg.norm(feet[1:, :, :2] - feet[:-1, :, :2], axis=2)
    result: np.ndarray = (moved * both).sum(axis=0)
    return result


def _median_iqr(values: np.ndarray) -> tuple[float | None, float | None]:
    values = values[np.isfinite(values)]
    if len(values) == 0:
        return None, None
    q1, median, q3 = np.percentile(values, [25, 50, 75])
    return float(median), float(q3 - q1)


def per_cycle_rms(values: np.ndarray, period: int) -> np.ndarray:
    """RMS of ``values`` over each whole gait cycle of ``period`` samples (a last partial cycle is dropped)."""
    cycles = len(values) // max(period, 1)
    if cycles == 0:
        return np.zeros(0)
    block = values[:cycles * period].reshape(cycles, period)
    return np.asarray(np.sqrt((block * block).mean(axis=1)))


def _before(run: RunLog, row: int) -> np.ndarray:
    """Horizontal body position when cycle ``row`` began: the row before's (each row is logged after its cycle)."""
    return np.asarray(run.position[max(row - 1, 0), :2])


def _period(run: RunLog) -> int:
    """Gait period in cycles from the robot and the gait the summary names (0 if that gait cannot be loaded)."""
    from shc_cli.control.gait import step_cycle
    from shc_cli.errors import ShcError
    from shc_cli.spec.loading import load_gait

    try:
        gait = load_gait(run.summary.gait or run.robot.walker.gait).gait
    except ShcError:
        return 0
    if gait is None:
        return 0
    frequency = float(run.summary.step_frequency_hz or run.robot.walker.step_frequency.default)
    return step_cycle(gait, frequency, run.dt).period


def analyze_run(run: RunLog, window: Window = Window()) -> dict[str, Any]:
    """Every metric of one run over the window; keys documented in docs/commands.md (``shc analyze``)."""
    mask = window_mask(run, window)
    rows = np.flatnonzero(mask)
    dt = run.dt
    summary = run.summary
    out: dict[str, Any] = {
        "run": str(run.path), "kind": run.kind, "robot": run.robot.name, "gait": summary.gait,
        "scenario": summary.scenario or "plan",
        "step_frequency_hz": (summary.step_frequency_hz if "step_frequency_hz" in summary.model_fields_set
                              else run.robot.walker.step_frequency.default),
        "window_s": len(rows) * dt, "window_start_s": float(run.t[rows[0]]) if len(rows) else None,
    }
    out.update(dict.fromkeys(ANALYZE_KEYS))
    if len(rows) < 2:
        return out
    walking = (summary.scenario or "WG") == "WG"
    figures = walk_figures(run, rows, walking, summary.step_period_cycles or _period(run))
    speed, commanded = figures.displacement_speed_mps, figures.commanded_speed_mps
    # mean_speed_mps: the displacement speed under its first name (sweep tables and older readers use it)
    out.update(distance_m=figures.distance_m, walked_m=figures.walked_m,
               displacement_speed_mps=speed, path_speed_mps=figures.path_speed_mps,
               mean_speed_mps=speed, commanded_speed_mps=commanded,
               speed_ratio=float(speed / commanded) if commanded > 1e-9 else None)
    steady = rows if window.steady else np.flatnonzero(window_mask(run, Window(window.skip_s, steady=True)))
    if len(steady) >= 2:
        moved = np.linalg.norm(run.position[steady[-1], :2] - _before(run, steady[0]))
        out["steady_speed_mps"] = float(moved / ((steady[-1] - steady[0] + 1) * dt))
    if run.power is not None:
        out["mean_power_w"], out["cot"] = figures.mean_power_w, figures.cot
        out["cot_displacement"] = figures.cot_displacement
    from shc_cli.analysis.joint_limits import joint_limit_fraction

    out["joint_limit_fraction"] = joint_limit_fraction(run, rows)
    contact = run.contact[rows]
    per_leg = contact.mean(axis=0)
    out["duty_factor"] = float(per_leg.mean())
    out["duty_factor_per_leg"] = {leg: float(v) for leg, v in zip(run.legs, per_leg, strict=True)}

    feet, com = feet_and_com(run, rows)
    slip = foot_slip(feet, contact)
    out["foot_slip_m"] = float(slip.mean())
    out["foot_slip_per_leg_m"] = {leg: float(v) for leg, v in zip(run.legs, slip, strict=True)}

    margins = np.full(len(rows), np.nan)
    zmp_margin = np.full(len(rows), np.nan)
    zmp_centre = np.full(len(rows), np.nan)
    zmp = np.full((len(rows), 2), np.nan)
    forces = run.foot_force[rows] if run.foot_force is not None else None
    for i in range(len(rows)):
        down = contact[i]
        if not down.any():
            continue
        polygon = support_polygon(feet[i, down, :2])
        margins[i] = edge_margin(polygon, com[i, :2])
        if forces is not None and forces[i, down].sum() > 0.0:
            weights = forces[i, down]
            zmp[i] = (feet[i, down, :2] * weights[:, None]).sum(axis=0) / weights.sum()  # eq. 32
            zmp_margin[i] = edge_margin(polygon, zmp[i])  # eq. 33
            zmp_centre[i] = float(np.linalg.norm(zmp[i] - polygon_centroid(polygon)))
    out["stability_margin_median_m"], _ = _median_iqr(margins)
    out["stability_margin_min_m"] = float(np.nanmin(margins)) if np.isfinite(margins).any() else None
    if forces is not None:
        out["zmp_margin_median_m"], out["zmp_margin_iqr_m"] = _median_iqr(zmp_margin)
        out["zmp_centre_distance_median_m"], out["zmp_centre_distance_iqr_m"] = _median_iqr(zmp_centre)

    cycles = {"height": np.zeros(0), "roll_rate": np.zeros(0), "pitch_rate": np.zeros(0)}
    period = summary.step_period_cycles or _period(run)
    if period > 0:
        first, last = rows[0], rows[-1] + 1  # whole cycles of the window's span
        height = per_cycle_rms(run.height[first:last], period) if run.height is not None else np.zeros(0)
        out["gait_cycles"] = int((last - first) // period)
        out["height_median_m"], out["height_iqr_m"] = _median_iqr(height)
        if run.body_rate is not None:
            roll = per_cycle_rms(run.body_rate[first:last, 0], period)
            pitch = per_cycle_rms(run.body_rate[first:last, 1], period)
            out["roll_rate_median_rps"], out["roll_rate_iqr_rps"] = _median_iqr(roll)
            out["pitch_rate_median_rps"], out["pitch_rate_iqr_rps"] = _median_iqr(pitch)
            cycles.update(roll_rate=roll, pitch_rate=pitch)
        cycles["height"] = height
    from shc_cli.analysis.odometry import odometry_errors, tracks

    found = tracks(run, rows)
    if found is not None:
        out["odometry_drift_percent"], out["odometry_heading_error_deg"] = odometry_errors(found)
    out["_series"] = {"rows": rows, "margin": margins, "zmp": zmp, "zmp_margin": zmp_margin, "feet": feet,
                      "com": com, "contact": contact, "cycles": cycles, "tracks": found}
    return out


def analyze_log(run: RunLog, window: Window = Window()) -> dict[str, Any]:
    """:func:`analyze_run` plus whether the run played to its end (``complete``) and why it stopped
    (``stop_reason``: ``end``, ``SIGINT``, ``fell``, ``fault``, …)."""
    from shc_cli.analysis.path_measures import path_measures

    result = analyze_run(run, window)
    result.update(path_measures(run))
    result["complete"] = run.complete
    result["stop_reason"] = run.summary.stop_reason
    return result


def public(result: dict[str, Any]) -> dict[str, Any]:
    """A result of :func:`analyze_run` without its plot series (the ``_``-keys): what ``analyze --json`` prints."""
    return {k: v for k, v in result.items() if not k.startswith("_")}
