"""``shc plan``: run the controller kinematically (commanded joints fed back), log everything, print one line."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import typer

__all__ = ["run_plan"]


def run_plan(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
             commands: Path | None, out: Path | None, plots: bool, after: Callable[[Path], None] | None = None,
             overwrite: bool = False) -> Path:
    """Plan (:func:`shc_cli.api.plan`), print one line, then ``after(run directory)``; returns the run directory
    (exit 130/143 after SIGINT/SIGTERM)."""
    from shc_cli.analysis.progress import progress_note
    from shc_cli.api import plan
    from shc_cli.commands.outcome import exit_if_interrupted, interrupted_note

    run = plan(robot_name, gait=gait_name, velocity=velocity, duration=duration, commands=commands, out=out,
               plots=plots, overwrite=overwrite)
    path, summary = run.path, run.summary
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
