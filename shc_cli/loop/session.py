"""Running a loop into a run directory and finishing it, also when interrupted.

:func:`execute` is what ``plan``, ``simulate`` and ``run-hw`` share around :class:`~shc_cli.loop.run_loop.RunLoop`:
SIGINT and SIGTERM become a stop request (the loop ends the run, or shuts the robot down first), every logged
row is flushed and closed, the summary gets ``"complete"``, ``"stop_reason"`` and the controller's count of
cycles whose joint speeds it limited (``"joint_speed_limited_cycles"``, ``"joint_speed_limited_share"``), the
plots are drawn and the directory gets its final name — for an interrupted run too (only ``"complete": false``
marks it). A second signal while finishing skips the plots (not the summary, made from the log read back); the rows
are on disk before anything else happens. Meanwhile the package's log records go to the directory's ``events.log``
(:mod:`shc_cli.events`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from shc_cli.control.verified_limits import controller_shares
from shc_cli.errors import interrupt
from shc_cli.events import recording
from shc_cli.loop.gc_pause import collecting
from shc_cli.loop.run_loop import LoopResult, ReadingT, RunLoop
from shc_cli.record.runlog import RunDirectory
from shc_cli.record.summary import RunSummary


def execute(loop: RunLoop[ReadingT], run: RunDirectory, summarise: Callable[[LoopResult], RunSummary],
            plot: Callable[[Path], None] | None = None, after_loop: Callable[[LoopResult], None] | None = None
            ) -> tuple[Path, RunSummary, LoopResult]:
    """Run the loop, then finish the run directory (summary, plots, final name), interrupted or not.

    Args:
        loop: the loop (its backend started).
        run: the run directory the loop's recorder writes.
        summarise: the run's summary from the loop's result; ``complete`` and ``stop_reason`` are added.
        plot: draws the plots into the given directory (skipped on a second signal).
        after_loop: called right after the loop ends, before the summary (e.g. release the robot).

    Returns:
        the finished run directory, its summary and the loop's result.
    """
    signals = run.signals  # caught since the run directory was created (a signal before the loop stops it at once)
    signals.install()
    signals.on_stop = loop.request_stop
    if signals.received is not None:
        loop.request_stop(signals.received)
    try:
        with recording(run.partial, lambda: loop.cycle):  # warnings, faults and state changes: events.log
            try:
                with collecting():  # also when the command paused the garbage collector (shc_cli.loop.gc_pause)
                    result = loop.run()
            finally:
                run.close()  # every row on disk before anything else (also when the loop raised)
                signals.loop_over = True  # a signal from now on is kept (signals.late), not lost on the ended loop
            if after_loop is not None:
                after_loop(result)  # not interruptible: a repeated signal only repeats the stop request
            try:  # a repeated signal now only repeats the stop request: the summary (from the log) is always made
                summary = summarise(result)
            except KeyboardInterrupt:  # not from shc's handler: the rows and a minimal summary
                summary = RunSummary(cycles=result.cycles, summary_skipped=True)
            signals.finishing = True  # from here a repeated signal skips what is left (the plots)
            controller = loop.controller
            limited = controller.joint_speed_limited_cycles
            summary = summary.updated(complete=result.complete, stop_reason=result.stop_reason,
                                      joint_speed_limited_cycles=limited,
                                      joint_speed_limited_share=limited / controller.cycles if controller.cycles
                                      else 0.0)
            verified = controller_shares(controller)
            if verified is not None:  # only robots that verify their speed limits have the key
                summary = summary.updated(speed_limits_verified=verified)
            late = signals.late is not None
            if late:
                summary.plots_skipped = True
            elif plot is not None and result.cycles > 0:  # a run stopped before its first cycle has nothing to draw
                try:
                    plot(run.partial)
                except KeyboardInterrupt:
                    summary.plots_skipped = True
        finished = run.finish(summary)
        if late:  # the run is kept as it ended; the signal still stops what runs it (a sweep, a study)
            raise interrupt(signals.late or "SIGINT")
        return finished, summary, result
    finally:
        signals.restore()
