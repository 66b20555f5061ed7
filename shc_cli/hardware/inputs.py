"""Where ``run-hw`` takes its commands from: a timeline (``--velocity``/``--commands``) or JSON lines on stdin.

Each source answers :meth:`next` once per RUNNING cycle with the cycle's :class:`Command`, or ``None`` when it
is finished (the timeline is over, stdin is closed or asked to stop) — the robot then stops walking.

JSON lines on stdin (one object per line; every key optional): ``{"velocity": [vx, vy, wz]}`` (the robot's input
mode), ``{"pose_velocity": [x, y, z, roll, pitch, yaw]}``, ``{"stop": true}``. The last velocity holds until the
next line; the **watchdog** sets it to zero when no line has come for ``watchdog_s`` seconds (a lost link must not
leave the robot walking), and a malformed line is ignored with a warning on stderr.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from typing import IO

from shc_cli.control.controller import Command, RobotState


class TimelineInput:
    """The commands of a timeline, one per cycle."""

    def __init__(self, commands: list[Command]) -> None:
        self.commands = commands
        self.index = 0

    def next(self) -> Command | None:
        if self.index >= len(self.commands):
            return None
        command = self.commands[self.index]
        self.index += 1
        return command


class StdinInput:
    """JSON lines from a stream (stdin), read by a thread, with a watchdog.

    Args:
        stream: the text stream.
        watchdog_s: seconds without a line after which the velocity input becomes zero.
    """

    def __init__(self, stream: IO[str] | None = None, watchdog_s: float = 0.5) -> None:
        self.stream = stream or sys.stdin
        self.watchdog_s = watchdog_s
        self.velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.pose_velocity: tuple[float, ...] = (0.0,) * 6
        self.last = time.monotonic()
        self.finished = False
        self.watchdog_trips = 0
        self._lock = threading.Lock()
        self._thread = threading.Thread(target=self._read, name="run-hw-stdin", daemon=True)
        self._thread.start()

    def _read(self) -> None:
        for line in self.stream:
            text = line.strip()
            if not text:
                continue
            try:
                data = json.loads(text)
                if not isinstance(data, dict):
                    raise ValueError("not an object")
                with self._lock:
                    if "velocity" in data:
                        vx, vy, wz = (float(v) for v in data["velocity"])
                        self.velocity = (vx, vy, wz)
                    if "pose_velocity" in data:
                        values = tuple(float(v) for v in data["pose_velocity"])
                        if len(values) != 6:
                            raise ValueError("pose_velocity needs 6 numbers")
                        self.pose_velocity = values
                    if data.get("stop"):
                        self.finished = True
                    self.last = time.monotonic()
            except (ValueError, TypeError) as error:
                print(f"warning: stdin: ignored line {text[:60]!r} ({error})", file=sys.stderr, flush=True)
            if self.finished:
                return
        self.finished = True  # end of input

    def next(self) -> Command | None:
        with self._lock:
            if self.finished:
                return None
            if time.monotonic() - self.last > self.watchdog_s and any(self.velocity):
                self.velocity = (0.0, 0.0, 0.0)
                self.pose_velocity = (0.0,) * 6
                self.watchdog_trips += 1
            return Command(velocity=self.velocity, pose_velocity=self.pose_velocity,  # type: ignore[arg-type]
                           state_request=RobotState.RUNNING)
