"""``shc plan``: run the controller kinematically (commanded joints fed back), log everything, print one line."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import typer

__all__ = ["run_plan"]


def run_plan(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
             commands: Path | None, out: Path | None, plots: bool, after: Callable[[Path], None] | None = None,
             overwrite: bool = False, live: bool = False, live_port: int = 8765, realtime: bool = False,
             path: Path | None = None, fail_leg: str | None = None) -> Path:
    """Plan (:func:`shc_cli.api.plan`), print one line, then ``after(run directory)``; returns the run directory
    (exit 130/143 after SIGINT/SIGTERM)."""
    from shc_cli.analysis.run_line import plan_line
    from shc_cli.api import plan
    from shc_cli.commands.outcome import exit_if_interrupted, interrupted_note

    run = plan(robot_name, gait=gait_name, velocity=velocity, duration=duration, commands=commands, out=out,
               plots=plots, overwrite=overwrite, live=live, live_port=live_port, realtime=realtime, path=path,
               fail_leg=fail_leg)
    summary = run.summary
    typer.echo(plan_line(summary, run.path, interrupted_note(summary)))
    if after is not None:
        after(run.path)
    exit_if_interrupted(summary)
    return run.path
