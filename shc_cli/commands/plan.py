"""``shc plan``: run the controller kinematically (commanded joints fed back) and log everything."""

from __future__ import annotations

import time
from collections.abc import Callable
from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from shc_cli.loop.run_inputs import parse_velocity, pose_sets_for, walk_cycles

if TYPE_CHECKING:
    from shc_cli.loop.summary import RunSummary

__all__ = ["parse_velocity", "plan_to", "pose_sets_for", "run_plan", "walk_cycles"]


def plan_to(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
            commands: Path | None, out: Path | None, plots: bool, overwrite: bool = False
            ) -> tuple[Path, RunSummary]:
    """Load, run through the one loop on the kinematic backend, log (silently); returns the run directory and its
    summary (``complete`` false when a signal stopped it; ``overwrite``: replace an existing run directory when the
    run finishes)."""
    from shc_cli.backends.kinematic import KinematicBackend
    from shc_cli.control.controller import Controller
    from shc_cli.loop.input_sources import TimelineInput
    from shc_cli.loop.plan_summary import PlanRecord, plan_summary
    from shc_cli.loop.run_inputs import load_inputs
    from shc_cli.loop.run_loop import START_UP_MARGIN_S, RunLoop, StartUp
    from shc_cli.loop.runlog import RunWriter
    from shc_cli.loop.session import execute

    inputs = load_inputs(robot_name, gait_name, velocity, duration, commands, default_s=10.0, check_fit=True)
    robot = inputs.robot
    directory = out or Path("runs") / f"{datetime.now():%Y%m%d-%H%M%S}-plan"
    controller = Controller(robot, inputs.gait, pose_sets=inputs.pose_sets)
    writer = RunWriter(directory, robot, overwrite)
    writer.write_robot(robot)
    record = PlanRecord(controller)
    start_up = StartUp(round((robot.start_up.time_to_start + START_UP_MARGIN_S) / robot.time_delta))
    loop = RunLoop(controller, KinematicBackend(), TimelineInput(inputs.timeline.commands(inputs.cycles)), writer,
                   start_up, observers=[record], flush_every=500)
    started = time.perf_counter()

    def plot(folder: Path) -> None:
        from shc_cli.plots import plot_plan

        plot_plan(robot, record.outputs, folder, gait=inputs.gait.name)

    path, summary, _ = execute(loop, writer, lambda _: plan_summary(robot, controller, record,
                                                                     time.perf_counter() - started),
                               plot if plots else None)
    return path, summary


def run_plan(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
             commands: Path | None, out: Path | None, plots: bool, after: Callable[[Path], None] | None = None,
             overwrite: bool = False) -> Path:
    """Load, run, log, print one line, then ``after(run directory)``; returns the run directory (exit 130/143 after
    SIGINT/SIGTERM)."""
    from shc_cli.analysis.progress import progress_note
    from shc_cli.commands.outcome import exit_if_interrupted, interrupted_note

    path, summary = plan_to(robot_name, gait_name, velocity, duration, commands, out, plots, overwrite)
    typer.echo(f"{summary.robot} / {summary.gait}: {summary.cycles} cycles "
               f"({summary.duration_s:.2f} s), path speed {summary.path_speed_mps:.4f} m/s, displacement "
               f"speed {summary.displacement_speed_mps:.4f} m/s, stance feet "
               f"{summary.achieved_mean_speed_mps:.4f} m/s (eq. 16: {summary.eq16_speed_mps:.4f}), "
               f"IK deviations {summary.ik_deviation_count}, "
               f"clamped {summary.ik_clamp_count}{progress_note(summary)}{interrupted_note(summary)} → {path}")
    if after is not None:
        after(path)
    exit_if_interrupted(summary)
    return path

