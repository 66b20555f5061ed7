"""The one line a simulated run prints: where it walked, what it drew, its cost of transport — and, where a figure
cannot be measured, why not.

A figure of a run with too little walking (a 1 ms run, a Ctrl-C during start-up, a robot that did not get
anywhere) is not a number: the line says "not enough walking to measure" instead of ``CoT None`` or a mean power
of 0.0 W, and a run flagged NO PROGRESS prints no CoT (dividing its power by a speed near zero gives a figure that
means nothing). The air and standing scenarios (SA, WA, SG) have no walking by design: their line is the power.

A walk that went somewhere but badly says so (:func:`walk_warnings`): statically unstable (the centre of mass
outside the stance feet's support polygon more than half the time) or slipping (the feet slide more than
:data:`SLIP_SHARE` of the distance walked) — an imported robot can walk a metre that way and look fine — or short
of the distance asked (under :data:`~shc_cli.analysis.shortfall.SHORT_SHARE` of it), with the joint that saturated
and the foot that slipped (:mod:`shc_cli.analysis.shortfall`).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.analysis.progress import progress_note

if TYPE_CHECKING:
    from shc_cli.record.summary import RunSummary

NOT_MEASURED = "not enough walking to measure"
"""What the line says for a figure the run cannot give."""
GENERIC_SERVOS = "note: generic servos — power is indicative"
"""Appended once when the robot file gives no ``[servo]``: power and CoT then come from default servo figures."""


SLIP_SHARE = 0.15
"""Foot slip (per foot, while in contact) per metre walked above which the line warns: below 0.10 for every bundled
robot walking 10 s on flat ground (bullet 0.064, athena 0.075, octopod 0.025; tests/test_walk_warnings.py), 0.26 for
the imported PhantomX of docs/your-robot.md on AX-12A servos."""


def generic_servos(robot_servo_model: str | None) -> bool:
    """Whether the robot's servos are the defaults of a robot file without ``[servo]`` (model ``generic``)."""
    return robot_servo_model in (None, "generic")


def simulation_line(summary: RunSummary, terrain: str, path: Path, note: str = "") -> str:
    """The summary line of ``shc simulate``.

    Args:
        summary: the run's summary (:meth:`shc_cli.loop.physics_summary.PhysicsRecord.summary`).
        terrain: the terrain as given (``flat``, ``ramp:5`` …).
        path: the run directory.
        note: appended before the path (e.g. that a signal stopped the run).
    """
    parts = [f"{summary.robot} / {summary.gait} / {summary.scenario} on {terrain} ({summary.engine or '?'}): "
             f"{summary.sim_time_s or 0.0:.1f} s simulated in {summary.wall_time_s or 0.0:.1f} s"]
    walking = summary.scenario == "WG"
    window = summary.analysed_time_s or 0.0
    measured = summary.mean_power_w is not None and window > 0.0
    if walking:
        if window > 0.0:
            parts.append(f"distance {summary.distance_m or 0.0:.3f} m, path speed {summary.path_speed_mps or 0.0:.4f} "
                         f"m/s, displacement speed {summary.displacement_speed_mps or 0.0:.4f} m/s")
        else:
            parts.append(f"speed: {NOT_MEASURED}")
    parts.append(f"mean power {summary.mean_power_w:.1f} W" if measured and summary.mean_power_w is not None
                 else f"power: {NOT_MEASURED}")
    if walking and measured:
        parts.append(f"CoT {summary.cot:.3f}" if summary.cot is not None and not summary.no_progress
                     else f"CoT: {NOT_MEASURED}")
    line = ", ".join(parts)
    if summary.fell:
        line += f", FELL ({summary.fall})" if summary.fall else ", FELL"
    elif walking:
        line += progress_note(summary)
        if window > 0.0:
            line += "".join(f", warning: {warning}" for warning in walk_warnings(path, summary))
    line += path_note(summary) + speed_note(summary) + note
    if generic_servos(summary.servo_model):
        line += f" ({GENERIC_SERVOS})"
    return f"{line} → {path}"


def walk_warnings(path: Path, summary: RunSummary) -> list[str]:
    """What was wrong with a walk that did not fall, from its log in ``path`` (the RUNNING window ``shc analyze``
    measures, with its figures): a negative median static margin, foot slip above :data:`SLIP_SHARE` of the
    distance walked (not for a run flagged NO PROGRESS: no distance to share). Nothing when the log cannot be
    read."""
    import numpy as np

    from shc_cli.analysis import metrics
    from shc_cli.analysis.progress import cycle_path_length
    from shc_cli.analysis.shortfall import SHORT_SHARE, shortfall_reasons
    from shc_cli.errors import ShcError
    from shc_cli.record.runread import read_run

    try:
        log = read_run(path)  # the run directory the simulation just finished
    except (ShcError, OSError):
        return []
    rows = np.flatnonzero(metrics.window_mask(log, metrics.Window()))
    if len(rows) < 2:
        return []
    feet, com = metrics.feet_and_com(log, rows)
    contact = log.contact[rows]
    margins = [metrics.edge_margin(metrics.support_polygon(feet[i, down, :2]), com[i, :2])
               for i, down in enumerate(contact) if down.any()]
    warnings = []
    if margins and (median := float(np.median(margins))) < 0.0:
        warnings.append(f"statically unstable (median static margin {median:.3f} m: the centre of mass outside the "
                        "stance feet's polygon more than half the time)")
    # the distance walked: the body's path sampled once per gait cycle (a turn or a closed path counts, the sway
    # within a step does not), not the straight line from start to end (a square path back to its start has none)
    distance = cycle_path_length(metrics.window_path(log.position[:, :2], rows), summary.step_period_cycles or 1)
    slip = float(metrics.foot_slip(feet, contact).mean())
    if not summary.no_progress and distance > 0.0 and slip > SLIP_SHARE * distance:
        warnings.append(f"feet slip {slip:.3f} m each over {distance:.3f} m walked ({100 * slip / distance:.0f} %, "
                        f"above {100 * SLIP_SHARE:.0f} %)")
    share = summary.walked_share
    if share is not None and share < SHORT_SHARE and (summary.commanded_distance_m or 0.0) > 0.0:
        reasons = shortfall_reasons(log, rows, distance, SLIP_SHARE)
        why = "; ".join(reasons) if reasons else "no joint saturated and no foot slipped"
        warnings.append(f"walked {100 * share:.0f} % of the {summary.commanded_distance_m:.2f} m commanded "
                        f"(under {100 * SHORT_SHARE:.0f} %): {why}")
    return warnings


def plan_line(summary: RunSummary, path: Path, note: str = "") -> str:
    """The summary line of ``shc plan``: cycles, speeds, the stance feet's speed against paper eq. 16 (or that the
    run had no walking cycle to measure it on), IK deviations and clamps."""
    if summary.achieved_mean_speed_mps is None or summary.eq16_speed_mps is None:
        feet = f"stance feet: {NOT_MEASURED}"
    else:
        feet = f"stance feet {summary.achieved_mean_speed_mps:.4f} m/s (eq. 16: {summary.eq16_speed_mps:.4f})"
    gaits = " → ".join(summary.gaits) if summary.gaits else str(summary.gait)
    return (f"{summary.robot} / {gaits}: {summary.cycles} cycles "
            f"({summary.duration_s or 0.0:.2f} s), path speed {summary.path_speed_mps or 0.0:.4f} m/s, displacement "
            f"speed {summary.displacement_speed_mps or 0.0:.4f} m/s, {feet}, IK deviations "
            f"{summary.ik_deviation_count}, clamped {summary.ik_clamp_count}{progress_note(summary)}"
            f"{path_note(summary)}{speed_note(summary)}{note} → {path}")


def speed_note(summary: RunSummary) -> str:
    """``", speed limits verified (41–56 % of OpenSHC's)"`` when the robot's verified speed limits are below
    OpenSHC's, and ``", joint speed limited in 257 cycles (10.3 %)"`` when the controller had to hold a joint to its
    ``max_vel`` (the inputs asked for more than the servos can do); else empty."""
    verified = summary.speed_limits_verified
    note = ""
    if verified:  # the robot verifies its speed limits and kept less than OpenSHC's (docs/deviations.md)
        low, high = min(verified.values()), max(verified.values())
        kept = f"{100.0 * low:.0f} %" if low == high else f"{100.0 * low:.0f}–{100.0 * high:.0f} %"
        note = f", speed limits verified ({kept} of OpenSHC's)"
    cycles = summary.joint_speed_limited_cycles
    if not cycles:
        return note
    share = summary.joint_speed_limited_share or 0.0
    return f"{note}, joint speed limited in {cycles} cycles ({100.0 * share:.1f} %)"


def path_note(summary: RunSummary) -> str:
    """``", path: 4/4 waypoints reached (odometry) in 84.9 s"`` for a ``--path`` run (the follower's own view;
    ``shc analyze`` measures against the ground truth), else empty."""
    if not summary.waypoints:
        return ""
    reached = sum(w.reached for w in summary.waypoints)
    last = summary.waypoints[-1]
    when = f" in {last.left_s:.1f} s" if last.reached and last.left_s is not None else ""
    return f", path: {reached}/{len(summary.waypoints)} waypoints reached (odometry){when}"
