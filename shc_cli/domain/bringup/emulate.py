"""``shc hw emulate``: the robot's servo map served by emulated buses on pseudo-terminals (one per bus), so the
bring-up commands and ``run-hw`` can be tried without hardware. The servos are the emulators of
:mod:`shc_cli.hardware.emulator` (Protocol 2.0) and :mod:`shc_cli.hardware.emulator_protocol1` (Protocol 1.0,
Feetech), at the robot's baud rate, standing at their servo map's zero; they answer until the process ends.
"""

from __future__ import annotations

import os
import signal
import threading
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.spec.robot import Robot


def emulate(robot: Robot, on_ready: Callable[[list[str]], None], links: list[Path] | None = None,
            baud: int | None = None, duration: float | None = None, dynamics: bool = False) -> None:
    """Serve the robot's buses until SIGINT/SIGTERM (or ``duration`` [s]); ``on_ready`` gets the ports (bus 0
    first) once they answer. ``links``: symbolic links made to the ports (removed at the end). ``dynamics``: the
    servos move as the robot's ``[servo]`` model."""
    from shc_cli.errors import ShcError
    from shc_cli.hardware.emulator_process import robot_emulators

    emulators = robot_emulators(robot, baud, dynamics)
    links = links or []
    if len(links) > len(emulators):
        raise ShcError(f"--link given {len(links)} times, but {robot.name} has {len(emulators)} bus"
                       f"{'es' if len(emulators) > 1 else ''}")
    stop = threading.Event()
    previous = {sig: signal.signal(sig, lambda *_: stop.set()) for sig in (signal.SIGINT, signal.SIGTERM)}
    made: list[Path] = []
    try:
        for emulator in emulators:
            emulator.start()
        for link, emulator in zip(links, emulators, strict=False):
            if link.is_symlink():
                link.unlink()
            elif link.exists():
                raise ShcError(f"{link}: exists and is not a link (give --link a new path)")
            link.symlink_to(emulator.port)
            made.append(link)
        on_ready([str(link) for link in made] + [e.port for e in emulators[len(made):]])
        stop.wait(duration)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        for emulator in emulators:
            emulator.stop()
        for link in made:
            if link.is_symlink() and os.readlink(link):
                link.unlink()
