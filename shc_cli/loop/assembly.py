"""The one place where a run is put together and run: a :class:`RunSpec` and :func:`assemble`.

Every kind of run (``plan``, ``simulate``, ``run-hw``, ``shc ros``/``ros2`` on each backend, ``replay``) is a build
function: it opens what the run needs through the :class:`Assembly` it is handed (the run directory, the physics
world, the servo bus, the input, a live server — each closed by the assembly in reverse order, also when the
build or the run raises) and returns a :class:`RunSpec`: the controller, the backend, the input, the recorder,
the observers, the summariser, the plots and the live/pacing/progress plug-ins. :func:`assemble` builds the one
:class:`~shc_cli.loop.run_loop.RunLoop` from it and owns the rest: SIGINT/SIGTERM as a stop request (Ctrl-C exits
130, SIGTERM 143, with a finished run directory), every row on disk before anything else, the summary made once
from the finished record (the fields every run shares handed to the summariser, :class:`Finished`, not patched in
afterwards), the plots (skipped on a second signal) and the directory's final name. Meanwhile the package's log
records go to the directory's ``events.log`` (:mod:`shc_cli.events`).

A new capability plugs in as an observer (told every cycle; may stop the run with a reason) or as an input (the
commands), without new wiring: docs/architecture.md, "The run assembler".
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from contextlib import AbstractContextManager, ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar

from shc_cli.loop.run_loop import ControlledStop, LoopResult, Observer, ReadingT, Recorder, RunLoop, StartUp

if TYPE_CHECKING:
    from shc_cli.backends.base import Backend, InputSource
    from shc_cli.control.controller import Command, Controller, CycleOutput
    from shc_cli.loop.pacing import WallClock
    from shc_cli.record.runlog import RunDirectory
    from shc_cli.record.summary import RunSummary

T = TypeVar("T")


class Closable(Protocol):
    """Anything with a ``close()`` (an input, a servo bus, a live server)."""

    def close(self) -> object:
        ...


ClosableT = TypeVar("ClosableT", bound=Closable)

OnProgress = Callable[[int, int], None]
"""Told ``(walked cycles, cycles to walk)`` before the run, every :data:`PROGRESS_EVERY` walking cycles and
``(total, total)`` when the run ends (e.g. a progress bar)."""
PROGRESS_EVERY = 50


@dataclass(frozen=True)
class Finished:
    """What a summariser is given once the loop has ended and every row is on disk.

    Attributes:
        result: how the loop ended.
        directory: the run directory (still ``.partial``): the finished record to read back.
        shared: the fields every run's summary has, made by the assembler: ``complete``, ``stop_reason``, the
            controller's joint-speed limiting (``joint_speed_limited_cycles``, ``joint_speed_limited_share``,
            ``speed_limits_verified`` for a robot that verifies its limits), the pacer's statistics and a path
            run's fields.
    """

    result: LoopResult
    directory: Path
    shared: dict[str, object]


Summariser = Callable[[Finished], "RunSummary"]
"""Makes a run's summary, once, from the finished record (:class:`Finished`)."""


class Progress:
    """Counts the walking cycles for an :data:`OnProgress` (an observer of the loop; the assembler tells the end)."""

    def __init__(self, on_progress: OnProgress, total: int) -> None:
        self.on_progress, self.total, self.walked = on_progress, total, 0
        on_progress(0, total)

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        if command.state_request is None or out.robot_state.name == "RUNNING":
            self.walked += 1
            if self.walked % PROGRESS_EVERY == 0:
                self.on_progress(self.walked, self.total)
        return None

    def stop(self) -> None:
        self.on_progress(self.total, self.total)


@dataclass
class RunSpec(Generic[ReadingT]):
    """One run, as its build function describes it to :func:`assemble`.

    Attributes:
        controller: the controller (built from the backend's start joints).
        backend: the backend (started).
        source: the input (the commands once RUNNING).
        recorder: writes each cycle (the run directory's tables; :class:`~shc_cli.loop.run_loop.NullRecorder`).
        start_up: bring the robot to RUNNING first (None: the input drives the states itself).
        run: the run directory (None: nothing is recorded, no summary — a replay compares instead).
        summarise: the summary from the finished record (required with ``run``).
        controlled_stop: walk to a stop and shut down before ending (servos).
        observers: the kind's own observers, told every cycle first (a fall detector, a recorder of outputs,
            ROS outputs); a returned text stops the run with that reason.
        progress: counts the walking cycles (told the end before the summary).
        live: streams each cycle (its server handed to the assembly to close).
        pacing: the wall-clock pacer (its statistics go into the summary).
        late_observers: told after the pacer (a deadline).
        path_fields: a path run's summary fields, called at the end.
        plot: draws the plots into the run directory (skipped on a second signal, and for a run without cycles).
        after_loop: called right after the loop ends, before the summary (release the robot).
        on_loop: told the loop before it runs (a session that asks whether a stop was requested).
        flush_every: flush the recorder every this many cycles.
        on_fault: told each fault's text as it happens.
        absorb: told a fault mid-run before it stops the run; True: walked on from it (a leg given up,
            :class:`~shc_cli.loop.leg_fault.LegFaultAdapter`).
    """

    controller: Controller
    backend: Backend[ReadingT]
    source: InputSource
    recorder: Recorder[ReadingT]
    start_up: StartUp | None
    run: RunDirectory | None = None
    summarise: Summariser | None = None
    controlled_stop: ControlledStop | None = None
    observers: Sequence[Observer[ReadingT]] = ()
    progress: Progress | None = None
    live: Observer[ReadingT] | None = None
    pacing: WallClock | None = None
    late_observers: Sequence[Observer[ReadingT]] = ()
    path_fields: Callable[[], dict[str, object]] = dict
    plot: Callable[[Path], None] | None = None
    after_loop: Callable[[LoopResult], None] | None = None
    on_loop: Callable[[RunLoop[ReadingT]], None] | None = None
    flush_every: int = 200
    on_fault: Callable[[str], None] | None = None
    absorb: Callable[[str], bool] | None = None

    def all_observers(self) -> list[Observer[ReadingT]]:
        """Every observer in the order the loop tells them: the kind's, progress, live, pacing, the late ones."""
        plugged = [self.progress, self.live, self.pacing]
        return [*self.observers, *(o for o in plugged if o is not None), *self.late_observers]


@dataclass(frozen=True)
class Outcome:
    """A run as :func:`assemble` ended it: the loop's result, and with a run directory its final path and summary."""

    result: LoopResult
    path: Path | None = None
    summary: RunSummary | None = None

    @property
    def pair(self) -> tuple[Path, RunSummary]:
        """``(path, summary)`` of a recorded run."""
        assert self.path is not None and self.summary is not None, "a run without a run directory"
        return self.path, self.summary


class Assembly:
    """Handed to a build function: what it opens through it is closed in reverse order when the run is over (or
    when the build or the run raised)."""

    def __init__(self, stack: ExitStack) -> None:
        self._stack = stack

    def enter(self, manager: AbstractContextManager[T]) -> T:
        """Enter ``manager`` (a run directory, a backend); it exits when the run is over."""
        return self._stack.enter_context(manager)

    def closing(self, thing: ClosableT) -> ClosableT:
        """``thing`` (an input, a servo bus, a live server), closed when the run is over."""
        self._stack.callback(thing.close)
        return thing

    def callback(self, call: Callable[[], object]) -> None:
        """Call ``call`` when the run is over."""
        self._stack.callback(call)


def assemble(build: Callable[[Assembly], RunSpec[ReadingT]]) -> Outcome:
    """Build a run (``build`` opens its parts through the :class:`Assembly`), run it, finish its directory.

    Returns:
        the loop's result; for a recorded run the finished run directory and its summary.

    Raises:
        ShcError: bad input found by ``build`` (one line), with what it opened closed again.
        KeyboardInterrupt: a signal that came while the run was finishing (the run is kept as it ended; the
            signal still stops what runs it: a sweep, a study).
    """
    with ExitStack() as stack:
        spec = build(Assembly(stack))
        loop = RunLoop(spec.controller, spec.backend, spec.source, spec.recorder, spec.start_up,
                       spec.controlled_stop, observers=spec.all_observers(), flush_every=spec.flush_every,
                       on_fault=spec.on_fault, absorb=spec.absorb)
        if spec.on_loop is not None:
            spec.on_loop(loop)
        if spec.run is None:
            return Outcome(loop.run())
        return _recorded(loop, spec, spec.run)
    raise AssertionError("unreachable")  # (mypy: ExitStack may swallow exceptions)


def _recorded(loop: RunLoop[ReadingT], spec: RunSpec[ReadingT], run: RunDirectory) -> Outcome:
    """Run the loop, then finish the run directory (summary, plots, final name), interrupted or not."""
    from shc_cli.control.verified_limits import controller_shares
    from shc_cli.errors import interrupt
    from shc_cli.events import recording
    from shc_cli.loop.gc_pause import collecting
    from shc_cli.record.summary import RunSummary

    assert spec.summarise is not None, "a recorded run needs a summariser"
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
            if spec.after_loop is not None:
                spec.after_loop(result)  # not interruptible: a repeated signal only repeats the stop request
            controller = loop.controller
            limited = controller.joint_speed_limited_cycles
            ended: dict[str, object] = {
                "complete": result.complete, "stop_reason": result.stop_reason,
                "joint_speed_limited_cycles": limited,
                "joint_speed_limited_share": limited / controller.cycles if controller.cycles else 0.0}
            verified = controller_shares(controller)
            if verified is not None:  # only robots that verify their speed limits have the key
                ended["speed_limits_verified"] = verified
            try:  # a repeated signal now only repeats the stop request: the summary (from the log) is always made
                if spec.progress is not None:
                    spec.progress.stop()
                shared = {**(spec.pacing.statistics() if spec.pacing is not None else {}), **spec.path_fields(),
                          **ended}
                summary = spec.summarise(Finished(result, run.partial, shared))
            except KeyboardInterrupt:  # not from shc's handler: the rows and a minimal summary
                summary = RunSummary.model_validate({"cycles": result.cycles, "summary_skipped": True, **ended})
            signals.finishing = True  # from here a repeated signal skips what is left (the plots)
            late = signals.late is not None
            if late:
                summary.plots_skipped = True
            elif spec.plot is not None and result.cycles > 0:  # a run stopped before its first cycle: nothing to draw
                try:
                    spec.plot(run.partial)
                except KeyboardInterrupt:
                    summary.plots_skipped = True
        finished = run.finish(summary)
        if late:  # the run is kept as it ended; the signal still stops what runs it (a sweep, a study)
            raise interrupt(signals.late or "SIGINT")
        return Outcome(result, finished, summary)
    finally:
        signals.restore()
