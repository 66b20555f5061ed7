"""Auto posing: OpenSHC's cyclic body pose and its per-leg negation (study §7.3; pose_controller.cpp v0.5.10).

:class:`AutoPoser` reproduces ``PoseController::updateAutoPose``, ``AutoPoser::updatePose`` and
``LegPoser::updateAutoPose``; :meth:`AutoPoser.reset` is ``setAutoPoseParams``. It is pure: the caller passes
what OpenSHC reads from the walk controller (walk state, the reference leg's stride, every leg's phase and
step state) and reads back the body auto pose, each leg's auto pose and the posing state.

Integration contract (OpenSHC order; see also /work/notes/openshc-walk-exact.md §1–§4):

* **When.** In the pose update at the top of every cycle whose robot state is not UNKNOWN
  (``updateCurrentPose``), only if auto posing is on and *not* (IMU posing on and RUNNING), and **before** the
  walk update. The inputs are therefore the previous cycle's: the walk state after the last ``updateWalk``,
  the legs' phases and step states after the last ``iteratePhase``, and ``zero_stride`` = the reference leg's
  stored stride (from its last ``updateStride``) has norm 0. Before the walker exists, pass STOPPED, a zero
  stride, phases 0 and FORCE_STOP states (the result is then identity and POSING_COMPLETE).
* **Body pose.** ``body = walk_plane ∘ manual ∘ inclination ∘ auto ∘ tip_align`` (``∘`` = :meth:`Pose.add`,
  each term only if enabled; ``auto`` is :attr:`AutoPoser.body_pose`).
* **Tip poses** (``updateStance``). For WALKING / MANUAL_TO_WALKING legs the tip is posed with
  ``body.remove(body_pose).add(leg_poses[leg])``, so a negated leg does not see the auto pose; MANUAL /
  WALKING_TO_MANUAL legs take the walker tip unchanged.
* **Stopping gate.** After the update, hand :attr:`AutoPoser.state` to the walk controller (``setPoseState``):
  STOPPING → STOPPED additionally needs ``state == POSING_COMPLETE``. With auto posing off (or skipped for IMU
  posing) the state stays what it was, initially POSING_COMPLETE.
* **Reset.** Call :meth:`AutoPoser.reset` where OpenSHC calls ``setAutoPoseParams``: after a gait change when
  ``auto_pose_type == "auto"`` (with the new gait, cycle and set). OpenSHC v0.5.10 does *not* call it after a
  ``step_frequency`` change, which leaves synchronised posing on the old normaliser (study §14 quirk 18);
  calling it then too is the fix.

Units: phases and lengths in control iterations (set windows in base units); poses in metres and radians;
``time_delta`` in seconds; ``pose_frequency`` in hertz.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from shc_cli.control.bezier import quartic, smooth_step
from shc_cli.control.gait import StepCycle, even_up
from shc_cli.control.pose import IDENTITY, Pose, rot_x, rot_y, rot_z
from shc_cli.control.stepping import FORCE_STANCE, FORCE_STOP, MOVING, STARTING, STOPPED, STOPPING
from shc_cli.spec.autopose import AutoPoseSet, Poser
from shc_cli.spec.gait import Gait


class PosingState(IntEnum):
    """OpenSHC ``PosingState``."""

    POSING = 0
    STOP_POSING = 1
    POSING_COMPLETE = 2


def euler_rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Extrinsic roll–pitch–yaw ``Rz(yaw)·Ry(pitch)·Rx(roll)`` [rad] (OpenSHC ``eulerAnglesToQuaternion``)."""
    if roll == 0.0 and pitch == 0.0 and yaw == 0.0:
        return IDENTITY
    return np.asarray(rot_z(yaw) @ rot_y(pitch) @ rot_x(roll))


@dataclass
class _PoserCycle:
    """One OpenSHC ``AutoPoser``: its window [base units], amplitudes and start/stop checks."""

    spec: Poser
    start_check: bool = False
    end_first: bool = False  # saw the window start while STOP_POSING
    end_second: bool = False  # then saw the window end
    posing: bool = False  # OpenSHC allow_posing_

    def update(self, phase: int, state: PosingState, synchronised: bool, normaliser: int, length: int,
               gravity: np.ndarray) -> Pose:
        """``AutoPoser::updatePose``: this poser's pose at master ``phase`` [iterations]."""
        start = self.spec.start * normaliser
        end = self.spec.end * normaliser
        if start > end:  # window wraps past the cycle end
            end += length
            if phase < start:
                phase += length
        self.start_check = not synchronised or (not self.start_check and state == PosingState.POSING
                                                and phase == start)
        self.end_first = self.end_first or (state == PosingState.STOP_POSING and phase == start)
        self.end_second = self.end_second or (state == PosingState.STOP_POSING and phase == end and self.end_first)
        if not self.posing and self.start_check:
            self.posing = True
            self.end_first = self.end_second = False
        elif self.posing and synchronised and self.end_first and self.end_second:
            self.posing = False
            self.start_check = False
        if not (start <= phase < end and self.posing):
            return Pose()
        iteration = phase - start + 1
        count = end - start
        first_half = iteration <= count // 2
        spec = self.spec
        translation = gravity * spec.gravity if spec.gravity != 0.0 else np.array([spec.x, spec.y, spec.z])
        amplitude = np.concatenate([translation, [spec.roll, spec.pitch, spec.yaw]])
        nodes = np.zeros((5, 6))
        nodes[(3, 4) if first_half else (0, 1), :] = amplitude  # rise 0 → A, then fall A → 0
        delta_t = 1.0 / (count / 2.0)
        offset = 0 if first_half else int(count / 2.0)
        values = quartic(nodes, (iteration - offset) * delta_t)
        return Pose(values[:3], euler_rotation(float(values[3]), float(values[4]), float(values[5])))


@dataclass
class _LegNegation:
    """One OpenSHC ``LegPoser``'s negation window [base units] and switch (the switch survives a reset)."""

    start: int = 0
    end: int = 0
    ratio: float = 0.0
    on: bool = False

    def update(self, phase: int, step_state: int, body: Pose, normaliser: int, length: int) -> Pose:
        """``LegPoser::updateAutoPose``: the leg's auto pose at master ``phase`` [iterations]."""
        start = self.start * normaliser or length  # 0 means the cycle length (the same phase)
        end = self.end * normaliser or length
        if start > end:
            end += length
            if phase < start:
                phase += length
        if step_state not in (FORCE_STANCE, FORCE_STOP) and phase == start:
            self.on = True
        if phase < start or phase > end:  # the end phase itself is still negated
            self.on = False
        if not self.on:
            return body
        iteration = phase - start + 1
        count = end - start
        control = 1.0
        if self.ratio > 0.0:
            if iteration <= count // 2:
                control = min(1.0, iteration / (count * self.ratio))
            else:
                control = min(1.0, (count - iteration) / (count * self.ratio))  # < 0 at the end phase
        negation = Pose().interpolate(smooth_step(control), body)
        return body.remove(negation)


class AutoPoser:
    """OpenSHC auto posing for one robot (``PoseController`` auto-pose state, its ``AutoPoser``s and ``LegPoser``s).

    Args:
        pose_set: the auto-pose set (see :mod:`shc_cli.spec.autopose`).
        gait: the gait walked; its offset multipliers choose the reference leg.
        cycle: the walker's step cycle (synchronised sets use its period and normaliser).
        leg_ids: leg ids in id order (OpenSHC's leg container order).
        time_delta: control period [s] (free-running sets derive their cycle from it).
        gravity: gravity direction for ``gravity`` amplitudes (normalised here); default straight down.

    Raises:
        ValueError: no leg with offset multiplier 0 (no reference leg), a leg missing from the gait, or a
            free-running frequency too high for ``time_delta``.
    """

    def __init__(self, pose_set: AutoPoseSet, gait: Gait, cycle: StepCycle, leg_ids: Sequence[str],
                 time_delta: float, gravity: Sequence[float] = (0.0, 0.0, -1.0)) -> None:
        self.leg_ids = list(leg_ids)
        self.time_delta = time_delta
        self.gravity = np.asarray(gravity, dtype=float)
        self.state = PosingState.POSING_COMPLETE
        self.master_phase = 0
        self.pose_phase = 0  # own phase counter [iterations] (free-running sets)
        self._body = Pose()
        self._legs = [Pose() for _ in self.leg_ids]
        self._negations = [_LegNegation() for _ in self.leg_ids]
        self.pose_set = pose_set
        self.gait = gait
        self.reset(cycle)

    # -- OpenSHC setAutoPoseParams ---------------------------------------------------------------------------

    def reset(self, cycle: StepCycle, gait: Gait | None = None, pose_set: AutoPoseSet | None = None) -> None:
        """Re-derive the posing cycle, the reference leg and the posers (OpenSHC ``setAutoPoseParams``).

        Fresh posers start idle. Kept, as in OpenSHC: the posing state, the pose phase counter, the last
        poses and each leg's negation switch.
        """
        self.gait = gait or self.gait
        self.pose_set = pose_set or self.pose_set
        pose_set = self.pose_set
        if pose_set.synchronised:
            self.phase_length = cycle.period  # same arithmetic as OpenSHC's with the step frequency
            self.normaliser = cycle.normaliser
        else:
            base = pose_set.pose_phase_length
            raw = (1.0 / pose_set.pose_frequency) / self.time_delta
            self.phase_length = even_up(math.trunc(raw / base)) * base
            self.normaliser = self.phase_length // base
            if self.phase_length == 0:
                raise ValueError(f"pose_frequency {pose_set.pose_frequency:g} Hz leaves less than one iteration per "
                                 f"base unit at time_delta {self.time_delta:g} s; lower the frequency")
        reference = None
        for index, leg in enumerate(self.leg_ids):
            negation = pose_set.negation.get(leg)
            state = self._negations[index]
            state.start, state.end, state.ratio = (negation.start, negation.end, negation.transition_ratio) \
                if negation is not None else (0, 0, 0.0)
            if leg not in self.gait.offset_multiplier:
                raise ValueError(f"leg {leg} has no offset multiplier in gait '{self.gait.name}'")
            if self.gait.offset_multiplier[leg] == 0:
                reference = index  # the last such leg in id order
        if reference is None:
            raise ValueError(f"gait '{self.gait.name}' has no leg with offset multiplier 0 to synchronise with")
        self.reference_leg = reference
        self._posers = [_PoserCycle(spec) for spec in pose_set.poser]

    # -- OpenSHC PoseController::updateAutoPose --------------------------------------------------------------

    def update(self, walk_state: int, zero_stride: bool, leg_phases: np.ndarray, leg_states: np.ndarray) -> None:
        """One cycle of auto posing.

        Args:
            walk_state: walk state after the previous walk update (:class:`~shc_cli.control.walk.WalkState`).
            zero_stride: the reference leg's stored stride vector has norm exactly 0.
            leg_phases: each leg's step phase [iterations], legs in id order (previous cycle's).
            leg_states: each leg's step state (``stepping.SWING`` … ``FORCE_STOP``), legs in id order.
        """
        if walk_state in (STARTING, MOVING):
            self.state = PosingState.POSING
        elif (zero_stride and walk_state == STOPPING) or walk_state == STOPPED:
            self.state = PosingState.STOP_POSING
        synchronised = self.pose_set.synchronised
        if synchronised:
            master = int(leg_phases[self.reference_leg])
        else:
            master = self.pose_phase
            self.pose_phase = (self.pose_phase + 1) % self.phase_length
        self.master_phase = master
        gravity = self._gravity()
        body = Pose()
        idle = 0
        for poser in self._posers:
            pose = poser.update(master, self.state, synchronised, self.normaliser, self.phase_length, gravity)
            idle += not poser.posing
            body = body.add(pose)
        if idle == len(self._posers):
            self.state = PosingState.POSING_COMPLETE
        self._body = body
        self._legs = [negation.update(master, int(leg_states[index]), body, self.normaliser, self.phase_length)
                      for index, negation in enumerate(self._negations)]

    def _gravity(self) -> np.ndarray:
        return np.asarray(self.gravity / np.linalg.norm(self.gravity))

    # -- outputs -----------------------------------------------------------------------------------------------

    @property
    def body_pose(self) -> Pose:
        """The body auto pose [m, rad] (OpenSHC ``auto_pose_``); do not modify."""
        return self._body

    @property
    def leg_poses(self) -> list[Pose]:
        """Each leg's auto pose, legs in id order (the body auto pose, negated in the leg's window)."""
        return list(self._legs)

    @property
    def posing_complete(self) -> bool:
        """True when every poser is idle: the walk controller may then go STOPPING → STOPPED."""
        return self.state == PosingState.POSING_COMPLETE

    @property
    def negated_legs(self) -> list[str]:
        """Ids of the legs whose negation is switched on."""
        return [leg for leg, negation in zip(self.leg_ids, self._negations, strict=True) if negation.on]


__all__ = ["AutoPoser", "PosingState", "euler_rotation"]
