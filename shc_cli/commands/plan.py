"""``shc plan``: run the controller kinematically (commanded joints fed back) and log everything."""

from __future__ import annotations

import itertools
import math
import time
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import typer

from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.control.walk import WalkState
from shc_cli.errors import Issue, ShcError, SpecError
from shc_cli.runlog import RunWriter
from shc_cli.spec.autopose import AutoPoseSet, compatibility_issues, load_auto_pose_set
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot
from shc_cli.spec.timeline import Timeline, constant, load_timeline

START_UP_MARGIN_S = 2.0
"""Extra time allowed for reaching RUNNING beyond the robot's start-up duration [s]."""


def parse_velocity(text: str) -> tuple[float, float, float]:
    """``"VX,VY,WZ"`` → floats, or a one-line error."""
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or any(not math.isfinite(v) for v in values):
        raise SpecError([Issue(None, None, "--velocity", f"'{text}' is not three numbers VX,VY,WZ",
                               "e.g. --velocity 0.5,0,0")])
    return values


def run_plan(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
             commands: Path | None, out: Path | None, plots: bool, overwrite: bool = False) -> Path:
    """Load, run, log; returns the run directory (``overwrite``: replace an existing one when the run finishes)."""
    from shc_cli.spec.checks import load_checked

    robot, gait, loaded = load_checked(robot_name, gait_name)
    gait_file, _ = loaded.where(("walker", "gait"))
    if duration is not None and (duration <= 0 or not math.isfinite(duration)):
        raise SpecError([Issue(None, None, "--duration", f"{duration:g} must be a positive number of seconds",
                               "e.g. --duration 20")])
    timeline = load_timeline(commands, robot.time_delta) if commands else constant(parse_velocity(velocity))
    for _, change in timeline.changes:
        tips = {**_mapping(change.get("tip_velocity")), **_mapping(change.get("tip_position"))}
        named = [change.get("leg_toggle"), *tips]
        unknown = [leg for leg in named if leg is not None and leg not in robot.legs]
        if unknown:
            raise SpecError([Issue(commands, None, "step", f"no leg '{unknown[0]}' on robot '{robot.name}'",
                                   f"legs: {', '.join(robot.legs)}")])
        new_gait = change.get("gait")
        if isinstance(new_gait, Gait) and set(new_gait.offset_multiplier) != set(robot.legs):
            raise SpecError([Issue(commands, None, "gait", f"gait '{new_gait.name}' does not fit robot '{robot.name}'",
                                   f"give one multiplier for each of {', '.join(robot.legs)}")])
    cycles = walk_cycles(timeline, duration, robot.time_delta, commands is not None)
    pose_sets = pose_sets_for(robot, gait, timeline, gait_file.parent)
    directory = out or Path("runs") / f"{datetime.now():%Y%m%d-%H%M%S}-plan"
    controller = Controller(robot, gait, pose_sets=pose_sets)
    writer = RunWriter(directory, robot, overwrite)
    writer.write_robot(robot)
    started = time.perf_counter()
    try:
        outputs = _run(controller, robot, timeline, cycles, writer)
    except KeyboardInterrupt:
        writer.close()
        raise ShcError(f"interrupted: the cycles completed so far are in {writer.partial}") from None
    summary = _summary(robot, controller, outputs, time.perf_counter() - started)
    if plots:
        from shc_cli.plots import plot_plan

        plot_plan(robot, outputs, writer.partial, gait=gait.name)
    path = writer.finish(summary)
    from shc_cli.analysis.progress import progress_note

    typer.echo(f"{robot.name} / {gait.name}: {summary['cycles']} cycles "
               f"({summary['duration_s']:.2f} s), path speed {summary['path_speed_mps']:.4f} m/s, displacement "
               f"speed {summary['displacement_speed_mps']:.4f} m/s, stance feet "
               f"{summary['achieved_mean_speed_mps']:.4f} m/s (eq. 16: {summary['eq16_speed_mps']:.4f}), "
               f"IK deviations {summary['ik_deviation_count']}, "
               f"clamped {summary['ik_clamp_count']}{progress_note(summary)} → {path}")
    return path


def _mapping(value: object) -> dict[str, object]:
    return dict(value) if isinstance(value, dict) else {}


def pose_sets_for(robot: Robot, gait: Gait, timeline: Timeline, folder: Path) -> dict[str, AutoPoseSet]:
    """The auto-pose set of every gait a run uses (``pose.auto_pose_type``; 'auto' = named after the gait);
    empty when the robot does not auto-pose."""
    if not robot.pose.auto:
        return {}
    gaits = [gait, *(switch for _, c in timeline.changes if isinstance(switch := c.get("gait"), Gait))]
    sets: dict[str, AutoPoseSet] = {}
    for used in gaits:
        loaded = load_auto_pose_set(robot.pose.auto_pose_type, used, relative_to=folder)
        problems = compatibility_issues(loaded, used, list(robot.legs))
        if problems:
            raise SpecError(problems)
        assert loaded.pose_set is not None
        sets[used.name] = loaded.pose_set
    return sets


def walk_cycles(timeline: Timeline, duration: float | None, dt: float, from_file: bool,
                default_s: float = 10.0) -> int:
    """Control cycles to play after start-up: ``duration`` [s] if given, else a timeline file's length plus 1 s,
    else ``default_s`` [s]."""
    if duration is not None:
        return max(1, round(duration / dt))
    if from_file:
        return timeline.last_cycle + round(1.0 / dt)
    return round(default_s / dt)


def _run(controller: Controller, robot: Robot, timeline: Timeline, walk_cycles: int,
         writer: RunWriter) -> list[CycleOutput]:
    """Start up (request RUNNING until reached), then play the timeline."""
    dt = robot.time_delta
    outputs: list[CycleOutput] = []
    limit = round((robot.start_up.time_to_start + START_UP_MARGIN_S) / dt)
    cycle = 0
    while controller.state != RobotState.RUNNING:
        if cycle > limit:
            raise ShcError(f"{robot.name}: did not reach RUNNING within {limit} cycles of start-up")
        out = controller.step(Command(state_request=RobotState.RUNNING))
        writer.write(cycle, cycle * dt, (0.0, 0.0, 0.0), out)
        outputs.append(out)
        cycle += 1
    for command in timeline.commands(walk_cycles):
        out = controller.step(command)
        writer.write(cycle, cycle * dt, command.velocity, out)
        outputs.append(out)
        cycle += 1
        if cycle % 500 == 0:
            writer.flush()
    return outputs


def _summary(robot: Robot, controller: Controller, outputs: list[CycleOutput], seconds: float) -> dict[str, Any]:
    """Cycles, speeds (achieved by the stance feet vs paper eq. 16), odometry, IK statistics."""
    dt = robot.time_delta
    cycle = controller.cycle
    walker = controller.walker
    achieved, predicted = [], []
    for before, now in itertools.pairwise(outputs):
        if now.walk_state != WalkState.MOVING:
            continue
        stance = (now.stance_progress >= 0.0) & (before.stance_progress >= 0.0)
        if stance.any():
            feet = (now.walker_tips[stance, :2] - before.walker_tips[stance, :2]).mean(axis=0)
            achieved.append(float(np.linalg.norm(feet)) / dt)
        # Paper eq. 16, v = l_s·f/β, with l_s the stride (body travel in one stance) the walker commands.
        stride = math.hypot(*now.velocity[:2]) * cycle.duty_factor / cycle.frequency
        predicted.append(stride * cycle.frequency / cycle.duty_factor)
    distance = float(np.linalg.norm(walker.odometry_position)) if walker else 0.0
    from shc_cli.analysis.metrics import window_speeds
    from shc_cli.runread import ideal_path

    xy, _ = ideal_path(np.array([o.velocity for o in outputs]), dt)
    running = np.flatnonzero([o.robot_state == RobotState.RUNNING for o in outputs])
    path_speed, displacement_speed = window_speeds(xy, running, dt)  # as `shc analyze` measures the plan
    from shc_cli.analysis.progress import cycle_path_length, progress_fields

    desired = np.array([o.velocity[:2] for o in outputs]).reshape(-1, 2)[running]
    commanded = float(np.linalg.norm(desired, axis=1).mean()) if len(desired) else 0.0
    return {
        "robot": robot.name,
        "gait": controller.gait.name,
        "cycles": len(outputs),
        "duration_s": len(outputs) * dt,
        "time_delta_s": dt,
        "startup_cycles": sum(1 for o in outputs if o.robot_state != RobotState.RUNNING),
        "step_period_cycles": cycle.period,
        "cycle_frequency_hz": cycle.frequency,
        "step_frequency_hz": controller.parameters["step_frequency"],
        "duty_factor": cycle.duty_factor,
        "moving_cycles": len(predicted),
        "achieved_mean_speed_mps": float(np.mean(achieved)) if achieved else 0.0,
        "path_speed_mps": path_speed,
        "displacement_speed_mps": displacement_speed,
        "commanded_speed_mps": commanded,
        **progress_fields(cycle_path_length(xy[running], cycle.period), commanded, len(running) * dt),
        "eq16_speed_mps": float(np.mean(predicted)) if predicted else 0.0,
        "odometry_distance_m": distance,
        "odometry_yaw_rad": walker.odometry_yaw if walker else 0.0,
        "ik_deviation_count": sum(o.ik_deviations for o in outputs),
        "ik_clamp_count": sum(o.ik_clamped for o in outputs),
        "wall_time_s": seconds,
        "walkspace": {str(b): r for b, r in controller.walkspace.items()},
    }
