"""``shc sweep``: a grid of simulations in parallel processes (or on a Dask cluster), analysed into one table.

Layout of the output directory::

    OUT/sweep.toml            the sweep file, as run
    OUT/variants/SLUG.toml    robot files of points that change robot parameters (extends + overrides)
    OUT/runs/SLUG/            one simulate run directory per point (log.csv, summary.json, robot.toml)
    OUT/results.csv           one row per point, grid order: its values, status, error and the analyze metrics
    OUT/results.partial.csv   rows as runs finish (kept if the sweep is interrupted)
    OUT/cot.png               CoT and speed vs step frequency (OpenSHC paper Fig. 14–16 style)

Every point runs in a worker process through :func:`~shc_cli.domain.sweeps.points.run_point`, which never raises:
a failing run becomes a row with ``status = failed`` and its error. ``resume`` re-reads finished run directories
instead of simulating.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from shc_cli.domain.sweeps import points
from shc_cli.domain.sweeps.checks import check_executor, check_points
from shc_cli.domain.sweeps.pool import RunPool
from shc_cli.domain.sweeps.results import WARNINGS, PartialTable, Row, sweep_columns, write_table
from shc_cli.errors import Interrupted, Issue, SpecError, check_choice, signal_name
from shc_cli.spec.sweep import Sweep, load_sweep

OnRow = Callable[[int, int, Row | None], None]
"""Called before the first run with ``(0, total, None)`` and as each run finishes with the number of finished runs,
the total and the run's row (e.g. a progress bar)."""


@dataclass(frozen=True)
class SweepReport:
    """A finished sweep.

    Attributes:
        name: the sweep's name.
        path: its output directory (``results.csv`` in it).
        rows: the results rows, grid order (values as computed, not yet table text).
        workers: parallel runs it used.
        executor: ``local`` or ``dask``.
        elapsed_s: wall time of the runs and the tables [s].
    """

    name: str
    path: Path
    rows: list[Row]
    workers: int
    executor: str
    elapsed_s: float

    @property
    def ok(self) -> list[Row]:
        """The rows of the runs that finished."""
        return [r for r in self.rows if r["status"] == "ok"]

    @property
    def failed(self) -> int:
        """The number of runs that failed (their rows have the error)."""
        return len(self.rows) - len(self.ok)

    @property
    def fell(self) -> int:
        """The number of finished runs whose robot fell."""
        return sum(1 for r in self.ok if str(r.get("fell")) == "True")

    @property
    def warned(self) -> list[Row]:
        """The finished runs with engine warnings (column :data:`~shc_cli.domain.sweeps.results.WARNINGS`)."""
        return [r for r in self.ok if r.get(WARNINGS)]

    @property
    def no_steady_speed(self) -> bool:
        """No finished run held its velocity for a whole gait cycle after the ramp (``steady_speed_mps`` empty)."""
        return bool(self.ok) and all(r.get("steady_speed_mps") in (None, "") for r in self.ok)


def with_engine(sweep: Sweep, engine: str | None) -> Sweep:
    """The sweep with ``engine`` (``--engine``) for every run, unless the file chooses the engine itself."""
    if engine is None:
        return sweep
    from shc_cli.backends.engine_registry import ENGINES

    check_choice("--engine", engine, ENGINES, "a physics engine")
    if "engine" in sweep.fixed or "engine" in sweep.grid:
        return sweep
    return dataclasses.replace(sweep, points=[dataclasses.replace(point, options={**point.options, "engine": engine})
                                              for point in sweep.points])


def run_sweep(file: Path, workers: int | None = None, executor: str = "local", scheduler: str | None = None,
              out: Path | None = None, resume: bool = False, overwrite: bool = False, engine: str | None = None,
              on_row: OnRow | None = None) -> SweepReport:
    """Check the sweep, run every point, write the results table and plots.

    Args:
        file: the sweep file.
        workers: parallel runs (None: every core).
        executor: ``local`` (worker processes) or ``dask``.
        scheduler: the Dask scheduler's address (None: a LocalCluster).
        out: the output directory (None: ``runs/<sweep name>``).
        resume: continue an existing output directory (finished runs are read, not run again).
        overwrite: delete an existing output directory (shc's own) first.
        engine: the physics engine of every run whose sweep file does not choose one (``engine`` in ``[fixed]`` or
            ``[grid]``).
        on_row: called as each run finishes.
    """
    sweep = with_engine(load_sweep(file), engine)
    check_executor(executor, scheduler)
    check_points(sweep)
    out = out or Path("runs") / sweep.name
    if resume and overwrite:
        raise SpecError([Issue(None, None, "--overwrite", "cannot be combined with --resume", "choose one")])
    if not resume:
        from shc_cli.record.runlog import clear_output

        clear_output(out, overwrite,
                     "add --resume to continue it, --overwrite to run it again, or choose another --out")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    points.clear_stop(out)
    if sweep.path.resolve() != (out / "sweep.toml").resolve():
        shutil.copyfile(sweep.path, out / "sweep.toml")
    count = workers or os.cpu_count() or 1
    columns = sweep_columns(list(sweep.grid))
    started = time.perf_counter()
    rows: list[Row] = []
    partial = out / "results.partial.csv"
    with PartialTable(partial, columns) as table, RunPool(executor, count, scheduler) as pool:
        try:
            if on_row is not None:
                on_row(0, len(sweep.points), None)
            for row in pool.results(sweep.points, out):
                rows.append(row)
                table.append(row)
                if on_row is not None:
                    on_row(len(rows), len(sweep.points), row)
        except KeyboardInterrupt as error:
            raise Interrupted(f"{len(rows)} runs finished, their rows are in {partial}; continue with --resume",
                              signal_name(error)) from None
    rows.sort(key=lambda r: int(r["index"]))
    write_table(out / "results.csv", columns, rows)
    partial.unlink()
    _plot_cot(sweep, rows, out)
    return SweepReport(sweep.name, out, rows, count, executor, time.perf_counter() - started)


def _plot_cot(sweep: Sweep, rows: list[Row], out: Path) -> None:
    """``cot.png`` when the finished runs have more than one step frequency (rows grouped by their other grid keys:
    a ``group`` key is added to them)."""
    from shc_cli.plots import plot_cot

    done = [r for r in rows if r["status"] == "ok"]
    if len({r.get("step_frequency_hz") for r in done}) > 1:
        group_keys = [k for k in sweep.grid if k not in ("robot", "gait") and not k.endswith("step_frequency")]
        for row in done:
            row["group"] = ", ".join(f"{k} {row[k]}" for k in group_keys if k in row)  # grids may differ in keys
        plot_cot(done, out / "cot.png")
