"""One point of a sweep (or one run of a study trial): simulate it into ``OUT/runs/SLUG`` and analyse it into a
results row — in a worker process, so a failing run is a row (``status = failed``), not the end of the sweep.

A user error (:class:`~shc_cli.errors.ShcError`: a bad option, a missing file) is the row's one-line ``error``. Any
other exception is a programming error: its traceback is kept in ``OUT/runs/SLUG/error.log`` (:data:`ERROR_LOG`),
logged, and the row's ``error`` names that file. A Ctrl-C stops the sweep instead of failing the run.
"""

from __future__ import annotations

import logging
import shutil
import traceback
from pathlib import Path

from shc_cli.domain.sweeps.checks import is_adjustable
from shc_cli.domain.sweeps.options import option, point_config
from shc_cli.domain.sweeps.results import METRICS, RUN_KEYS, WARNINGS, Row
from shc_cli.errors import Interrupted, ShcError, SpecError, interrupt, signal_name
from shc_cli.spec.sweep import Point, variant_text

log = logging.getLogger(__name__)

ERROR_LOG = "error.log"
"""File in a failed point's run directory with the traceback of a programming error."""


STOP_REQUEST = ".stop-request"
"""File in a sweep's or study's output directory that asks the runs not yet started to stop at once (written when the
sweep is interrupted: the worker processes have runs queued; its text is the signal's name)."""


def request_stop(out: Path, signal: str) -> None:
    """Ask the runs under ``out`` not yet started to stop (:data:`STOP_REQUEST`)."""
    (out / STOP_REQUEST).write_text(signal, encoding="utf-8")


def clear_stop(out: Path) -> None:
    """Forget an earlier interrupted sweep's stop request (a sweep or study starting, or resuming, in ``out``)."""
    (out / STOP_REQUEST).unlink(missing_ok=True)


def run_point(point: Point, out: str, metrics: tuple[str, ...] = METRICS, skip: float = 0.0) -> Row:
    """Simulate one grid point into ``out/runs/<slug>`` (or re-read it if finished) and analyse it; never raises
    but for a Ctrl-C (``KeyboardInterrupt``).

    Returns the results row: index, slug, the grid values, ``status`` (``ok``/``failed``), ``error``, the
    :data:`RUN_KEYS` and the ``metrics`` (``shc analyze`` keys, leaving out the first ``skip`` seconds of running as
    ``shc analyze --skip``). ``shc optimize`` runs its trials through it too.
    """
    row: Row = {"index": point.index, "slug": point.slug, **point.values, "status": "ok", "error": ""}
    directory = Path(out) / "runs" / point.slug
    stop = Path(out) / STOP_REQUEST
    if stop.exists():  # the sweep was interrupted while this run waited in a worker's queue
        raise interrupt(stop.read_text(encoding="utf-8").strip())
    try:
        if stopped_by_signal(directory) or _failed_before(directory):  # run it again
            shutil.rmtree(directory)
        if not (directory / "summary.json").exists():
            partial = directory.with_name(directory.name + ".partial")
            if partial.exists():
                shutil.rmtree(partial)  # a crashed earlier attempt
            simulate_point(point, Path(out), directory)
        from shc_cli.analysis.metrics import Window, analyze_run
        from shc_cli.domain.stored_run import open_run

        stopped = signal_stop(directory)
        if stopped is not None:  # Ctrl-C during this run: it is kept (partial), the sweep stops
            raise interrupt(stopped)
        run = open_run(directory)
        if run.summary.stop_reason == "diverged":  # the physics blew up: no figure of it means anything
            row.update(status="failed", error=f"{run.summary.fault} (run kept in {directory})")
            return row
        result = analyze_run(run, Window(skip_s=skip))
        summary = run.summary.model_dump(include=set(RUN_KEYS))  # RunSummary fields
        row.update({key: summary[key] for key in RUN_KEYS})
        row[WARNINGS] = "; ".join(run.summary.engine_warnings or [])
        row.update({key: result.get(key) for key in metrics})
    except ShcError as error:  # a failing run is a row, not the end of the sweep
        if interrupted(error):
            raise interrupt(signal_name(error)) from error  # Ctrl-C during the run: stop the sweep, not this run
        row.update(status="failed", error=one_line(error))
    except Exception as error:  # a programming error: a row too, with its traceback kept
        if interrupted(error):
            raise interrupt(signal_name(error)) from error
        row.update(status="failed", error=f"{one_line(error)} (traceback in {keep_traceback(directory, error)})")
    return row


def failed_row(point: Point, error: BaseException) -> Row:
    """The row of a point whose worker process died (``error``: what the pool reported)."""
    return {"index": point.index, "slug": point.slug, **point.values, "status": "failed", "error": one_line(error)}


def keep_traceback(directory: Path, error: BaseException) -> Path:
    """Write ``error``'s traceback to ``directory/error.log`` (the run directory, finished or not, stays as it
    was), log it, and return the file's path."""
    path = directory / ERROR_LOG
    directory.mkdir(parents=True, exist_ok=True)
    path.write_text("".join(traceback.format_exception(error)), encoding="utf-8")
    log.error("%s: %s (traceback in %s)", directory.name, one_line(error), path)
    return path


def _failed_before(directory: Path) -> bool:
    """A run directory holding only an earlier attempt's :data:`ERROR_LOG` (no summary): run it again."""
    return (directory / ERROR_LOG).exists() and not (directory / "summary.json").exists()


def interrupted(error: BaseException) -> bool:
    """Whether ``error`` stands for a Ctrl-C: ``simulate`` turns the KeyboardInterrupt into a one-line ShcError,
    keeping it as the context."""
    seen: BaseException | None = error
    while seen is not None:
        if isinstance(seen, (KeyboardInterrupt, Interrupted)):
            return True
        seen = seen.__cause__ or seen.__context__
    return False


def stopped_by_signal(directory: Path) -> bool:
    """A finished run directory whose summary says it did not play to its end because of a signal."""
    return signal_stop(directory) is not None


def signal_stop(directory: Path) -> str | None:
    """The signal (``"SIGINT"``, ``"SIGTERM"``) that stopped the finished run in ``directory``, or None."""
    import json

    from shc_cli.record.summary import parse_summary

    try:
        summary = parse_summary(json.loads((directory / "summary.json").read_text(encoding="utf-8")))
    except (OSError, ValueError, TypeError):  # pydantic's ValidationError is a ValueError
        return None
    return summary.stop_reason if summary.stop_reason in ("SIGINT", "SIGTERM") else None


def one_line(error: BaseException) -> str:
    """An error as one line of the table: a spec error's issues, else ``Type: first line``."""
    if isinstance(error, SpecError):
        return "; ".join(str(issue) for issue in error.issues)
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0] if text else ''}"


def simulate_point(point: Point, out: Path, directory: Path) -> None:
    """Simulate the point into ``directory`` (its robot a variant file under ``out/variants`` if it changes
    robot-file values): its :class:`~shc_cli.domain.config.SimulationConfig`, passed down whole."""
    from shc_cli.domain.simulate import simulate

    simulate(point_config(point, robot=robot_for(point, out), out=directory, plots=False))


def robot_for(point: Point, out: Path) -> str:
    """The robot to load: the named one, or a variant file ``out/variants/SLUG.toml`` extending it with the point's
    overrides."""
    from shc_cli.spec.loading import load_robot, resolve

    name = str(option(point, "robot"))
    if not point.overrides:
        return name
    base = resolve("robots", name)
    robot = load_robot(base).robot
    adjustable = {path for path in point.overrides if is_adjustable(robot, path)}
    path = out / "variants" / f"{point.slug}.toml"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(variant_text(base, point.overrides, adjustable), encoding="utf-8")
    return str(path)
