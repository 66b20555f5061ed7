"""``shc sweep``: run a sweep file (:func:`shc_cli.api.sweep`) with a progress bar and print what it gave."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import typer

if TYPE_CHECKING:
    from shc_cli.domain.sweeps.results import Row
    from shc_cli.progress import ProgressBar


class _Progress:
    """The progress bar over the sweep's runs (none, quiet, in pipes and CI)."""

    def __init__(self) -> None:
        self.bar: ProgressBar | None = None

    def __call__(self, done: int, total: int, row: Row | None) -> None:
        from shc_cli.progress import progress_bar

        if row is None:
            self.bar = progress_bar("sweep", total)
        elif self.bar is not None:
            self.bar.update(done, str(row["slug"])[:40])


def run_sweep(file: Path, workers: int | None, executor: str, scheduler: str | None, out: Path | None,
              resume: bool, overwrite: bool, engine: str | None) -> None:
    """Run the sweep and print its line (runs, time, ok / fell / failed, the table) and notes."""
    from shc_cli.api import sweep
    from shc_cli.domain.sweeps.results import WARNINGS

    report = sweep(file, workers=workers, executor=executor, scheduler=scheduler, out=out, resume=resume,
                   overwrite=overwrite, engine=engine, progress=_Progress()).report
    count = report.workers
    typer.echo(f"{report.name}: {len(report.rows)} runs in {report.elapsed_s:.1f} s with {count} "
               f"{report.executor} worker{'s' if count != 1 else ''}: {len(report.ok)} ok ({report.fell} fell), "
               f"{report.failed} failed → {report.path / 'results.csv'}")
    warned = report.warned
    if warned:
        typer.echo(f"note: {len(warned)} run{'s' if len(warned) != 1 else ''} had engine warnings (results.csv "
                   f"column {WARNINGS}), e.g. {warned[0]['slug']}: {warned[0][WARNINGS]}")
    if report.no_steady_speed:
        typer.echo("note: steady_speed_mps is empty: no run held its velocity for a whole gait cycle after the "
                   "acceleration ramp (make `duration` longer)")
