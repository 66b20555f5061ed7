"""Packing and unpacking: the robot's joint configurations, which one it is in, and the joint-space transitions
between them (OpenSHC's pack/unpack, state_controller.h); the tip-space start-up and shut-down sequences are in
:mod:`shc_cli.control.sequence`.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from shc_cli.control.bezier import cubic
from shc_cli.control.startup import iterations
from shc_cli.errors import KinematicsError
from shc_cli.model.chains import FloatArray
from shc_cli.spec.robot import Robot

PROGRESS_COMPLETE = 100
"""Progress value of a finished transition [%]."""
PACK_TIME = 2.0
"""Duration of one pack/unpack transition at ``step_frequency`` 1 Hz [s] (state_controller.h)."""
JOINT_TOLERANCE = 0.01
"""A joint this close to a configuration counts as in it [rad] (pose_controller.h)."""


class SequenceError(KinematicsError):
    """The start-up sequence cannot be found or run (OpenSHC shuts the controller down here)."""


# -- joint configurations ------------------------------------------------------------------------------------------


def joint_configurations(robot: Robot, width: int | None = None) -> tuple[FloatArray, FloatArray]:
    """The robot's packed and unpacked joint configurations as arrays over legs.

    Args:
        robot: the robot; every joint must list the same number of packed positions.
        width: joints per leg in the arrays (default: the largest joint count); missing joints are 0.

    Returns:
        ``(packed, unpacked)``: ``packed`` is ``(K, L, width)`` with ``packed[k]`` = OpenSHC's ``packed_k``
        configuration; ``unpacked`` is ``(L, width)`` [rad].
    """
    legs = list(robot.legs.values())
    width = width or max(len(leg.joints) for leg in legs)
    counts = {len(joint.packed) for leg in legs for joint in leg.joints.values()}
    if len(counts) > 1:
        raise SequenceError(f"robot '{robot.name}': every joint needs the same number of packed positions, "
                            f"found {sorted(counts)} (list packed_0, packed_1, … for every joint)")
    steps = counts.pop() if counts else 0
    packed = np.zeros((steps, len(legs), width))
    unpacked = np.zeros((len(legs), width))
    for i, leg in enumerate(legs):
        for k, joint in enumerate(leg.joints.values()):
            packed[:, i, k] = joint.packed
            unpacked[i, k] = joint.unpacked
    return packed, unpacked


# -- state estimation ----------------------------------------------------------------------------------------------


class Configuration(Enum):
    """What the joints matched when the robot state was estimated."""

    PACKED = "packed"
    READY = "ready"
    UNDEFINED = "undefined"


@dataclass(frozen=True)
class StateEstimate:
    """Outcome of OpenSHC's UNKNOWN → PACKED/READY estimate.

    Attributes:
        configuration: READY if every joint is within tolerance of ``unpacked``, else PACKED if of the last packed
            configuration, else UNDEFINED.
        ready: the robot state becomes READY (else PACKED).
        messages: OpenSHC's console messages, in order (a packed robot also gets the "undefined" warning).
    """

    configuration: Configuration
    ready: bool
    messages: tuple[str, ...]


def estimate_state(joints: FloatArray, packed_last: FloatArray, unpacked: FloatArray,
                   sequence_mode: bool) -> StateEstimate:
    """OpenSHC's estimate of the robot state from the joints (``transitionRobotState``, UNKNOWN branch).

    A leg is packed (ready) when each of its joints is strictly within :data:`JOINT_TOLERANCE` of the last packed
    (the unpacked) position; the robot is packed (ready) when every leg is. As in the source, the "undefined"
    ``else`` belongs to the READY test, so a packed robot ends PACKED through the undefined branch (with a fatal
    message first in direct mode), and in direct mode a ready robot also ends PACKED.

    Args:
        joints: measured joint positions ``(L, n)`` [rad] (OpenSHC reads ``current_position``).
        packed_last: last packed configuration ``(L, n)`` [rad].
        unpacked: unpacked configuration ``(L, n)`` [rad].
        sequence_mode: ``start_up_sequence``.
    """
    packed = bool((np.abs(joints - packed_last) < JOINT_TOLERANCE).all())
    ready = bool((np.abs(joints - unpacked) < JOINT_TOLERANCE).all())
    messages: list[str] = []
    if packed and not sequence_mode:
        messages.append("Syropod currently in packed state and cannot run direct startup sequence.")
    elif packed:
        messages.append("Syropod currently in PACKED state.")
    if ready and not sequence_mode:
        messages.append("Syropod currently in READY state but is set to execute DIRECT transition.")
    elif ready:
        messages.append("Syropod currently in READY state.")
    else:
        messages.append("Current Syropod state is undefined! Ensure Syropod legs are not bearing load.")
    configuration = Configuration.READY if ready else Configuration.PACKED if packed else Configuration.UNDEFINED
    return StateEstimate(configuration, ready and sequence_mode, tuple(messages))


# -- joint-space transitions (packLegs / unpackLegs) -----------------------------------------------------------------


class PackDirection(Enum):
    PACK = "pack"
    UNPACK = "unpack"


@dataclass(frozen=True)
class JointCycle:
    """One cycle of a joint-space transition.

    Attributes:
        joints: new desired joint positions ``(L, n)`` [rad] (not clamped: packed poses may lie outside limits).
        progress: OpenSHC's progress 1..100 of the current sub-transition; 0 on the cycle that finishes an
            intermediate one; 100 only when the whole pack/unpack is done.
    """

    joints: FloatArray
    progress: int


class PackTransition:
    """OpenSHC's ``packLegs`` / ``unpackLegs`` (all legs together, joint space).

    Pack goes ``packed_0, packed_1, …, packed_{K−1}``; unpack from there retraces ``packed_{K−2} … packed_0`` then
    ``unpacked``. Each leg is a cubic Bézier ``[o, o, t, t]`` over ``n = round(PACK_TIME/f_p/dt)`` cycles,
    τ = 1/n on the first cycle, exactly the target on the n-th; the next sub-transition starts on the following
    cycle from there.

    Quirk 10 (reproduced): ``pack_step`` starts at 0, so an unpack that was not preceded by a pack (a robot found
    packed at start-up) goes straight to ``unpacked``, skipping the intermediate packed configurations. Pass
    ``pack_step = K − 1`` to retrace them instead (a fix, not OpenSHC).

    Args:
        packed: packed configurations ``(K, L, n)`` [rad], K ≥ 1.
        unpacked: unpacked configuration ``(L, n)`` [rad].
        time_delta: control period [s].
        pack_step: initial pack step (OpenSHC: 0).
    """

    def __init__(self, packed: FloatArray, unpacked: FloatArray, time_delta: float, pack_step: int = 0) -> None:
        if len(packed) == 0:
            raise SequenceError("the robot has no packed configuration: give every joint packed = [...]")
        self.packed = np.asarray(packed, dtype=float)
        self.unpacked = np.asarray(unpacked, dtype=float)
        self.time_delta = time_delta
        self.pack_step = pack_step
        self._executing = False
        self._target = self.unpacked
        self._origin = self.unpacked
        self._count = 0
        self._first = True

    def step(self, direction: PackDirection, joints: FloatArray, step_frequency: float) -> JointCycle:
        """One cycle of packing or unpacking from the current desired joints ``joints`` ``(L, n)`` [rad]."""
        steps = len(self.packed)
        if not self._executing:
            if direction is PackDirection.PACK:
                self._target = self.packed[self.pack_step]
            else:
                self._target = self.packed[self.pack_step - 1] if self.pack_step > 0 else self.unpacked
        out, progress = self._transition(joints, PACK_TIME / step_frequency)
        self._executing = progress not in (0, PROGRESS_COMPLETE)
        if direction is PackDirection.PACK and progress == PROGRESS_COMPLETE and self.pack_step < steps - 1:
            self._executing = False
            self.pack_step += 1
            progress = 0
        elif direction is PackDirection.UNPACK and progress == PROGRESS_COMPLETE and self.pack_step != 0:
            self._executing = False
            self.pack_step -= 1
            progress = 0
        return JointCycle(out, progress)

    def _transition(self, joints: FloatArray, duration: float) -> tuple[FloatArray, int]:
        """``LegPoser::transitionConfiguration`` for all legs (they share n, so one progress)."""
        if self._first:
            self._origin = np.array(joints, dtype=float)
            self._first = False
            self._count = 0
        n = iterations(duration, self.time_delta)
        self._count += 1
        nodes = np.stack([self._origin, self._origin, self._target, self._target])
        out = cubic(nodes, self._count * (1.0 / n))
        progress = min(max(int(((self._count - 1) / n) * PROGRESS_COMPLETE), 1), PROGRESS_COMPLETE)
        if self._count >= n:
            self._first = True
            return out, PROGRESS_COMPLETE
        return out, progress
