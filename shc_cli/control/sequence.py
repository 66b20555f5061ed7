"""OpenSHC's sequence mode (``start_up_sequence: true``): pack/unpack, start-up/shut-down sequences, state estimate.

Pure computation over arrays of legs in id order; no I/O, no model state. Reproduces, from
``csiro-robotics/syropod_highlevel_controller`` v0.5.10 (``src/pose_controller.cpp``: ``packLegs``,
``unpackLegs``, ``executeSequence``, ``LegPoser::transitionConfiguration``, ``LegPoser::stepToPosition``;
``src/state_controller.cpp`` v0.5.10 ``transitionRobotState``; constants from ``pose_controller.h`` 2019 and
``state_controller.h``), study §9.2–§9.3.

Pieces:

* :class:`PackTransition` — ``packLegs`` / ``unpackLegs``: joint-space cubic transitions, ``PACK_TIME/f_p`` s each
  (in :mod:`shc_cli.control.packing` with the joint configurations and the state estimate; re-exported here).
* :class:`StepToPosition` — ``LegPoser::stepToPosition`` for many legs: a dual quartic Bézier tip path with lift,
  evaluated directly (not integrated) with the body pose interpolated from identity.
* :class:`Sequence` — ``executeSequence(START_UP | SHUT_DOWN)``: discovery on the first start-up, replays after.
* :func:`estimate_state` — the ``UNKNOWN`` branch of ``transitionRobotState``.

Integration contract (for :class:`shc_cli.control.controller.Controller`, which stays the one owner of the model
state — desired joints, joint velocities, FK tips — and of IK). Inside one control cycle, as OpenSHC's
``StateController::loop`` (study §9.2–§9.4, §10.1):

1. Body pose update (``updateCurrentPose``) whenever the state is not UNKNOWN.
2. If a transition is pending, one call of the transition handler:

   * UNKNOWN (first request only): ``estimate_state(joints, packed[-1], unpacked, sequence_mode)`` on the measured
     joints (without feedback: the initial joints); state := READY if ``estimate.ready`` else PACKED; done.
   * PACKED → READY: ``cycle = packer.step(UNPACK, model.joints, f_p)``; ``model.joints := cycle.joints``, FK for the
     tips; joint velocities untouched (OpenSHC does not write them); READY when ``cycle.progress == 100``.
   * READY → PACKED: the same with ``PACK``; PACKED at 100.
   * READY → RUNNING: ``plan = sequence.begin(START_UP, model.tips, default_tips, f_p, swing_height)`` with
     ``default_tips = body_pose.inverse_transform(walker default tips)`` (identity tips ``(x_s, y_s, 0)`` before the
     first start-up); then **one IK step for the legs in ``plan.active`` only** towards ``plan.targets`` (legs not
     active get no IK call at all: their joints and velocities stay as they are), with the robot's normal IK options
     (velocity clamp per ``robot.ik``, not the "simulation" variant); then
     ``progress = sequence.finish(result)`` with ``result`` = OpenSHC's ``applyIK`` return per leg
     (:attr:`shc_cli.model.ik.StepResult.result`: limit proximity, 0 if the tip missed by > 5 mm on an axis).
     (:meth:`Sequence.step` does the three calls with a callable.) At 100, in this order: walker re-created
     (leg steppers at the identity tips), default joints := current joints, workspaces, walkspace, limits,
     state := RUNNING — and the RUNNING part of the same cycle then runs (walk update, tip poses, IK).
   * RUNNING → READY: while the walker is not STOPPED, force the velocity input to zero (the RUNNING walk update
     still runs this cycle); once STOPPED (and manual legs returned), ``sequence.begin(SHUT_DOWN, …)``, IK,
     ``finish`` as above; READY at 100.
3. If the state is RUNNING: the running cycle, whose first priority is again the pending transition.

Quirk 8 (study §14): OpenSHC reaches step 2 twice per cycle in RUNNING (``loop`` calls ``transitionRobotState``,
then ``runningState`` calls it again because the flag is still set), so the shut-down sequence advances **two**
iterations (two stepToPosition evaluations and two IK steps) per control cycle: every step takes half its nominal
time (Bullet: 0.45 s per group step, 1.36 s lowering). The controller runs one iteration per cycle by default
(each step at its nominal time, a deliberate deviation, docs/deviations.md) and reproduces the quirk with its
option ``openshc_double_shutdown=True`` (what a recorded OpenSHC shut-down needs to be matched). This module is
neutral: each ``begin``/``finish`` pair is one OpenSHC iteration; the controller decides how many it runs per cycle.

Deliberate simplifications (exact for the shipped robots): admittance deltas are zero (``admittance_control``
off), tip rotations are undefined (``gravity_aligned_tips`` off; the IK is position-only) and legs are never
manually manipulated during a sequence.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum

import numpy as np
from numpy.typing import NDArray

from shc_cli.control.bezier import quartic, smooth_step
from shc_cli.control.packing import (  # re-exported: the controller reaches both parts as ``sequence``
    JOINT_TOLERANCE as JOINT_TOLERANCE,
)
from shc_cli.control.packing import PACK_TIME as PACK_TIME
from shc_cli.control.packing import PROGRESS_COMPLETE as PROGRESS_COMPLETE
from shc_cli.control.packing import Configuration as Configuration
from shc_cli.control.packing import JointCycle as JointCycle
from shc_cli.control.packing import PackDirection as PackDirection
from shc_cli.control.packing import PackTransition as PackTransition
from shc_cli.control.packing import SequenceError as SequenceError
from shc_cli.control.packing import StateEstimate as StateEstimate
from shc_cli.control.packing import estimate_state as estimate_state
from shc_cli.control.packing import joint_configurations as joint_configurations
from shc_cli.control.pose import Pose
from shc_cli.control.startup import iterations
from shc_cli.model.chains import FloatArray

BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.int64]

GENERATING = -1
"""Progress reported while the first start-up is still discovering its sequence."""
TIP_TOLERANCE = 0.01
"""A tip this close to its target needs no step when there is no lift [m] (pose_controller.h)."""
SAFETY_FACTOR = 0.15
"""Discovery stops a leg early when its IK result drops below ``SAFETY_FACTOR/(step + 1)`` (pose_controller.h)."""
HORIZONTAL_TRANSITION_TIME = 1.0
"""Duration of a horizontal transition at ``step_frequency`` 1 Hz [s] (pose_controller.h)."""
VERTICAL_TRANSITION_TIME = 3.0
"""Duration of a vertical transition at ``step_frequency`` 1 Hz [s] (pose_controller.h)."""
TRANSITION_STEP_THRESHOLD = 20
"""A discovery needing more transitions than this fails (pose_controller.h)."""
HALF_BODY_DEPTH = 0.05
"""Legs bear the load when the mean tip z is below ``−HALF_BODY_DEPTH`` in base_link [m] (model.h)."""


# -- stepToPosition --------------------------------------------------------------------------------------------------


class StepToPosition:
    """``LegPoser::stepToPosition`` for ``L`` legs, each with its own iteration state.

    Per leg, the first call takes the origin ``o`` = the model tip; each call then advances one iteration ``k`` of
    ``n = round(T/dt)`` and returns the tip target ``P_k⁻¹·B(k)`` (base_link) where ``P_k`` = identity interpolated
    towards ``body_pose`` by ``smoothStep((k−1)/n)`` and ``B`` is the dual quartic Bézier with nodes
    ``[o, o, o+h, t + ¾(o−t) + h, t + ½(o−t) + h]`` (first ``n//2`` iterations, ``τ = 2k/n``) and
    ``[t + ½(o−t) + h, t + ¼(o−t) + h, t + h, t, t]`` (the rest, ``τ = 2(k − n//2)/n``), ``h`` = lift on z.
    With odd ``n`` the last τ exceeds 1 slightly (e.g. 546/545), as in OpenSHC. A leg within
    :data:`TIP_TOLERANCE` of its target with no lift finishes at once, its target being the origin.

    Args:
        legs: number of legs.
        time_delta: control period [s].
    """

    def __init__(self, legs: int, time_delta: float) -> None:
        self.time_delta = time_delta
        self.first = np.ones(legs, dtype=bool)
        self.count = np.zeros(legs, dtype=np.int64)
        self.origin = np.zeros((legs, 3))
        self.current = np.zeros((legs, 3))
        """Latest tip target per leg (OpenSHC ``current_tip_pose_``), base_link [m]."""

    def reset(self, legs: BoolArray | None = None) -> int:
        """``resetStepToPosition``: the next call starts a new step; returns 100."""
        if legs is None:
            self.first[:] = True
        else:
            self.first[legs] = True
        return PROGRESS_COMPLETE

    def step(self, model_tips: FloatArray, targets: FloatArray, lift: float, duration: float,
             active: BoolArray, body_pose: Pose | None = None) -> IntArray:
        """Advance the ``active`` legs one iteration; their new tip targets are in :attr:`current`.

        Args:
            model_tips: model tip positions (FK of the desired joints) ``(L, 3)``, base_link [m].
            targets: target tip positions ``(L, 3)``, base_link [m].
            lift: lift height added to z at the middle of the step [m].
            duration: step duration T [s].
            active: legs to advance ``(L,)``.
            body_pose: body pose reached at the end (default identity).

        Returns:
            Progress per leg ``(L,)``: ``int(100·(k−1)/n)``, 100 on the last iteration; 0 for inactive legs.
        """
        pose = Pose() if body_pose is None else body_pose
        progress = np.zeros(len(active), dtype=np.int64)
        n = iterations(duration, self.time_delta)
        delta_t = 1.0 / n
        half = n // 2
        for leg in np.flatnonzero(active).tolist():
            if self.first[leg]:
                self.origin[leg] = model_tips[leg]
                self.current[leg] = model_tips[leg]
                self.count[leg] = 0
                self.first[leg] = False
            origin, target = self.origin[leg], np.asarray(targets[leg], dtype=float)
            if float(np.linalg.norm(origin - pose.inverse_transform(target))) < TIP_TOLERANCE and lift == 0.0:
                self.first[leg] = True
                progress[leg] = PROGRESS_COMPLETE
                continue
            self.count[leg] += 1
            count = int(self.count[leg])
            ratio = (count - 1) / n
            body = Pose().interpolate(smooth_step(ratio), pose)
            offset = origin - target
            primary = np.stack([origin, origin, origin, target + 0.75 * offset, target + 0.5 * offset])
            secondary = np.stack([target + 0.5 * offset, target + 0.25 * offset, target, target, target])
            primary[2:, 2] += lift
            secondary[:3, 2] += lift
            swing = (count + (n - 1)) % n + 1
            if swing <= half:
                point = quartic(primary, swing * delta_t * 2.0)
            else:
                point = quartic(secondary, (swing - half) * delta_t * 2.0)
            self.current[leg] = body.inverse_transform(point)
            if count >= n:
                self.first[leg] = True
                progress[leg] = PROGRESS_COMPLETE
            else:
                progress[leg] = int(ratio * PROGRESS_COMPLETE)
        return progress


# -- executeSequence -------------------------------------------------------------------------------------------------


class SequenceKind(Enum):
    START_UP = "start_up"
    SHUT_DOWN = "shut_down"


@dataclass(frozen=True)
class SequencePlan:
    """What one sequence iteration asks of the controller.

    Attributes:
        targets: tip targets ``(L, 3)`` in base_link [m]; meaningful where ``active``.
        active: legs that take one IK step towards ``targets`` this iteration; the others get no IK call.
    """

    targets: FloatArray
    active: BoolArray


class Sequence:
    """OpenSHC's ``executeSequence``: the stepped start-up and shut-down between READY and RUNNING.

    The first START_UP *discovers* the sequence: from the current tips it alternates horizontal transitions
    (even steps; xy to the default tips, z kept; legs in groups ``id % 2`` with lift ``swing_height`` when the legs
    bear the load, else all at once without lift; ``2·1/f_p`` s) and vertical ones (odd steps; z to the default,
    xy kept; all legs; ``2·3/f_p`` s). A leg whose IK result drops below ``SAFETY_FACTOR/(step+1)`` stops where it
    is. The transition after the first one completed without such an alert is the last. Each leg's reached
    targets are stored (index 0 = its start tip). Later START_UPs replay them forwards, SHUT_DOWNs backwards,
    at the nominal times and without early stops.

    Use per iteration: ``plan = begin(...)``, one IK step for ``plan.active``, ``progress = finish(result)`` — or
    :meth:`step` with a callable doing the IK. Progress is −1 while discovering, then 0..99, and 100 once.

    Args:
        legs: number of legs (ids 0..L−1 in order; group = id % 2).
        time_delta: control period [s].
    """

    def __init__(self, legs: int, time_delta: float) -> None:
        self.legs = legs
        self.time_delta = time_delta
        self.groups = np.arange(legs) % 2
        self.stepper = StepToPosition(legs, time_delta)
        self.transition_poses: list[list[FloatArray]] = [[] for _ in range(legs)]
        """Per leg, the stored tip targets of each transition step (base_link) [m]."""
        self.transition_step = 0
        self.transition_step_count = 0
        self.first_execution = True
        self.reset_sequence = True
        self.set_target = True
        self.proximity_alert = False
        self.horizontal_complete = False
        self.vertical_complete = False
        self.current_group = 0
        self.legs_completed = 0
        self.completed = np.zeros(legs, dtype=bool)
        self.targets = np.zeros((legs, 3))
        self._pending: _Iteration | None = None

    # The two halves of one OpenSHC iteration ------------------------------------------------------------------------

    def begin(self, kind: SequenceKind, model_tips: FloatArray, default_tips: FloatArray,
              step_frequency: float, swing_height: float) -> SequencePlan:
        """First half of one iteration: set targets if due and advance the stepping legs' tip paths.

        Args:
            kind: START_UP or SHUT_DOWN.
            model_tips: model tips (FK of the desired joints) at the start of the iteration ``(L, 3)``, base_link [m].
            default_tips: default stance tips under this cycle's body pose ``(L, 3)``, base_link [m]
                (only used while discovering).
            step_frequency: current ``step_frequency`` [Hz].
            swing_height: current ``swing_height`` [m].
        """
        if self._pending is not None:
            raise RuntimeError("Sequence.begin called twice without finish")
        start_up = kind is SequenceKind.START_UP
        if self.reset_sequence and start_up:
            self.reset_sequence = False
            self.first_execution = True
            self.transition_step = 0
            self.transition_poses = [[np.array(tip, dtype=float)] for tip in model_tips]
        elif self.first_execution and not start_up:
            raise SequenceError("a shut-down sequence needs a completed start-up sequence first")
        step = self.transition_step
        divisor = max(self.transition_step_count, 1)
        if start_up:
            horizontal = step % 2 == 0
            next_step, step_target = step + 1, self.transition_step_count
            total = step * 100 // divisor
        else:
            horizontal = step % 2 == 1
            next_step, step_target = step - 1, 0
            total = 100 - step * 100 // divisor
        # Discovery: the transition after the first one completed without a proximity alert is the last.
        final = (self.horizontal_complete or self.vertical_complete) if self.first_execution \
            else next_step == step_target
        safety = SAFETY_FACTOR / (step + 1) if self.first_execution else 0.0
        scale = 2.0 if self.first_execution else 1.0
        active = np.zeros(self.legs, dtype=bool)
        progress = np.zeros(self.legs, dtype=np.int64)
        direct = False
        if horizontal:
            if self.set_target:
                self.set_target = False
                self.completed[:] = False
                for leg in range(self.legs):
                    target = self._stored_or_default(leg, next_step, default_tips)
                    target[2] = model_tips[leg][2]  # keep the height
                    self.targets[leg] = target
            direct = not legs_bearing_load(model_tips)
            for leg in range(self.legs):
                if self.completed[leg]:
                    continue
                if self.groups[leg] == self.current_group or direct:
                    active[leg] = True
                else:  # not in the stepping group: done without moving (and without IK)
                    self.legs_completed += 1
                    self.completed[leg] = True
            lift = 0.0 if direct else swing_height
            duration = HORIZONTAL_TRANSITION_TIME / step_frequency * scale
            progress = self.stepper.step(model_tips, self.targets, lift, duration, active)
        else:
            if self.set_target:
                self.set_target = False
                for leg in range(self.legs):
                    target = self._stored_or_default(leg, next_step, default_tips)
                    target[0], target[1] = model_tips[leg][0], model_tips[leg][1]  # keep the horizontal position
                    self.targets[leg] = target
            active[:] = True
            duration = VERTICAL_TRANSITION_TIME / step_frequency * scale
            progress = self.stepper.step(model_tips, self.targets, 0.0, duration, active)
        self._pending = _Iteration(start_up, horizontal, direct, next_step, final, safety, total, active, progress)
        return SequencePlan(self.stepper.current.copy(), active)

    def finish(self, limit_proximity: FloatArray) -> int:
        """Second half of one iteration, after the IK step: early stops, completion, progress.

        Args:
            limit_proximity: OpenSHC's ``applyIK`` result per leg ``(L,)`` (limit proximity, 0 if the tip missed by
                more than 5 mm on an axis); only the active legs' values are read.

        Returns:
            −1 while discovering, 100 when the sequence is complete, else the overall progress 0..99.

        Raises:
            SequenceError: the discovery needed more than :data:`TRANSITION_STEP_THRESHOLD` transitions.
        """
        it = self._pending
        if it is None:
            raise RuntimeError("Sequence.finish called without begin")
        self._pending = None
        divisor = max(self.transition_step_count, 1)
        sequence_complete = False
        if it.horizontal:
            progress = 0  # OpenSHC keeps the progress of the last leg stepped (0 if none stepped)
            for leg in np.flatnonzero(it.active).tolist():
                leg_progress = int(it.progress[leg])
                exceeded = float(limit_proximity[leg]) < it.safety
                if self.first_execution and exceeded:  # stop early where the leg is
                    self.targets[leg] = self.stepper.current[leg]
                    leg_progress = self.stepper.reset(_only(self.legs, leg))
                    self.proximity_alert = True
                if leg_progress == PROGRESS_COMPLETE:
                    self.completed[leg] = True
                    self.legs_completed += 1
                    if self.first_execution:
                        reached = self.targets[leg] if not exceeded else self.stepper.current[leg]
                        self.transition_poses[leg].append(np.array(reached, dtype=float))
                progress = leg_progress
            if it.direct:
                normalised = progress // divisor
            else:
                normalised = (progress // 2 + (0 if self.current_group == 0 else 50)) // divisor
            if self.legs_completed == self.legs:
                self.set_target = True
                self.legs_completed = 0
                if self.current_group == 1 or it.direct:
                    self.current_group = 0
                    self.transition_step = it.next_step
                    self.horizontal_complete = not self.proximity_alert
                    sequence_complete = it.final
                    self.proximity_alert = False
                elif self.current_group == 0:
                    self.current_group = 1
        else:
            within = not bool((np.asarray(limit_proximity, dtype=float) < it.safety).any())
            progress = int(it.progress[-1])  # the last leg's progress decides, as in OpenSHC
            if (not within and self.first_execution) or progress == PROGRESS_COMPLETE:
                for leg in range(self.legs):
                    progress = self.stepper.reset(_only(self.legs, leg))
                    if self.first_execution:
                        reached = self.targets[leg] if within else self.stepper.current[leg]
                        self.transition_poses[leg].append(np.array(reached, dtype=float))
                self.vertical_complete = within
                self.transition_step = it.next_step
                sequence_complete = it.final
                self.set_target = True
            normalised = progress // divisor
        if self.first_execution:
            self.transition_step_count = self.transition_step
        if self.transition_step > TRANSITION_STEP_THRESHOLD:
            raise SequenceError(f"no start-up sequence found within {TRANSITION_STEP_THRESHOLD} transitions "
                                "(OpenSHC shuts down here): start from a configuration nearer the stance, "
                                "e.g. adjust 'unpacked' joints or the stance positions")
        if sequence_complete:
            self.set_target = True
            self.vertical_complete = False
            self.horizontal_complete = False
            self.first_execution = False
            return PROGRESS_COMPLETE
        total = min(it.total + normalised, PROGRESS_COMPLETE - 1)
        return GENERATING if self.first_execution else total

    def step(self, kind: SequenceKind, model_tips: FloatArray, default_tips: FloatArray, step_frequency: float,
             swing_height: float, solve: Callable[[FloatArray, BoolArray], FloatArray]) -> int:
        """One whole iteration: :meth:`begin`, ``solve(targets, active) -> limit proximity``, :meth:`finish`."""
        plan = self.begin(kind, model_tips, default_tips, step_frequency, swing_height)
        return self.finish(solve(plan.targets, plan.active))

    @property
    def discovering(self) -> bool:
        """True until the first start-up sequence has completed."""
        return self.first_execution

    def _stored_or_default(self, leg: int, index: int, default_tips: FloatArray) -> FloatArray:
        poses = self.transition_poses[leg]
        source = poses[index] if 0 <= index < len(poses) else default_tips[leg]
        return np.array(source, dtype=float)


@dataclass(frozen=True)
class _Iteration:
    """State carried from :meth:`Sequence.begin` to :meth:`Sequence.finish`."""

    start_up: bool
    horizontal: bool
    direct: bool
    next_step: int
    final: bool
    safety: float
    total: int
    active: BoolArray
    progress: IntArray


def _only(legs: int, leg: int) -> BoolArray:
    mask = np.zeros(legs, dtype=bool)
    mask[leg] = True
    return mask


def legs_bearing_load(model_tips: FloatArray) -> bool:
    """OpenSHC ``Model::legsBearingLoad``: mean tip z (summed in leg order) below ``−HALF_BODY_DEPTH``."""
    total = 0.0
    for z in np.asarray(model_tips, dtype=float)[:, 2].tolist():
        total += z
    return -(total / len(model_tips)) > HALF_BODY_DEPTH


__all__ = [
    "GENERATING", "HALF_BODY_DEPTH", "HORIZONTAL_TRANSITION_TIME", "JOINT_TOLERANCE", "PACK_TIME",
    "PROGRESS_COMPLETE", "SAFETY_FACTOR", "TIP_TOLERANCE", "TRANSITION_STEP_THRESHOLD", "VERTICAL_TRANSITION_TIME",
    "Configuration", "JointCycle", "PackDirection", "PackTransition", "Sequence", "SequenceError", "SequenceKind",
    "SequencePlan", "StateEstimate", "StepToPosition", "estimate_state", "joint_configurations",
    "legs_bearing_load",
]
