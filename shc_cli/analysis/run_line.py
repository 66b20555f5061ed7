"""The one line a simulated run prints: where it walked, what it drew, its cost of transport — and, where a figure
cannot be measured, why not.

A figure of a run with too little walking (a 1 ms run, a Ctrl-C during start-up, a robot that did not get
anywhere) is not a number: the line says "not enough walking to measure" instead of ``CoT None`` or a mean power
of 0.0 W, and a run flagged NO PROGRESS prints no CoT (dividing its power by a speed near zero gives a figure that
means nothing). The air and standing scenarios (SA, WA, SG) have no walking by design: their line is the power.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.analysis.progress import progress_note

if TYPE_CHECKING:
    from shc_cli.loop.summary import RunSummary

NOT_MEASURED = "not enough walking to measure"
"""What the line says for a figure the run cannot give."""
GENERIC_SERVOS = "note: generic servos — power is indicative"
"""Appended once when the robot file gives no ``[servo]``: power and CoT then come from default servo figures."""


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
        line += ", FELL"
    elif walking:
        line += progress_note(summary)
    line += path_note(summary) + speed_note(summary) + note
    if generic_servos(summary.servo_model):
        line += f" ({GENERIC_SERVOS})"
    return f"{line} → {path}"


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
