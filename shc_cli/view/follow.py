"""``shc view RUN --follow``: the viewer attached to a run in progress, tailing the run directory as it is written.

A run (``plan``, ``simulate``, ``run-hw``, ``shc ros``) writes its tables into ``RUN.partial/`` while it runs —
``log.csv`` (or ``joints.csv``, ``body.csv``, ``tips.csv`` for a kinematic run) flushed every 100–200 cycles, and its
``robot.toml`` at the start — and renames the directory to ``RUN`` when it is finished. The follower reads what is
on disk every :data:`POLL_S`: the complete lines of each table (a row being written is left for the next read; the
tables of a kinematic run are cut to the same length), as a :class:`~shc_cli.record.runread.RunLog` of the run's own
robot, with no summary yet (so the terrain is drawn flat until the run has finished). When ``RUN`` appears, the
finished run is read once more, with its summary, and the following ends. Reading the whole log each time keeps
this simple and costs O(rows) per poll: tens of milliseconds for a few minutes of a run.
"""

from __future__ import annotations

import logging
import shutil
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

from shc_cli.errors import NotFoundError
from shc_cli.record.runlog import PARTIAL_SUFFIX
from shc_cli.record.runread import RunLog

log = logging.getLogger(__name__)

POLL_S = 1.0
"""How often the run directory is read again [s]."""
TABLES = ("log.csv", "joints.csv", "body.csv", "tips.csv")


def run_paths(target: str) -> tuple[Path, Path]:
    """``(RUN.partial, RUN)`` for ``RUN`` or ``RUN.partial``; a one-line error when neither exists."""
    path = Path(target.rstrip("/"))
    final = path.with_name(path.name.removesuffix(PARTIAL_SUFFIX))
    partial = final.with_name(final.name + PARTIAL_SUFFIX)
    if not partial.is_dir() and not final.is_dir():
        raise NotFoundError(f"{target}: no run in progress ({partial} does not exist) and no finished run (start the "
                            "run first: shc simulate --out RUN …, then shc view RUN --follow)")
    return partial, final


def snapshot(partial: Path) -> RunLog | None:
    """What a run in progress has written so far, or None (no robot file or no complete row yet, or the directory
    has just been renamed)."""
    from shc_cli.errors import ShcError
    from shc_cli.record.runread import read_tables
    from shc_cli.spec.loading import load_robot

    try:
        robot = load_robot(partial / "robot.toml").robot
        contents = {name: (partial / name).read_bytes() for name in TABLES if (partial / name).exists()}
    except (OSError, ShcError):
        return None
    if robot is None or not contents:
        return None
    kept = {name: data[:data.rfind(b"\n") + 1] for name, data in contents.items()}  # complete lines only
    rows = min(data.count(b"\n") for data in kept.values())  # header included
    if rows < 2:
        return None
    folder = Path(tempfile.mkdtemp(prefix="shc-follow-"))
    try:
        for name, data in kept.items():
            (folder / name).write_bytes(b"".join(data.splitlines(keepends=True)[:rows]))
        run = read_tables(folder, robot)
    except (OSError, ShcError, ValueError, KeyError, IndexError):  # a table caught mid-write: the next poll
        return None
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    run.path = partial
    return run


class Follower:
    """A thread that reads the run every :data:`POLL_S` and tells ``on_update(run, finished)`` each time it has
    grown, until the run has finished (``finished`` True: the final directory, with its summary) or :meth:`stop`.

    Args:
        partial: the run's directory while it runs (``RUN.partial``).
        final: its name once finished (``RUN``).
        on_update: told each new state of the run.
    """

    def __init__(self, partial: Path, final: Path, on_update: Callable[[RunLog, bool], None]) -> None:
        self.partial, self.final, self.on_update = partial, final, on_update
        self.rows = 0
        self.finished = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="shc-view-follow", daemon=True)

    def first(self, timeout_s: float = 600.0) -> RunLog:
        """The run as it is now, waiting (up to ``timeout_s``) for its first rows (:meth:`start` follows it on)."""
        from shc_cli.domain.stored_run import open_run

        deadline = time.monotonic() + timeout_s
        while True:
            if self.final.is_dir() and not self.partial.is_dir():
                self.finished = True
                return open_run(self.final)
            run = snapshot(self.partial)
            if run is not None:
                self.rows = len(run.t)
                return run
            if time.monotonic() > deadline:
                raise NotFoundError(f"{self.partial}: no rows written within {timeout_s:.0f} s")
            time.sleep(POLL_S / 4)

    def start(self) -> None:
        """Follow the run from the rows :meth:`first` read (nothing to follow once it has finished)."""
        if not self.finished:
            self._thread.start()

    def _run(self) -> None:
        from shc_cli.domain.stored_run import open_run

        while not self._stop.wait(POLL_S):
            try:
                if self.final.is_dir() and not self.partial.is_dir():
                    self.finished = True
                    self.on_update(open_run(self.final), True)
                    return
                run = snapshot(self.partial)
                if run is not None and len(run.t) > self.rows:
                    self.rows = len(run.t)
                    self.on_update(run, False)
            except Exception:  # a bug, not a run being written: stop following and say why
                log.exception("shc view: following %s stopped", self.partial)
                return

    def stop(self) -> None:
        self._stop.set()
