"""``shc hw jog``: move one joint at a time by a small angle, torque limited, and back; the user confirms the
direction and the zero, and the answers are written back to the robot file's ``[hardware.servos]``.

Each joint: its servo's present position is read; the torque is limited (``torque`` of the maximum) and enabled
with the goal at the present position; the goal moves ``angle`` towards the inside of the joint's limits, waits
until the servo gets there (or ``SETTLE_S``), goes back, and the torque goes off and its limit is restored. Then
two questions: did the joint turn the way the robot file calls positive (no: ``direction`` flips), and where is
its zero (here: the user has put the joint at angle 0 by hand, torque off, and its present position becomes
``zero_ticks``; keep: unchanged). Nothing is written until every joint is answered; a servo that fails is a
:class:`~shc_cli.hardware.servo_io.ServoFault` (every torque off, nothing written).
"""

from __future__ import annotations

import contextlib
import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.errors import ShcError
from shc_cli.events import NOTICE, event

if TYPE_CHECKING:
    from shc_cli.hardware.bus import ServoBus
    from shc_cli.hardware.servo_io import OneServo
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

SETTLE_S = 2.0
"""Longest wait for a jog to arrive [s]."""
MOVED_SHARE = 0.3
"""A jog that moves the servo less than this share of the angle is a fault (blocked, or the torque too low)."""


@dataclass(frozen=True)
class Question:
    """One question to the user: ``choices`` are the answers' first letters."""

    joint: str
    text: str
    choices: tuple[str, ...]


@dataclass
class JogReport:
    robot: str
    path: Path
    moves: dict[str, tuple[int, int, int]] = field(default_factory=dict)
    """Joint → (start, target, reached) [ticks]."""
    changes: dict[str, dict[str, int]] = field(default_factory=dict)
    """Joint → the servo-map fields written."""
    refused: dict[str, str] = field(default_factory=dict)
    """Joint → why the zero it was given was not written (its limits would leave the servo's range)."""


WORDS = [("forward", "backward"), ("left", "right"), ("up", "down")]
"""Directions along the body's x, y and z axes."""


def _words(delta: np.ndarray) -> tuple[str, str]:
    """The main direction of a tip displacement in the body frame, and its opposite, in words."""
    axis = int(np.argmax(np.abs(delta)))
    forward, back = WORDS[axis]
    return (forward, back) if delta[axis] > 0 else (back, forward)


def positive_hints(robot: Robot) -> dict[str, tuple[str, str]]:
    """For each joint, which way a positive turn moves its foot at the standing pose, and a negative one."""
    from shc_cli.domain.bringup.check import standing_joints
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    standing = standing_joints(robot)
    keys = [[f"{leg}_{joint}" for joint in spec.joints] for leg, spec in robot.legs.items()]
    q = np.zeros(chains.default_joints().shape)
    for i, row in enumerate(keys):
        for k, key in enumerate(row):
            q[i, k] = standing[key]
    base = chains.tips(q)
    hints = {}
    for i, row in enumerate(keys):
        for k, key in enumerate(row):
            moved = q.copy()
            moved[i, k] += 0.05
            hints[key] = _words(chains.tips(moved)[i] - base[i])
    return hints


def _settle(servo: OneServo, target: int, tolerance: int) -> int:
    deadline = time.monotonic() + SETTLE_S
    ticks = servo.ticks()
    while abs(ticks - target) > tolerance and time.monotonic() < deadline:
        time.sleep(0.02)
        ticks = servo.ticks()
    return ticks


def _jog_one(bus: ServoBus, index: int, angle: float, torque: float) -> tuple[int, int, int] | None:
    """Move slot ``index`` by ``angle`` [rad] into its limits and back; (start, target, reached) [ticks], or None
    when the joint cannot move ``angle`` either way inside its limits."""
    from shc_cli.hardware.servo_io import OneServo, ServoFault

    servo = OneServo(bus, index)
    slot = servo.slot
    start = servo.ticks()
    per_rad = bus.ticks_per_radian(index)
    q0 = bus.ticks_to_angle(index, start)
    low, high = slot.limits
    q1 = q0 + angle if q0 + angle <= high else q0 - angle
    if not low <= q1 <= high:
        return None
    target = bus.angle_to_ticks(index, q1)
    saved = servo.limit_torque(torque)
    servo.goal(start)
    servo.torque(True)
    try:
        servo.goal(target)
        tolerance = max(2, round(0.01 * per_rad))
        reached = _settle(servo, target, tolerance)
        servo.goal(start)
        _settle(servo, start, tolerance)
    finally:
        with contextlib.suppress(ShcError):
            servo.torque(False)
    servo.restore(saved)
    if abs(reached - start) < MOVED_SHARE * abs(target - start):
        raise ServoFault(f"{servo.name}: moved {reached - start:+d} ticks of {target - start:+d} (blocked, or the "
                         f"torque limit too low: raise --torque)")
    return start, target, reached


def jog(robot: Robot, path: Path, ports: list[str], ask: Callable[[Question], str], joints: list[str] | None = None,
        angle: float = 0.1, torque: float = 0.3, baud: int | None = None) -> JogReport:
    """Jog ``joints`` (default all, in the robot file's order) and write the answers to ``path``.

    Args:
        robot: the robot loaded from ``path``.
        path: its file (written back: direction and zero_ticks).
        ports: the buses' serial devices.
        ask: asks a :class:`Question`, returns one of its choices.
        joints: joint keys (``AR_coxa``) to jog.
        angle: jog size [rad].
        torque: torque limit as a share of the servos' maximum (0–1].
        baud: baud rate (None: ``hardware.baud``).
    """
    from shc_cli.domain.bringup.check import open_checked
    from shc_cli.domain.bringup.servo_file import write_servos
    from shc_cli.validation import servo_range_problem

    report = JogReport(robot.name, path)
    hints = positive_hints(robot)
    bus = open_checked(robot, ports, baud)
    try:
        keys = [slot.key for slot in bus.slots]
        for key in joints or keys:
            index = keys.index(key)
            slot = bus.slots[index]
            move = _jog_one(bus, index, angle, torque)
            if move is None:
                event(log, logging.WARNING, "hw_jog", "warning: %s: cannot move %.2f rad either way inside its limits "
                      "from where it is; skipped", key, angle)
                continue
            report.moves[key] = move
            start, target, reached = move
            sign = "+" if (target - start) * slot.direction > 0 else "-"
            event(log, NOTICE, "hw_jog", "%s (servo %d): ticks %d → %d → %d (%s%.2f rad) and back", key,
                  slot.servo_id, start, reached, start, sign, angle)
            expected = hints[key][0 if sign == "+" else 1]
            answer = ask(Question(key, f"{key} turned {sign}{angle:.2f} rad and back: by the robot file its foot "
                                       f"moved {expected} (at the standing pose; on a stand, the way it would). Did "
                                       "it? [y]es / [n]o, the other way / [s]kip", ("y", "n", "s")))
            if answer == "s":
                continue
            direction = -slot.direction if answer == "n" else slot.direction
            fields: dict[str, int] = {"direction": direction} if direction != slot.direction else {}
            answer = ask(Question(key, f"Zero of {key}: the torque is off. Put the joint at angle 0 by hand and "
                                       f"answer [h]ere, or [k]eep zero_ticks {slot.zero}", ("h", "k")))
            if answer == "h":
                from shc_cli.hardware.servo_io import OneServo

                here = OneServo(bus, index).ticks()
                zero = round(here - direction * slot.offset * bus.ticks_per_radian(index))
                problem = servo_range_problem(robot, key, direction, zero)
                if problem is None:
                    fields["zero_ticks"] = zero
                else:  # the next hw check/jog/run-hw would refuse the file: keep the zero it had
                    report.refused[key] = problem
                    event(log, logging.WARNING, "hw_jog", "warning: %s: zero_ticks %d not written: %s; kept "
                          "zero_ticks %d (turn the servo horn so that the joint's angle 0 is nearer the servo's "
                          "middle, or narrow the joint limits, then jog again)", key, zero, problem, slot.zero)
            if fields:
                report.changes[key] = fields
    except BaseException:
        with contextlib.suppress(Exception):
            bus.torque(False)
        raise
    finally:
        bus.close()
    write_servos(path, report.changes)
    return report


def check_jog_options(robot: Robot, joints: list[str] | None, angle: float, torque: float) -> None:
    """Refuse unknown joints and sizes outside (0, 0.5] rad and (0, 1] (one line, exit 2)."""
    from shc_cli.errors import Issue, SpecError

    keys = [f"{leg}_{joint}" for leg, spec in robot.legs.items() for joint in spec.joints]
    for joint in joints or []:
        if joint not in keys:
            raise SpecError([Issue(None, None, "--joint", f"{joint!r} is not a joint of {robot.name}",
                                   f"one of {', '.join(keys[:6])}, …")])
    if not 0 < angle <= 0.5:
        raise SpecError([Issue(None, None, "--angle", f"{angle:g} rad", "give 0 < angle ≤ 0.5 rad (about 29°)")])
    if not 0 < torque <= 1:
        raise SpecError([Issue(None, None, "--torque", f"{torque:g}", "give a share of the maximum torque, 0–1")])
    if math.isnan(angle) or math.isnan(torque):
        raise SpecError([Issue(None, None, "--angle/--torque", "not a number", "give numbers")])
