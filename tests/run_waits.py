"""Waiting for a running shc subprocess to walk: the tests act on a walking robot however slow the machine is."""

from __future__ import annotations

import subprocess
import time
from pathlib import Path


def wait_running(run: Path, process: subprocess.Popen[str] | None = None, extra_s: float = 0.0,
                 timeout_s: float = 90.0) -> None:
    """Wait until the streamed ``log.csv`` of the run directory ``run`` (still ``RUN.partial``; flushed every 100–200
    cycles) shows RUNNING, then ``extra_s`` more [s]. A ``process`` that ends first fails the wait at once with its
    stderr (a run that faulted during start-up), instead of waiting ``timeout_s`` for a log that is never written."""
    log = run.with_name(run.name + ".partial") / "log.csv"
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process is not None and process.poll() is not None:
            raise AssertionError(f"{run.name}: the process ended before walking: {process.communicate()[1]}")
        if log.exists() and ",RUNNING," in log.read_text():
            time.sleep(extra_s)
            return
        time.sleep(0.1)
    raise AssertionError(f"{log}: never RUNNING within {timeout_s:.0f} s")
