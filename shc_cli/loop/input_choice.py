"""The ``--input`` option of ``run-hw`` and ``simulate``: which source drives the run once the start-up is done.

``timeline`` (``--velocity``/``--commands``), ``commands:FILE`` (the same as ``--commands FILE``), or a live
source held between events (:mod:`shc_cli.loop.input_sources`): ``stdin`` (JSON lines, with a watchdog),
``keyboard`` (the terminal) and ``gamepad[:DEVICE]`` (Linux evdev). The keyboard and the gamepad cycle through the
bundled gaits that fit the robot's legs; stdin names a gait (bundled or a file) and it is checked against them.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from shc_cli.backends.base import InputSource
from shc_cli.control.controller import Command
from shc_cli.errors import Issue, SpecError
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot

INPUTS = "timeline, commands:FILE, stdin, keyboard, gamepad or gamepad:DEVICE"
_TAKES_ARGUMENT = {"timeline": False, "commands": True, "stdin": False, "keyboard": False, "gamepad": None}
"""Input kind → whether it takes ``:ARGUMENT`` (None: optional)."""
LIVE = ("stdin", "keyboard", "gamepad")
"""The kinds a person drives while the run happens."""


def check_input(value: str) -> str:
    """``value`` if it names an input, else a one-line error (``--input``)."""
    kind, _, argument = value.partition(":")
    if kind not in _TAKES_ARGUMENT or _TAKES_ARGUMENT[kind] not in (None, bool(argument)):
        raise SpecError([Issue(None, None, "--input", f"'{value}' is not an input", f"use {INPUTS}")])
    return value


def is_live(value: str) -> bool:
    """The input is driven by a person while the run happens (stdin, keyboard, gamepad)."""
    return value.partition(":")[0] in LIVE


def commands_file(value: str, commands: Path | None) -> Path | None:
    """The command timeline file: ``commands:FILE``'s, else ``--commands``."""
    kind, _, argument = value.partition(":")
    return Path(argument) if kind == "commands" else commands


def open_input(value: str, robot: Robot, gait: Gait, commands: Sequence[Command], watchdog: float) -> InputSource:
    """The source ``value`` names (opened: a keyboard puts the terminal in cbreak mode until ``close``).

    Args:
        value: the ``--input`` value (checked by :func:`check_input`).
        robot: the robot (the gaits offered must fit its legs).
        gait: the gait it starts with (the keyboard's and gamepad's next gait is the one after it).
        commands: the timeline's commands (``timeline`` and ``commands:FILE``).
        watchdog: stdin: seconds without a line before the velocities go to zero [s].

    Raises:
        InputError: the device is missing or unusable (one line).
    """
    from shc_cli.loop.input_sources import GamepadInput, KeyboardInput, StdinInput, TimelineInput
    from shc_cli.spec.loading import bundled, load_gait

    kind, _, argument = value.partition(":")

    def gait_of(name: str) -> Gait:
        found = load_gait(name).gait
        if set(found.offset_multiplier) != set(robot.legs):
            legs = ", ".join(found.offset_multiplier)
            raise SpecError([Issue(None, None, "gait", f"gait '{name}' is for legs {legs}",
                                   f"use a gait for {', '.join(robot.legs)}")])
        return found

    if kind == "stdin":
        return StdinInput(watchdog_s=watchdog, load_gait=gait_of)
    if kind in ("keyboard", "gamepad"):
        gaits = [g for g in (load_gait(name).gait for name in bundled("gaits"))
                 if set(g.offset_multiplier) == set(robot.legs)]
        source: KeyboardInput | GamepadInput = KeyboardInput(gaits) if kind == "keyboard" else GamepadInput(
            argument or None, gaits)
        names = [g.name for g in gaits]
        source.gait_index = names.index(gait.name) if gait.name in names else 0  # the next gait is the one after
        return source
    return TimelineInput(commands)
