"""The summary of a ``plan`` run: cycles, the speed the stance feet achieve against paper eq. 16, odometry, IK.

Eq. 16 is predicted independently of the walker's own velocity: the stride ``l_s`` comes from the walkspace-derived
limit of the commanded direction (the scaled walkspace radius ``r`` of that bearing, study §3.3) and the input —
``l_s = 2·r·|throttle|`` in throttle mode, ``l_s = min(|v_in|, v_max)·β/f`` in real mode — and ``f`` and ``β`` from
the gait's step cycle; then ``v = l_s·f/β``. It holds for straight walking at a steady input (the linear input
only; a yaw input is not part of it).
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np

from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.control.walk import WalkState
from shc_cli.record.summary import RunSummary
from shc_cli.record.summary_kinds import Kind, summary_of
from shc_cli.spec.robot import Robot


class PlanRecord:
    """Keeps every controller output of a plan run and the eq. 16 speed of each MOVING cycle's input (with the
    limits of the gait in use then): an observer of the run loop."""

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self.outputs: list[CycleOutput] = []
        self.predicted: list[float] = []
        self.gaits: list[str] = []
        """The gaits the run walked, in order (a plan script may switch)."""

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        if not self.gaits or self.gaits[-1] != self.controller.gait.name:
            self.gaits.append(self.controller.gait.name)
        if self.outputs and out.walk_state == WalkState.MOVING:
            self.predicted.append(eq16_speed(self.controller, command.velocity[:2]))
        self.outputs.append(out)
        return None


def eq16_speed(controller: Controller, linear_input: tuple[float, float]) -> float:
    """Paper eq. 16 body speed ``l_s·f/β`` [m/s] for a linear velocity input, stride from the walkspace limit (a robot
    that verifies its speed limits: the stride of its verified speed limit)."""
    walker, cycle = controller.walker, controller.cycle
    if walker is None or not any(linear_input):
        return 0.0
    limits = walker.limits.bearings
    step = sorted(limits)[1] - sorted(limits)[0]
    bearing = round(math.degrees(math.atan2(linear_input[1], linear_input[0]))) % 360
    limit = limits[(bearing // step * step) % 360]  # OpenSHC reads the sector below the bearing
    magnitude = math.hypot(*linear_input)
    if walker.velocity_input_mode == "throttle" and controller.speed_shares is not None:  # verified limits: their
        stride = limit.linear_speed * min(magnitude, 1.0) * cycle.duty_factor / cycle.frequency  # speed's stride
    elif walker.velocity_input_mode == "throttle":
        stride = 2.0 * limit.scaled_radius * min(magnitude, 1.0)
    else:
        stride = min(magnitude, limit.linear_speed) * cycle.duty_factor / cycle.frequency
    return stride * cycle.frequency / cycle.duty_factor


def plan_summary(robot: Robot, controller: Controller, record: PlanRecord, seconds: float, directory: Path,
                 fields: dict[str, object] | None = None, kinds: tuple[Kind, ...] = ("plan",)) -> RunSummary:
    """Cycles, speeds (achieved by the stance feet vs paper eq. 16), odometry, IK statistics; the ideal body path's
    speeds from the finished tables in ``directory`` (the run directory, still ``.partial``) as ``shc analyze``
    gives them (:func:`shc_cli.analysis.metrics.walk_figures` over the RUNNING rows). ``fields``: the run's other
    fields (the fields every run shares, :class:`~shc_cli.loop.assembly.Finished`; a field of both: ``fields``'
    value); a summary of ``kinds`` (:func:`~shc_cli.record.summary_kinds.summary_of`)."""
    dt = robot.time_delta
    outputs = record.outputs
    cycle = controller.cycle
    walker = controller.walker
    achieved: list[float] = []
    predicted = record.predicted
    for before, now in itertools.pairwise(outputs):
        if now.walk_state != WalkState.MOVING:
            continue
        stance = (now.stance_progress >= 0.0) & (before.stance_progress >= 0.0)
        if stance.any():
            feet = (now.walker_tips[stance, :2] - before.walker_tips[stance, :2]).mean(axis=0)
            achieved.append(float(np.linalg.norm(feet)) / dt)
    distance = float(np.linalg.norm(walker.odometry_position)) if walker else 0.0
    from shc_cli.analysis.metrics import walk_figures
    from shc_cli.analysis.progress import progress_fields
    from shc_cli.loop.physics_summary import window_progress
    from shc_cli.record.runread import read_tables

    if outputs:
        log = read_tables(directory, robot)
        rows = np.flatnonzero(log.running)
        figures = walk_figures(log, rows, walking=False)
        path_speed, displacement_speed = figures.path_speed_mps, figures.displacement_speed_mps
        commanded = figures.commanded_speed_mps
        progress = window_progress(log, rows, cycle.period, commanded)
    else:  # stopped before its first cycle
        path_speed = displacement_speed = commanded = 0.0
        progress = progress_fields(0.0, 0.0, 0.0)
    return summary_of(kinds, {
        "robot": robot.name,
        "gait": controller.gait.name,
        "gaits": record.gaits or [controller.gait.name],
        "cycles": len(outputs),
        "duration_s": len(outputs) * dt,
        "time_delta_s": dt,
        "startup_cycles": sum(1 for o in outputs if o.robot_state != RobotState.RUNNING),
        "step_period_cycles": cycle.period,
        "cycle_frequency_hz": cycle.frequency,
        "step_frequency_hz": controller.parameters["step_frequency"],
        "duty_factor": cycle.duty_factor,
        "moving_cycles": len(predicted),
        "achieved_mean_speed_mps": float(np.mean(achieved)) if achieved else None,  # None: no MOVING cycle
        "path_speed_mps": path_speed,
        "displacement_speed_mps": displacement_speed,
        "commanded_speed_mps": commanded,
        **progress,
        "eq16_speed_mps": float(np.mean(predicted)) if predicted else None,
        "odometry_distance_m": distance,
        "odometry_yaw_rad": walker.odometry_yaw if walker else 0.0,
        "odometry_pose": list(outputs[-1].odometry) if outputs else None,
        "true_pose": ([*(float(v) for v in walker.odometry_position[:2]), walker.odometry_yaw] if walker
                      else None),
        "ik_deviation_count": sum(o.ik_deviations for o in outputs),
        "ik_clamp_count": sum(o.ik_clamped for o in outputs),
        "wall_time_s": seconds,
        "walkspace": {str(b): r for b, r in controller.walkspace.items()},
        **(fields or {}),
    })
