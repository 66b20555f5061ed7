"""Where ``run-hw`` takes its commands from: a timeline, JSON lines on stdin, the keyboard or a gamepad.

Each source answers :meth:`next` once per cycle after the start-up with the cycle's :class:`Command`, or ``None``
when it is finished (the timeline is over, stdin is closed or sent ``stop``, the gamepad is gone, ``x`` was pressed)
— the robot then stops walking and shuts down. The live sources hold their inputs between events: a velocity, a
pose velocity and a requested robot state (``running`` at first) hold until changed; a gait change is made once.

* **stdin** — one JSON object per line, every key optional: ``{"velocity": [vx, vy, wz]}`` (the robot's input mode),
  ``{"pose_velocity": [x, y, z, roll, pitch, yaw]}``, ``{"state": "packed" | "ready" | "running"}``,
  ``{"gait": "wave"}`` (a bundled name or a gait file), ``{"stop": true}``. A **watchdog** sets the velocities to
  zero when no line has come for ``watchdog_s`` seconds (a lost link must not leave the robot walking); a malformed
  line is ignored with a warning (logged: on stderr and in the run's ``events.log``).
* **keyboard** — the terminal in cbreak mode (Ctrl-C still stops): ``w``/``s`` forward/back, ``a``/``d`` left/right,
  ``q``/``e`` turn left/right, each press ±0.1 of full input (terminals send no key releases, so the input holds);
  ``r``/``f`` body up/down (pose velocity ±0.5 per press); space zeroes both; ``1`` packed, ``2`` ready,
  ``3`` running; ``g`` next gait; ``x`` stop and shut down.
* **gamepad** — a Linux evdev joystick (``evdev``): left stick walk (up forward, sideways strafe), right stick x
  turn, right stick y body pitch; A/south next gait, B/east zero velocity, Y/north ready, Start running,
  Select/Back packed, Mode/Home stop and shut down. Stick values are scaled by the device's own ranges with a 10 %
  dead zone. A disconnected gamepad stops the robot.
"""

from __future__ import annotations

import bisect
import contextlib
import json
import logging
import os
import sys
import threading
import time
from collections.abc import Callable, Sequence
from typing import IO, Any, overload

from shc_cli.control.controller import Command, RobotState
from shc_cli.control.pose import PoseReset
from shc_cli.errors import ShcError, install_hint
from shc_cli.events import NOTICE
from shc_cli.events import event as log_event
from shc_cli.spec.gait import Gait
from shc_cli.spec.timeline import EVENTS, Timeline

log = logging.getLogger(__name__)

STATES = {"packed": RobotState.PACKED, "ready": RobotState.READY, "running": RobotState.RUNNING}
KEY_STEP = 0.1
"""Velocity input change per key press [fraction of full input]."""
DEAD_ZONE = 0.1
"""Stick deflection below which a gamepad axis reads 0 [fraction of its range]."""


class InputError(ShcError):
    """An input device is missing or unusable (one line, exit 2)."""


def timeline_commands(timeline: Timeline, cycles: int) -> TimelineCommands:
    """The command of every cycle ``0 … cycles − 1`` of ``timeline``, made when asked for (memory independent of
    ``cycles``)."""
    return TimelineCommands(timeline.changes, cycles)


def _enums(change: dict[str, object]) -> dict[str, object]:
    """A timeline change with its enum names (``pose_reset``, ``state_request``) turned into the controller's
    :class:`PoseReset` and :class:`RobotState`."""
    out = dict(change)
    if isinstance(reset := out.get("pose_reset"), str):
        out["pose_reset"] = PoseReset[reset.upper()]
    if isinstance(state := out.get("state_request"), str):
        out["state_request"] = RobotState[state.upper()]
    return out


class TimelineCommands(Sequence[Command]):
    """The commands of a timeline's cycles ``0 … cycles − 1`` as a sequence built on demand.

    A run of hours (or ``--duration 1e9``) holds one entry per change, not one command per cycle: the command of
    a cycle is made when it is read. Every read makes a new :class:`Command` (callers may change theirs).

    Args:
        changes: the timeline's ``(cycle, change)`` pairs; a change holds from its cycle on (one-off requests,
            :data:`~shc_cli.spec.timeline.EVENTS`, only at it).
        cycles: how many cycles.
    """

    def __init__(self, changes: list[tuple[int, dict[str, object]]], cycles: int) -> None:
        self.cycles = cycles
        self.starts: list[int] = []
        """First cycle of each segment (ascending): where a change (or several on one cycle) takes effect."""
        self.held: list[dict[str, object]] = []
        """Inputs holding over each segment."""
        self.events: list[dict[str, object]] = []
        """One-off requests made at each segment's first cycle."""
        current: dict[str, object] = {}
        for cycle, change in sorted(changes, key=lambda c: c[0]):
            start = max(cycle, 0)
            if start >= cycles:
                break
            if not self.starts or self.starts[-1] != start:
                self.starts.append(start)
                self.events.append({})
                self.held.append({})
            change = _enums(change)
            current = {**current, **{k: v for k, v in change.items() if k not in EVENTS}}
            self.held[-1] = current
            self.events[-1].update({k: v for k, v in change.items() if k in EVENTS})

    def __len__(self) -> int:
        return self.cycles

    @overload
    def __getitem__(self, index: int) -> Command: ...

    @overload
    def __getitem__(self, index: slice) -> list[Command]: ...

    def __getitem__(self, index: int | slice) -> Command | list[Command]:
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(self.cycles))]
        if index < 0:
            index += self.cycles
        if not 0 <= index < self.cycles:
            raise IndexError("timeline cycle out of range")
        segment = bisect.bisect_right(self.starts, index) - 1
        if segment < 0:
            return Command()
        if index == self.starts[segment]:
            return Command(**self.held[segment], **self.events[segment])  # type: ignore[arg-type]
        return Command(**self.held[segment])  # type: ignore[arg-type]


class TimelineInput:
    """The commands of a timeline, one per cycle."""

    def __init__(self, commands: Sequence[Command]) -> None:
        self.commands = commands
        self.index = 0

    def next(self) -> Command | None:
        if self.index >= len(self.commands):
            return None
        command = self.commands[self.index]
        self.index += 1
        return command

    def close(self) -> None:
        """Nothing to release."""


class HeldInput:
    """Inputs that hold between events, shared by the live sources (thread-safe).

    Args:
        gaits: the gaits ``next_gait`` cycles through (the robot's bundled gaits).
        watchdog_s: seconds without an event after which the velocities become zero (``None``: no watchdog).
        clock: the monotonic clock the watchdog reads [s] (a test gives its own).
    """

    def __init__(self, gaits: list[Gait] | None = None, watchdog_s: float | None = None,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self.gaits = gaits or []
        self.watchdog_s = watchdog_s
        self.velocity = [0.0, 0.0, 0.0]
        self.pose_velocity = [0.0] * 6
        self.state = RobotState.RUNNING
        self.gait: Gait | None = None
        self.gait_index = 0
        self.finished = False
        self.watchdog_trips = 0
        self.last = clock()
        self._lock = threading.Lock()

    def update(self, change: Callable[[HeldInput], None]) -> None:
        """Apply ``change`` under the lock and feed the watchdog."""
        with self._lock:
            change(self)
            self.last = self.clock()

    def zero(self) -> None:
        """Velocity and pose velocity inputs to zero."""
        self.velocity, self.pose_velocity = [0.0, 0.0, 0.0], [0.0] * 6

    def next_gait(self) -> None:
        if self.gaits:
            self.gait_index = (self.gait_index + 1) % len(self.gaits)
            self.gait = self.gaits[self.gait_index]

    def next(self) -> Command | None:
        with self._lock:
            if self.finished:
                return None
            idle = self.watchdog_s is not None and self.clock() - self.last > self.watchdog_s
            if idle and (any(self.velocity) or any(self.pose_velocity)):
                self.zero()
                self.watchdog_trips += 1
                log_event(log, logging.WARNING, "watchdog", "warning: no input for %g s: velocities set to zero",
                      self.watchdog_s)
            gait, self.gait = self.gait, None
            return Command(velocity=tuple(self.velocity), pose_velocity=tuple(self.pose_velocity),  # type: ignore[arg-type]
                           state_request=self.state, gait=gait)

    def close(self) -> None:
        """Release the device (subclasses)."""


class StdinInput(HeldInput):
    """JSON lines from a stream (stdin), read by a thread, with a watchdog.

    Args:
        stream: the text stream.
        watchdog_s: seconds without a line after which the velocity inputs become zero.
        load_gait: gait name or file → Gait (raises :class:`ShcError` for an unknown one).
    """

    def __init__(self, stream: IO[str] | None = None, watchdog_s: float = 0.5,
                 load_gait: Callable[[str], Gait] | None = None, clock: Callable[[], float] = time.monotonic) -> None:
        super().__init__(watchdog_s=watchdog_s, clock=clock)
        self.stream = stream or sys.stdin
        self.load_gait = load_gait
        self._thread = threading.Thread(target=self._read, name="run-hw-stdin", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        try:
            for line in self.stream:
                text = line.strip()
                if not text:
                    continue
                try:
                    self.update(self._parse(text))
                except (ValueError, TypeError, KeyError, ShcError) as error:
                    log_event(log, logging.WARNING, "input", "warning: stdin: ignored line %r (%s)", text[:60], error)
                if self.finished:
                    return
        except (OSError, ValueError) as error:  # an unreadable or closed stream ends the input like EOF
            log_event(log, logging.WARNING, "input", "warning: stdin: %s: stopping", error)
        self.finished = True  # end of input

    def _parse(self, text: str) -> Callable[[HeldInput], None]:
        """The change one line asks for (validated before anything is applied)."""
        data = json.loads(text)
        if not isinstance(data, dict):
            raise ValueError("not an object")
        unknown = set(data) - {"velocity", "pose_velocity", "state", "gait", "stop"}
        if unknown:
            raise ValueError(f"unknown key {sorted(unknown)[0]!r}")
        velocity = [float(v) for v in data["velocity"]] if "velocity" in data else None
        if velocity is not None and len(velocity) != 3:
            raise ValueError("velocity needs 3 numbers")
        pose = [float(v) for v in data["pose_velocity"]] if "pose_velocity" in data else None
        if pose is not None and len(pose) != 6:
            raise ValueError("pose_velocity needs 6 numbers")
        if "state" in data and data["state"] not in STATES:
            raise ValueError(f"state is one of {', '.join(STATES)}")
        gait = None
        if "gait" in data:
            if self.load_gait is None:
                raise ValueError("gait changes are not available")
            gait = self.load_gait(str(data["gait"]))

        def change(held: HeldInput) -> None:
            if velocity is not None:
                held.velocity = velocity
            if pose is not None:
                held.pose_velocity = pose
            if "state" in data:
                held.state = STATES[data["state"]]
            if gait is not None:
                held.gait = gait
            if data.get("stop"):
                held.finished = True

        return change


KEYS: dict[str, Callable[[HeldInput], None]] = {
    "w": lambda h: _nudge(h.velocity, 0, KEY_STEP), "s": lambda h: _nudge(h.velocity, 0, -KEY_STEP),
    "a": lambda h: _nudge(h.velocity, 1, KEY_STEP), "d": lambda h: _nudge(h.velocity, 1, -KEY_STEP),
    "q": lambda h: _nudge(h.velocity, 2, KEY_STEP), "e": lambda h: _nudge(h.velocity, 2, -KEY_STEP),
    "r": lambda h: _nudge(h.pose_velocity, 2, 5 * KEY_STEP), "f": lambda h: _nudge(h.pose_velocity, 2, -5 * KEY_STEP),
    " ": lambda h: h.zero(),
    "1": lambda h: setattr(h, "state", RobotState.PACKED), "2": lambda h: setattr(h, "state", RobotState.READY),
    "3": lambda h: setattr(h, "state", RobotState.RUNNING), "g": lambda h: h.next_gait(),
    "x": lambda h: setattr(h, "finished", True),
}
"""Key → change of the held inputs."""
KEY_HELP = ("keys: w/s forward/back, a/d left/right, q/e turn, r/f body up/down, space zero, 1 packed, 2 ready, "
            "3 running, g gait, x stop")


def _nudge(values: list[float], index: int, step: float) -> None:
    values[index] = round(max(-1.0, min(1.0, values[index] + step)), 6)


class KeyboardInput(HeldInput):
    """Keys from a terminal (default: stdin), read by a thread; the terminal is in cbreak mode until :meth:`close`.

    Args:
        gaits: the gaits ``g`` cycles through.
        fd: the terminal's file descriptor.
    """

    def __init__(self, gaits: list[Gait] | None = None, fd: int | None = None) -> None:
        import termios
        import tty

        super().__init__(gaits)
        self.fd = sys.stdin.fileno() if fd is None else fd
        if not os.isatty(self.fd):
            raise InputError("--input keyboard: standard input is not a terminal (use stdin for piped JSON lines)")
        self._saved = termios.tcgetattr(self.fd)
        tty.setcbreak(self.fd)  # keys arrive one by one, unechoed; Ctrl-C still sends SIGINT
        log_event(log, NOTICE, "input", "%s", KEY_HELP)
        self._thread = threading.Thread(target=self._read, name="run-hw-keyboard", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        while not self.finished:
            try:
                data = os.read(self.fd, 1)
            except OSError:
                data = b""
            if not data:
                self.finished = True
                return
            change = KEYS.get(data.decode("ascii", "replace").lower())
            if change is not None:
                self.update(change)

    def close(self) -> None:
        import termios

        with contextlib.suppress(OSError, termios.error):
            termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)


class GamepadInput(HeldInput):
    """A gamepad through Linux evdev, read by a thread.

    Args:
        device: an evdev device path (``/dev/input/eventN``); default the first device with sticks and a south
            button.
        gaits: the gaits the south button cycles through.
    """

    def __init__(self, device: str | None = None, gaits: list[Gait] | None = None) -> None:
        super().__init__(gaits)
        try:
            import evdev
        except ImportError:  # evdev is Linux only
            raise InputError(f"--input gamepad needs the evdev package (Linux only): {install_hint()}") from None
        self.device = _open_gamepad(evdev, device)
        self.mapping = GamepadMapping(self.device.capabilities(absinfo=True))
        log_event(log, NOTICE, "input", "gamepad: %s (%s)", self.device.name, self.device.path)
        self._thread = threading.Thread(target=self._read, name="run-hw-gamepad", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        try:
            for event in self.device.read_loop():
                change = self.mapping.change(event.type, event.code, event.value)
                if change is not None:
                    self.update(change)
                if self.finished:
                    return
        except OSError:
            log_event(log, logging.WARNING, "input", "warning: the gamepad is gone: stopping")
        self.finished = True

    def close(self) -> None:
        with contextlib.suppress(OSError):
            self.device.close()


def _open_gamepad(evdev: Any, path: str | None) -> Any:
    if path is not None:
        try:
            return evdev.InputDevice(path)
        except OSError as error:
            raise InputError(f"{path}: cannot open the gamepad: {error.strerror} (check the device and that you may "
                             "read it: the 'input' group)") from None
    for candidate in evdev.list_devices():
        with contextlib.suppress(OSError):
            device = evdev.InputDevice(candidate)
            capabilities = device.capabilities()
            axes = {code if isinstance(code, int) else code[0] for code in capabilities.get(evdev.ecodes.EV_ABS, [])}
            keys = set(capabilities.get(evdev.ecodes.EV_KEY, []))
            if {evdev.ecodes.ABS_X, evdev.ecodes.ABS_Y} <= axes and evdev.ecodes.BTN_SOUTH in keys:
                return device
            device.close()
    raise InputError("no gamepad found in /dev/input (plug one in, check you may read it, or name it with "
                     "--input gamepad:/dev/input/eventN)")


class GamepadMapping:
    """evdev events → changes of the held inputs (pure: testable without a device).

    Args:
        capabilities: ``device.capabilities(absinfo=True)``: each axis with its minimum and maximum.
    """

    EV_KEY, EV_ABS = 0x01, 0x03
    ABS_X, ABS_Y, ABS_RX, ABS_RY = 0x00, 0x01, 0x03, 0x04
    BTN_SOUTH, BTN_EAST, BTN_NORTH, BTN_WEST = 0x130, 0x131, 0x133, 0x134
    BTN_SELECT, BTN_START, BTN_MODE = 0x13A, 0x13B, 0x13C

    def __init__(self, capabilities: dict[int, list[Any]]) -> None:
        self.ranges: dict[int, tuple[float, float]] = {}
        for entry in capabilities.get(self.EV_ABS, []):
            if isinstance(entry, tuple) and len(entry) == 2:
                code, info = entry
                self.ranges[code] = (float(info.min), float(info.max))

    def axis(self, code: int, value: int) -> float:
        """An axis value as −1..1 (its range's centre 0), with the dead zone."""
        low, high = self.ranges.get(code, (-32768.0, 32767.0))
        scaled = (2.0 * (value - low) / (high - low) - 1.0) if high > low else 0.0
        scaled = max(-1.0, min(1.0, scaled))
        return 0.0 if abs(scaled) < DEAD_ZONE else round(scaled, 4)

    def change(self, kind: int, code: int, value: int) -> Callable[[HeldInput], None] | None:
        """The change an event makes, or None for an event that changes nothing."""
        if kind == self.EV_ABS and code in (self.ABS_X, self.ABS_Y, self.ABS_RX, self.ABS_RY):
            scaled = self.axis(code, value)
            slot = {self.ABS_Y: ("velocity", 0), self.ABS_X: ("velocity", 1), self.ABS_RX: ("velocity", 2),
                    self.ABS_RY: ("pose_velocity", 4)}[code]

            def move(held: HeldInput) -> None:
                getattr(held, slot[0])[slot[1]] = -scaled + 0.0  # stick up/right is negative y/x: forward/left

            return move
        if kind == self.EV_KEY and value == 1:  # presses only
            return {self.BTN_SOUTH: lambda h: h.next_gait(),
                    self.BTN_EAST: lambda h: setattr(h, "velocity", [0.0, 0.0, 0.0]),
                    self.BTN_NORTH: lambda h: setattr(h, "state", RobotState.READY),
                    self.BTN_START: lambda h: setattr(h, "state", RobotState.RUNNING),
                    self.BTN_SELECT: lambda h: setattr(h, "state", RobotState.PACKED),
                    self.BTN_MODE: lambda h: setattr(h, "finished", True)}.get(code)
        return None
