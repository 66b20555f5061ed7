"""SIGINT and SIGTERM as a run's stop request, from the moment its run directory exists until it is finished.

A run directory (:class:`~shc_cli.record.runlog.RunDirectory`) catches both signals as soon as it is created, so a
signal while the physics opens or the controller is built is not lost: the loop, once it starts, stops at its
first cycle and the run directory is finished like any interrupted run (``summary.json`` with ``"complete":
false``). :func:`shc_cli.loop.assembly.assemble` routes the signals to the loop while it runs; a repeated signal while
the run is finishing skips what is left (the plots). Only the main thread can handle signals: elsewhere (a sweep's
worker thread) nothing is installed.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any

from shc_cli.errors import interrupt


class StopSignals:
    """The SIGINT/SIGTERM handler of one run.

    Attributes:
        received: the first signal's name (``"SIGINT"``, ``"SIGTERM"``) before the loop took over, else None.
        on_stop: while the loop runs, told each signal's name (the loop's ``request_stop``).
        late: the first signal's name after the loop ended and before the run finished (while the robot is released
            and the summary made, which a signal must not cut short), else None: the run is kept as it finished, its
            plots skipped, and then the signal is raised as :class:`KeyboardInterrupt` (a sweep or study stops).
        finishing: the loop is over: a signal now raises :class:`KeyboardInterrupt` (skip the rest).
    """

    def __init__(self) -> None:
        self.received: str | None = None
        self.on_stop: Callable[[str], None] | None = None
        self.late: str | None = None
        self.loop_over = False
        self.finishing = False
        self._previous: dict[signal.Signals, Any] = {}

    def install(self) -> None:
        """Catch SIGINT and SIGTERM (in the main thread only)."""
        if threading.current_thread() is threading.main_thread() and not self._previous:
            self._previous = {sig: signal.signal(sig, self._handle) for sig in (signal.SIGINT, signal.SIGTERM)}

    def _handle(self, signum: int, frame: FrameType | None) -> None:
        name = signal.Signals(signum).name
        if self.finishing:
            raise interrupt(name)  # a second Ctrl-C while finishing: skip what is left (the plots)
        if self.loop_over:
            self.late = self.late or name  # the loop ended on its own: no stop request left to make
            return
        if self.on_stop is not None:
            self.on_stop(name)  # on hardware a repeat while stopping changes nothing
            return
        if self.received is not None:
            raise interrupt(name)  # a second signal before the loop started: give up at once
        self.received = name

    def restore(self) -> None:
        """Put the previous handlers back."""
        for sig, old in self._previous.items():
            signal.signal(sig, old)
        self._previous = {}
