"""The one run loop: start-up to RUNNING, the input, the controller step, the backend, the log, the stop.

:class:`RunLoop` drives any :class:`~shc_cli.backends.base.Backend` (kinematic for ``plan``, physics for
``simulate``, Dynamixel for ``run-hw``) with any input source. Each cycle: the command (a RUNNING request
until the start-up is done, then the input's next command, then — after a stop request on a backend with a
controlled stop — requests towards the stop state), the controller step with the backend's sensors, the output
shown to a source that steers by it (:class:`~shc_cli.backends.base.FeedbackSource`: a path follower), the
targets applied, one control period, the reading, the fault check, the recorder's row, the observers (who may
stop the run: a fall). It stops when the input is over, on a fault, on an observer's reason or on a stop request
(SIGINT/SIGTERM via :func:`shc_cli.loop.assembly.assemble`, or :meth:`RunLoop.request_stop`). Robot and walk state
changes, faults, stop requests and the end are logged as events (:mod:`shc_cli.events`: the run's ``events.log``).
:meth:`RunLoop.run` is :meth:`RunLoop.begin`, :meth:`RunLoop.step` until it returns ``None``, :meth:`RunLoop.finish`;
the Gymnasium environment (:mod:`shc_cli.gym`) calls them itself, one cycle a step, with an :data:`Adjust` of the
controller's output (a policy's residual).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Generic, Protocol, TypeVar

import numpy as np

from shc_cli.backends.base import Backend, FeedbackSource, InputSource
from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.control.sensing import Sensors
from shc_cli.control.walk import WalkState
from shc_cli.errors import ShcError
from shc_cli.events import event
from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

START_UP_MARGIN_S = 2.0
"""Extra time allowed for reaching RUNNING beyond the robot's start-up duration [s] (plan, simulate)."""
HARDWARE_START_UP_SHARE = 2.5
"""A real robot's start-up, or its shut-down after a stop, may take this many times the robot's start-up duration
(``start_up.time_to_start``): the goals are rate-limited and the servos lag them (``run-hw``)."""
HARDWARE_START_UP_MARGIN_S = 10.0
"""Extra time allowed for a real robot's start-up beyond :data:`HARDWARE_START_UP_SHARE` of its duration [s]."""

ReadingT = TypeVar("ReadingT")
"""The backend's reading type (:data:`shc_cli.backends.base.ReadingT`)."""
ReadingT_contra = TypeVar("ReadingT_contra", contravariant=True)

Observer = Callable[[int, Command, CycleOutput, ReadingT], "str | None"]
"""Called after every logged cycle with (cycle, command, output, reading); a returned text stops the run with that
reason (e.g. ``"fell"``)."""


Adjust = Callable[[CycleOutput], CycleOutput]
"""Changes a cycle's controller output before the backend applies it (:meth:`RunLoop.step`)."""


@dataclass(frozen=True, slots=True)
class Cycle(Generic[ReadingT]):
    """One control cycle as :meth:`RunLoop.step` ran it: the command, the output (as applied), the joint
    targets the backend applied ``(L, n)`` [rad] and the reading after it."""

    command: Command
    out: CycleOutput
    applied: np.ndarray
    reading: ReadingT


class Recorder(Protocol[ReadingT_contra]):
    """Writes one logged cycle (the run's tables): the joint targets as applied ``(L, n)`` [rad] and the reading."""

    def record(self, cycle: int, command: Command, out: CycleOutput, applied: np.ndarray,
               reading: ReadingT_contra) -> None:
        ...

    def flush(self) -> None:
        ...


class NullRecorder:
    """Writes nothing (a replay compares instead of logging)."""

    def record(self, cycle: int, command: Command, out: CycleOutput, applied: np.ndarray, reading: object) -> None:
        """Nothing to write."""

    def flush(self) -> None:
        """Nothing to flush."""


class SequenceInput:
    """Any iterable of commands as an input source (a list, a generator over a recording)."""

    def __init__(self, commands: Iterable[Command]) -> None:
        self._commands = iter(commands)

    def next(self) -> Command | None:
        return next(self._commands, None)

    def close(self) -> None:
        """Nothing to release."""


@dataclass(frozen=True)
class StartUp:
    """How the loop brings the robot to RUNNING before the input starts.

    Attributes:
        limit_cycles: cycles allowed for it.
        as_fault: when the limit passes, stop as a fault (``run-hw``) instead of raising a one-line error.
    """

    limit_cycles: int
    as_fault: bool = False

    @classmethod
    def of(cls, robot: Robot, hardware: bool = False) -> StartUp:
        """The start-up allowance of ``robot``: its start-up duration plus :data:`START_UP_MARGIN_S` (an error when
        it passes), or on hardware :data:`HARDWARE_START_UP_SHARE` of it plus :data:`HARDWARE_START_UP_MARGIN_S` (a
        fault)."""
        time_to_start = robot.start_up.time_to_start
        if hardware:
            return cls(round((time_to_start * HARDWARE_START_UP_SHARE + HARDWARE_START_UP_MARGIN_S)
                             / robot.time_delta), as_fault=True)
        return cls(round((time_to_start + START_UP_MARGIN_S) / robot.time_delta))


@dataclass(frozen=True)
class ControlledStop:
    """After a stop request or the input's end, walk to a stop and shut down to ``state`` before ending (``run-hw``).

    Attributes:
        state: the state to reach.
        timeout_s: how long it may take at most [s].
    """

    state: RobotState
    timeout_s: float


@dataclass
class LoopResult:
    """How a run ended.

    Attributes:
        cycles: logged control cycles.
        stop_reason: ``"end"`` (the input was played to its end), ``"SIGINT"``, ``"SIGTERM"``, ``"fault"``,
            ``"fell"`` or another observer's or caller's reason.
        fault: the fault's text (``stop_reason == "fault"``).
        stop_requested: a stop was requested from outside (signal or :meth:`RunLoop.request_stop`).
    """

    cycles: int
    stop_reason: str
    fault: str | None = None
    stop_requested: bool = False

    @property
    def complete(self) -> bool:
        """The run played its input to the end."""
        return self.stop_reason == "end"


class RunLoop(Generic[ReadingT]):
    """Drives a controller on a backend.

    Args:
        controller: the controller (already built from the backend's start joints).
        backend: the backend (started).
        source: the input once RUNNING (or from the first cycle when ``start_up`` is None).
        recorder: writes each cycle.
        start_up: bring the robot to RUNNING first (None: the input drives the states itself, as a replay).
        controlled_stop: shut down before ending after a stop request (None: end at once).
        observers: called after each recorded cycle; a returned text stops the run.
        flush_every: flush the recorder every this many cycles.
        on_fault: told each fault's text as it happens (e.g. to print it).
        absorb: told a fault mid-run before it stops the run; True: walked on from it (the run stops only if the
            backend still reports one).
    """

    def __init__(self, controller: Controller, backend: Backend[ReadingT], source: InputSource,
                 recorder: Recorder[ReadingT],
                 start_up: StartUp | None, controlled_stop: ControlledStop | None = None,
                 observers: Sequence[Observer[ReadingT]] = (), flush_every: int = 200,
                 on_fault: Callable[[str], None] | None = None,
                 absorb: Callable[[str], bool] | None = None) -> None:
        self.controller, self.backend, self.source, self.recorder = controller, backend, source, recorder
        self.start_up, self.controlled_stop = start_up, controlled_stop
        self.observers = list(observers)
        self.flush_every = flush_every
        self.on_fault = on_fault
        self.absorb = absorb
        """Told a fault mid-run first: True when it was walked on from (``run-hw --on-fault adapt``), which ends
        no run unless the backend still reports a fault."""
        self.dt = controller.robot.time_delta
        self.started = start_up is None
        self.stop_reason: str | None = None
        self.requested = False
        self.fault_text: str | None = None
        self.cycle: int | None = None
        """The control cycle running now (``None`` before the loop runs)."""
        self._stopping_since: int | None = None
        self._stop_announced = False
        self._stop_limit_s = 0.0
        self._observe = source.observe if isinstance(source, FeedbackSource) else None
        """The source's feedback hook (:class:`~shc_cli.backends.base.FeedbackSource`), told every cycle's output."""
        self._cycle = 0
        self._over = False
        self._states: tuple[RobotState | None, WalkState | None] = (None, None)
        self._sensors: Sensors | None = None
        self.adjust: Adjust | None = None
        """Changes every cycle's output in :meth:`run` (a policy file's action, :mod:`shc_cli.loop.policy.drive`)."""

    def request_stop(self, reason: str) -> None:
        """Stop (or begin the controlled stop) at the next cycle; the first reason is kept."""
        self.requested = True
        if self.stop_reason is None:
            self.stop_reason = reason

    def _fault(self, text: str) -> None:
        self.fault_text = text
        self.stop_reason = "fault"
        event(log, logging.ERROR, "fault", "fault: %s", text, terminal=self.on_fault is None)
        if self.on_fault is not None:
            self.on_fault(text)

    def _command(self, cycle: int) -> Command | None:
        """This cycle's command; ``None`` ends the run."""
        controller = self.controller
        if not self.started and controller.state == RobotState.RUNNING:
            self.started = True
        if self.started and self.stop_reason is None:
            command = self.source.next()
            if command is not None:
                return command
            if self.stop_reason is None:  # (a stop requested while the input waited keeps its reason)
                self.stop_reason = "end"  # the input is over
        if self.stop_reason is not None:
            return self._stopping(cycle)
        assert self.start_up is not None
        if cycle > self.start_up.limit_cycles:
            text = f"did not reach RUNNING within {self.start_up.limit_cycles} cycles"
            if not self.start_up.as_fault:
                raise ShcError(f"{controller.robot.name}: {text} of start-up")
            self._fault(text)
            return None
        return Command(state_request=RobotState.RUNNING)

    def _stopping(self, cycle: int) -> Command | None:
        """After a stop request: end now, or walk to a stop and shut down first (:class:`ControlledStop`)."""
        stop, controller = self.controlled_stop, self.controller
        if not self._stop_announced:
            self._stop_announced = True
            text = "the input is over" if self.stop_reason == "end" else f"stop requested ({self.stop_reason})"
            event(log, logging.INFO, "stop_requested", "%s", text, cycle=cycle)
        if stop is None:
            return None
        if self._stopping_since is None:
            self._stopping_since = cycle
            down = controller.state > stop.state
            self._stop_limit_s = stop.timeout_s + (HARDWARE_START_UP_SHARE * controller.robot.start_up.time_to_start
                                                    if down else 0.0)
        walker = controller.walker
        stopped = walker is None or walker.state == WalkState.STOPPED
        reached = controller.state <= stop.state and not controller.transition_pending
        if (reached and stopped) or (cycle - self._stopping_since) * self.dt > self._stop_limit_s:
            return None
        return Command(state_request=stop.state)  # zero velocity: stop walking, then shut down

    def run(self) -> LoopResult:
        """Run until the input is over, a fault, an observer's reason or a stop request."""
        if self.begin():
            step, adjust = self.step, self.adjust
            while step(adjust) is not None:
                pass
        return self.finish()

    def begin(self) -> bool:
        """Before the first cycle: the backend's fault check and first sensors; False (a fault) ends the run."""
        self._cycle, self._over, self._states = 0, False, (None, None)
        fault = self.backend.fault()
        if fault is not None:
            self._fault(fault)
            return False
        self._sensors = self.backend.sensors(True)  # the controller's leg odometry reads them every cycle
        self.backend.begin()
        return True

    def step(self, adjust: Adjust | None = None) -> Cycle[ReadingT] | None:
        """One control cycle (:meth:`begin` first); ``None`` once the run is over (then :meth:`finish`).

        Args:
            adjust: changes the controller's output before it is applied (a learned policy's residual,
                :mod:`shc_cli.gym`); the recorder and the observers see the changed output.
        """
        controller, backend = self.controller, self.backend
        if self._over:
            return None
        cycle = self._cycle
        self.cycle = cycle
        command = self._command(cycle)
        if command is None:
            self._over = True
            return None
        out = controller.step(command, self._sensors)
        if adjust is not None:
            out = adjust(out)
        if self._observe is not None:
            self._observe(out)
        if out.robot_state is not self._states[0] or out.walk_state is not self._states[1]:
            self._states = self._state_events(cycle, out, *self._states)
        applied = backend.apply(out)
        backend.advance()
        reading = backend.read()
        fault = backend.fault()
        if fault is not None and self.absorb is not None and self.absorb(fault):
            fault = backend.fault()  # what is left once the failed legs' servos are set aside
        if fault is not None:  # the reading is not trusted: no row, no further target
            self._fault(fault)
            self._over = True
            return None
        self._sensors = backend.sensors(True)
        self.recorder.record(cycle, command, out, applied, reading)
        stop = None
        for observer in self.observers:
            stop = observer(cycle, command, out, reading)
            if stop is not None:
                break
        self._cycle = cycle = cycle + 1
        if stop is not None:
            self.stop_reason = stop
            self._over = True
        elif cycle % self.flush_every == 0:
            self.recorder.flush()
        return Cycle(command, out, applied, reading)

    def finish(self) -> LoopResult:
        """After the last cycle: the recorder flushed, the end logged; how the run ended."""
        cycle = self._cycle
        self.recorder.flush()
        self.cycle = None
        event(log, logging.INFO, "stopped", "ended after %d cycles (%s)", cycle, self.stop_reason or "end",
              cycle=cycle)
        return self._result(cycle)

    @staticmethod
    def _state_events(cycle: int, out: CycleOutput, robot_state: RobotState | None,
                      walk_state: WalkState | None) -> tuple[RobotState, WalkState]:
        """Log the robot and walk state changes of this cycle; the states now."""
        for name, before, now in (("robot_state", robot_state, out.robot_state),
                                  ("walk_state", walk_state, out.walk_state)):
            if now is not before:
                text = now.name if before is None else f"{before.name} → {now.name}"
                event(log, logging.INFO, name, "%s: %s", name.replace("_", " "), text, cycle=cycle)
        return out.robot_state, out.walk_state

    def _result(self, cycles: int) -> LoopResult:
        return LoopResult(cycles, self.stop_reason or "end", self.fault_text, self.requested)
