"""``shc sweep``: a grid of simulations in parallel processes (or on a Dask cluster), analysed into one table.

Layout of the output directory::

    OUT/sweep.toml            the sweep file, as run
    OUT/variants/SLUG.toml    robot files of points that change robot parameters (extends + overrides)
    OUT/runs/SLUG/            one simulate run directory per point (log.csv, summary.json, robot.toml)
    OUT/results.csv           one row per point, grid order: its values, status, error and the analyze metrics
    OUT/results.partial.csv   rows as runs finish (kept if the sweep is interrupted)
    OUT/cot.png               CoT and speed vs step frequency (OpenSHC paper Fig. 14–16 style)

Every point runs in a worker process through :func:`run_point`, which never raises: a failing run becomes a row
with ``status = failed`` and its error. ``--resume`` re-reads finished run directories instead of simulating.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import os
import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import typer

from shc_cli.errors import Issue, ShcError, SpecError
from shc_cli.spec.sweep import Point, Sweep, load_sweep, variant_text

METRICS = ("cot", "mean_power_w", "mean_speed_mps", "displacement_speed_mps", "path_speed_mps", "steady_speed_mps",
           "commanded_speed_mps", "speed_ratio", "distance_m", "duty_factor", "foot_slip_m",
           "stability_margin_median_m", "zmp_margin_median_m", "height_median_m", "height_iqr_m",
           "roll_rate_median_rps", "pitch_rate_median_rps", "step_frequency_hz")
"""Analysis keys copied into the results table."""
RUN_KEYS = ("engine", "fell", "sim_time_s", "wall_time_s", "physics_time_s")
"""Summary keys copied into the results table (the timings differ from run to run; compare the others)."""
WARNINGS = "engine_warnings"
"""Results column with the run's engine warnings (``summary.json`` ``engine_warnings``, joined by "; ")."""


def run_point(point: Point, out: str, metrics: tuple[str, ...] = METRICS, skip: float = 0.0) -> dict[str, Any]:
    """Simulate one grid point into ``out/runs/<slug>`` (or re-read it if finished) and analyse it; never raises.

    Returns the results row: index, slug, the grid values, ``status`` (``ok``/``failed``), ``error``, the
    :data:`RUN_KEYS` and the ``metrics`` (``shc analyze`` keys, leaving out the first ``skip`` seconds of running as
    ``shc analyze --skip``). ``shc optimize`` runs its trials through it too.
    """
    row: dict[str, Any] = {"index": point.index, "slug": point.slug, **point.values, "status": "ok", "error": ""}
    directory = Path(out) / "runs" / point.slug
    try:
        if _stopped_by_signal(directory):  # finished as a partial run by an earlier Ctrl-C: run it again
            shutil.rmtree(directory)
        if not (directory / "summary.json").exists():
            partial = directory.with_name(directory.name + ".partial")
            if partial.exists():
                shutil.rmtree(partial)  # a crashed earlier attempt
            _simulate(point, Path(out), directory)
        from shc_cli.analysis.metrics import Window, analyze_run
        from shc_cli.loop.opening import open_run

        if _stopped_by_signal(directory):  # Ctrl-C during this run: it is kept (partial), the sweep stops
            raise KeyboardInterrupt
        log = open_run(directory)
        result = analyze_run(log, Window(skip_s=skip))
        row.update({key: log.summary.get(key) for key in RUN_KEYS})
        row[WARNINGS] = "; ".join(log.summary.get(WARNINGS) or [])
        row.update({key: result.get(key) for key in metrics})
    except Exception as error:  # a failing run is a row, not the end of the sweep
        if _interrupted(error):
            raise KeyboardInterrupt from error  # Ctrl-C during the run: stop the sweep, not just this run
        row.update(status="failed", error=_one_line(error))
    return row


def _interrupted(error: BaseException) -> bool:
    """Whether ``error`` stands for a Ctrl-C: ``simulate`` turns the KeyboardInterrupt into a one-line ShcError,
    keeping it as the context."""
    seen: BaseException | None = error
    while seen is not None:
        if isinstance(seen, KeyboardInterrupt):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def _stopped_by_signal(directory: Path) -> bool:
    """A finished run directory whose summary says it did not play to its end because of a signal."""
    import json

    try:
        summary = json.loads((directory / "summary.json").read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return summary.get("stop_reason") in ("SIGINT", "SIGTERM")


def _one_line(error: BaseException) -> str:
    if isinstance(error, SpecError):
        return "; ".join(str(issue) for issue in error.issues)
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0] if text else ''}"


def _simulate(point: Point, out: Path, directory: Path) -> None:
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.simulate import simulate

    options = point.options
    robot = _robot_for(point, out)
    velocity = options["velocity"]
    if options["stride_percent"] is not None:
        velocity = f"{float(options['stride_percent']) / 100.0:g},0,0"
    simulate(SimulationConfig(robot=robot, gait=options["gait"] or None, velocity=velocity,
                              duration=float(options["duration"]), out=directory, plots=False,
                              terrain=options["terrain"], scenario=options["scenario"],
                              physics_rate=float(options["physics_rate"]), friction=float(options["friction"]),
                              restitution=float(options["restitution"]), seed=int(options["seed"]),
                              imu_noise=float(options["imu_noise"]), start=options["start"], stand=options["stand"],
                              engine=options["engine"]))


def _robot_for(point: Point, out: Path) -> str:
    """The robot to load: the named one, or a variant file extending it with the point's overrides."""
    from shc_cli.spec.loading import load_robot, resolve

    name = str(point.options["robot"])
    if not point.overrides:
        return name
    base = resolve("robots", name)
    robot = load_robot(base).robot
    adjustable = {path for path in point.overrides if _is_adjustable(robot, path)}
    path = out / "variants" / f"{point.slug}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(variant_text(base, point.overrides, adjustable), encoding="utf-8")
    return str(path)


def _field(robot: Any, dotted: str) -> Any:
    """The robot's value at a dotted robot-file path (tables and leg/joint maps alike), or ``None``."""
    node = robot
    for part in dotted.split("."):
        node = node.get(part) if isinstance(node, dict) else getattr(node, part, None)
        if node is None:
            return None
    return node


def _is_adjustable(robot: Any, dotted: str) -> bool:
    from shc_cli.spec.robot import Adjustable

    return isinstance(_field(robot, dotted), Adjustable)


def check_points(sweep: Sweep) -> None:
    """Fail early, with the sweep file's line, on robot-file paths that do not exist and robots/gaits that do not
    load — before any simulation starts."""
    check_runs(sweep.path, sweep.points, _key_lines(sweep))


def check_runs(path: Path, points: list[Point], document_lines: dict[str, int | None]) -> None:
    """Fail early with the line of the file at ``path`` (``document_lines``: line of each key) on robot-file paths
    the robot lacks and robots/gaits that do not load; used by sweeps and studies."""
    from shc_cli.spec.checks import load_checked
    from shc_cli.spec.loading import load_robot, resolve

    robots = {str(p.options["robot"]) for p in points}
    for name in sorted(robots):
        try:
            robot = load_robot(resolve("robots", name)).robot
        except ShcError as error:
            raise SpecError([Issue(path, document_lines.get("robot"), "robot", str(error).splitlines()[0],
                                   "name a bundled robot or a robot file")]) from None
        for dotted in {k for p in points for k in p.overrides}:
            if _field(robot, dotted) is None:
                raise SpecError([Issue(path, document_lines.get(dotted), dotted,
                                       f"robot '{name}' has no field '{dotted}'",
                                       "use a dotted path of `shc validate --show ROBOT`")])
    seen: set[tuple[str, str]] = set()
    for point in points:
        key = (str(point.options["robot"]), str(point.options["gait"]))
        if key in seen:
            continue
        seen.add(key)
        try:
            load_checked(key[0], key[1] or None)
        except SpecError as error:
            issue = error.issues[0]
            raise SpecError([Issue(path, document_lines.get("gait"), "gait",
                                   f"{key[0]} / {key[1] or 'own gait'}: {issue.problem}", issue.fix)]) from None
        except ShcError as error:  # a gait that does not exist
            raise SpecError([Issue(path, document_lines.get("gait"), "gait", str(error).splitlines()[0],
                                   "name a bundled gait or a gait file")]) from None


def _key_lines(sweep: Sweep) -> dict[str, int | None]:
    from shc_cli.spec.source import Document

    document = Document(sweep.path)
    out: dict[str, int | None] = {}
    for key in [*sweep.grid, *sweep.fixed]:
        out[key] = document.line(("grid", key)) or document.line(("fixed", key))
    return out


def result_columns(sweep: Sweep) -> list[str]:
    return ["index", "slug", *sweep.grid, "status", "error", *RUN_KEYS, WARNINGS, *METRICS]


def _format(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    return str(value)


def write_results(path: Path, columns: list[str], rows: list[dict[str, Any]]) -> None:
    """The results table, atomically."""
    from shc_cli.outputs import write_text

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in sorted(rows, key=lambda r: int(r["index"])):
        writer.writerow([_format(row.get(c)) for c in columns])
    write_text(path, buffer.getvalue())


class RunPool:
    """Where runs execute: in this process (one worker), a pool of worker processes, or a Dask cluster — kept
    open across batches (``shc optimize`` submits one batch of trials at a time). Use as a context manager.

    Dask: the scheduler at ``scheduler``, or a LocalCluster of ``workers`` single-threaded worker processes;
    workers need shc installed and must see the output directory (a shared file system).
    """

    def __init__(self, executor: str, workers: int, scheduler: str | None) -> None:
        self.executor, self.workers, self.scheduler = executor, workers, scheduler
        self._pool: Any = None
        self._client: Any = None
        self._cluster: Any = None
        self._dask: Any = None

    def __enter__(self) -> RunPool:
        if self.executor == "dask":
            try:
                from dask import distributed
            except ImportError:
                raise SpecError([Issue(None, None, "--executor", "dask is not installed", "pip install 'shc[dask]' "
                                       "(dask[distributed]) or use --executor local")]) from None
            self._dask = distributed  # untyped library
            if self.scheduler is None:
                self._cluster = self._dask.LocalCluster(n_workers=self.workers, threads_per_worker=1, processes=True,
                                                        dashboard_address=None)
            self._client = self._dask.Client(self._cluster if self._cluster is not None else self.scheduler)
        elif self.workers > 1:
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(max_workers=self.workers)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._pool is not None:
            interrupted = exc[0] is not None
            self._pool.shutdown(wait=not interrupted, cancel_futures=interrupted)
        if self._client is not None:
            self._client.close()
        if self._cluster is not None:
            self._cluster.close()

    def results(self, points: list[Point], out: Path, metrics: tuple[str, ...] = METRICS,
                skip: float = 0.0) -> Iterator[dict[str, Any]]:
        """Rows of :func:`run_point` as the runs finish (in order with one local worker)."""
        if self._client is not None:
            futures = self._client.map(run_point, points, out=str(out.resolve()), metrics=metrics, skip=skip,
                                       pure=False)
            for future in self._dask.as_completed(futures):
                yield future.result()
            return
        if self._pool is None:
            for point in points:
                yield run_point(point, str(out), metrics, skip)
            return
        from concurrent.futures import as_completed

        futures = {self._pool.submit(run_point, point, str(out), metrics, skip): point for point in points}
        for future in as_completed(futures):
            point = futures[future]
            error = future.exception()
            if error is not None:  # the worker process itself died
                yield {"index": point.index, "slug": point.slug, **point.values, "status": "failed",
                       "error": _one_line(error)}
            else:
                yield future.result()


def check_executor(executor: str, scheduler: str | None) -> None:
    """One line for an unknown executor or a scheduler without Dask."""
    if executor not in ("local", "dask"):
        raise SpecError([Issue(None, None, "--executor", f"'{executor}' is not an executor", "use local or dask")])
    if scheduler is not None and executor != "dask":
        raise SpecError([Issue(None, None, "--scheduler", "only the dask executor has a scheduler",
                               "add --executor dask")])


def pool_results(points: list[Point], out: Path, executor: str, workers: int,
                 scheduler: str | None) -> Iterator[dict[str, Any]]:
    """Rows as the runs finish, from a :class:`RunPool` opened for these points."""
    with RunPool(executor, workers, scheduler) as pool:
        yield from pool.results(points, out)


def with_engine(sweep: Sweep, engine: str | None) -> Sweep:
    """The sweep with ``engine`` (``--engine``) for every run, unless the file chooses the engine itself."""
    if engine is None:
        return sweep
    from shc_cli.backends.engine_registry import ENGINES

    if engine not in ENGINES:
        raise SpecError([Issue(None, None, "--engine", f"'{engine}' is not a physics engine",
                               f"use {' or '.join(ENGINES)}")])
    if "engine" in sweep.fixed or "engine" in sweep.grid:
        return sweep
    return dataclasses.replace(sweep, points=[dataclasses.replace(point, options={**point.options, "engine": engine})
                                              for point in sweep.points])


def run_sweep(file: Path, workers: int | None, executor: str, scheduler: str | None, out: Path | None,
              resume: bool, overwrite: bool = False, engine: str | None = None) -> Path:
    """Check the sweep, run every point, write the results table and plots; returns the output directory
    (``overwrite``: delete an existing output directory first; ``resume``: continue it).

    ``engine`` is the physics engine of every run whose sweep file does not choose one (``engine`` in
    ``[fixed]`` or ``[grid]``).
    """
    sweep = with_engine(load_sweep(file), engine)
    check_executor(executor, scheduler)
    check_points(sweep)
    out = out or Path("runs") / sweep.name
    if resume and overwrite:
        raise SpecError([Issue(None, None, "--overwrite", "cannot be combined with --resume", "choose one")])
    if not resume:
        from shc_cli.loop.runlog import clear_output

        clear_output(out, overwrite,
                     "add --resume to continue it, --overwrite to run it again, or choose another --out")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    shutil.copyfile(sweep.path, out / "sweep.toml") if sweep.path.resolve() != (out / "sweep.toml").resolve() \
        else None
    count = workers or os.cpu_count() or 1
    columns = result_columns(sweep)
    started = time.perf_counter()
    rows_iter = pool_results(sweep.points, out, executor, count, scheduler)
    rows: list[dict[str, Any]] = []
    progress = _progress(len(sweep.points))
    partial = out / "results.partial.csv"
    with partial.open("w", encoding="utf-8", newline="") as handle:
        writer = csv.writer(handle, lineterminator="\n")
        writer.writerow(columns)
        try:
            for row in rows_iter:
                rows.append(row)
                writer.writerow([_format(row.get(c)) for c in columns])
                handle.flush()
                if progress is not None:
                    progress(len(rows), row)
        except KeyboardInterrupt:
            raise ShcError(f"interrupted: {len(rows)} runs finished, their rows are in {partial}; "
                           "continue with --resume") from None
    write_results(out / "results.csv", columns, rows)
    partial.unlink()
    from shc_cli.plots import plot_cot

    done = [r for r in rows if r["status"] == "ok"]
    if len({r.get("step_frequency_hz") for r in done}) > 1:
        group_keys = [k for k in sweep.grid if k not in ("robot", "gait") and not k.endswith("step_frequency")]
        for row in done:
            row["group"] = ", ".join(f"{k} {row[k]}" for k in group_keys if k in row)  # grids may differ in keys
        plot_cot(done, out / "cot.png")
    failed = len(rows) - len(done)
    fell = sum(1 for r in done if str(r.get("fell")) == "True")
    typer.echo(f"{sweep.name}: {len(rows)} runs in {time.perf_counter() - started:.1f} s with {count} "
               f"{executor} worker{'s' if count != 1 else ''}: {len(done)} ok ({fell} fell), {failed} failed "
               f"→ {out / 'results.csv'}")
    warned = [r for r in done if r.get(WARNINGS)]
    if warned:
        typer.echo(f"note: {len(warned)} run{'s' if len(warned) != 1 else ''} had engine warnings (results.csv "
                   f"column {WARNINGS}), e.g. {warned[0]['slug']}: {warned[0][WARNINGS]}")
    if done and all(r.get("steady_speed_mps") in (None, "") for r in done):
        typer.echo("note: steady_speed_mps is empty: no run held its velocity for a whole gait cycle after the "
                   "acceleration ramp (make `duration` longer)")
    return out


def _progress(total: int) -> Callable[[int, dict[str, Any]], None] | None:
    """The progress bar over the sweep's runs (``None``, quiet, in pipes and CI)."""
    from shc_cli.progress import progress_bar

    bar = progress_bar("sweep", total)
    if bar is None:
        return None
    return lambda done, row: bar.update(done, str(row["slug"])[:40])
