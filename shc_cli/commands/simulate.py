"""``shc simulate``: the one controller driving the robot in physics (PyBullet or MuJoCo), logged and summarised."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import typer

from shc_cli.domain.config import SimulationConfig

if TYPE_CHECKING:
    from shc_cli.progress import ProgressBar

__all__ = ["run_simulate"]


def run_simulate(config: SimulationConfig, after: Callable[[Path], None] | None = None) -> Path:
    """Simulate, print one line, then ``after(run directory)``; returns the run directory. Exits 130/143 when a
    signal stopped the run, 4 when it fell and ``fail_on_fall`` is set, 6 when the physics diverged."""
    from shc_cli.analysis.run_line import simulation_line
    from shc_cli.api import simulate
    from shc_cli.commands.outcome import EXIT_FELL, exit_if_diverged, exit_if_interrupted, interrupted_note

    run = simulate(config=config, progress=_Bar())
    path, summary = run.path, run.summary
    typer.echo(simulation_line(summary, config.terrain, path, interrupted_note(summary)))
    for warning in summary.engine_warnings or []:
        hint = "" if "--physics-rate" in warning else " (try a higher --physics-rate)"
        typer.echo(f"note: {summary.engine}: {warning}{hint}", err=True)
    if after is not None:
        after(path)
    exit_if_interrupted(summary)
    exit_if_diverged(summary)
    if summary.fell and config.fail_on_fall:
        raise typer.Exit(EXIT_FELL)
    return path



class _Bar:
    """The progress bar over the walking cycles (none, quiet, in pipes and CI); it goes when the run ends."""

    def __init__(self) -> None:
        self.bar: ProgressBar | None = None
        self.started = False

    def __call__(self, done: int, total: int) -> None:
        from shc_cli.progress import progress_bar

        if not self.started:
            self.started, self.bar = True, progress_bar("simulating", total)
        if self.bar is not None and done > 0:
            self.bar.update(done)
