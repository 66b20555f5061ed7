"""Waiting for a running shc subprocess to walk: the tests act on a walking robot however slow the machine is."""

from __future__ import annotations

import subprocess
import threading
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


class StderrLines:
    """The stderr of a running ``shc -v …`` read as it comes: ``-v`` logs each state change as it happens, where the
    streamed log.csv that :func:`wait_running` reads is flushed every 100 cycles (10 s at an AX-12A bus's 10 Hz)."""

    def __init__(self, process: subprocess.Popen[str]) -> None:
        self.lines: list[str] = []
        self.running = threading.Event()
        self._thread = threading.Thread(target=self._read, args=(process,), daemon=True)
        self._thread.start()

    def _read(self, process: subprocess.Popen[str]) -> None:
        assert process.stderr is not None
        for line in process.stderr:
            self.lines.append(line)
            if line.strip().endswith("→ RUNNING"):
                self.running.set()

    def text(self) -> str:
        """All of it, once the process has ended."""
        self._thread.join(timeout=30)
        return "".join(self.lines)


def wait_running_on_stderr(process: subprocess.Popen[str], stderr: StderrLines, extra_s: float = 0.0,
                           timeout_s: float = 90.0) -> None:
    """Wait until ``process`` (``shc -v``, its stderr read by ``stderr``) says its robot is RUNNING, then ``extra_s``
    more [s]; a process that ends first fails the wait at once with its stderr."""
    deadline = time.monotonic() + timeout_s
    while not stderr.running.wait(timeout=0.1):
        if process.poll() is not None:
            raise AssertionError(f"the process ended before walking: {stderr.text()}")
        if time.monotonic() > deadline:
            raise AssertionError(f"never RUNNING within {timeout_s:.0f} s: {''.join(stderr.lines)}")
    time.sleep(extra_s)
