"""``shc optimize``: run a study file (:func:`shc_cli.api.optimize`) and print what it gave."""

from __future__ import annotations

from pathlib import Path

import typer


def run_optimize(file: Path, trials: int | None, workers: int | None, executor: str, scheduler: str | None,
                 out: Path | None, resume: bool, overwrite: bool) -> None:
    """Run the study and print its line: trials, time, complete / feasible / failed, the Pareto front, overhead."""
    from shc_cli.api import optimize

    report = optimize(file, trials=trials, workers=workers, executor=executor, scheduler=scheduler, out=out,
                      resume=resume, overwrite=overwrite).report
    count, stored = report.workers, len(report.trials)
    typer.echo(f"{report.name}: {report.ran} trials in {report.elapsed_s:.1f} s with {count} {report.executor} "
               f"worker{'s' if count != 1 else ''} ({stored} in the study: {report.complete} complete, "
               f"{report.feasible} feasible, {stored - report.complete} failed); {len(report.pareto)} on the Pareto "
               f"front → {report.path / 'pareto.csv'}; search overhead "
               f"{1000 * report.overhead_s / max(report.ran, 1):.0f} ms per trial")
    for note in report.notes:
        typer.echo(f"note: {note}", err=True)
