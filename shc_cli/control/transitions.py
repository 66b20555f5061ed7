"""The robot state machine (study §9.2): one state towards the request per call — the direct start-up (and shc's
direct shut-down), or OpenSHC's sequence mode (pack/unpack in joint space, stepped start-up and shut-down,
:mod:`shc_cli.control.sequence`). A collaborator of :class:`~shc_cli.control.controller.Controller`: it keeps the
transition in progress and works on the controller's shared state (:class:`~shc_cli.control.core.ControllerCore`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.control import sequence, stepping
from shc_cli.control.bezier import cubic
from shc_cli.control.startup import plan_direct_startup, transition_iterations
from shc_cli.control.states import RobotState, WalkState

if TYPE_CHECKING:
    from shc_cli.control.core import ControllerCore
    from shc_cli.model.chains import FloatArray


@dataclass
class _Transition:
    """A joint-space transition in progress (cubic Bézier from ``origin`` to ``target``)."""

    origin: FloatArray
    target: FloatArray
    count: int = 0
    steps: int = 1



class StateMachine:
    """Start-up, shut-down, packing and unpacking of one controller (its robot state transitions)."""

    def __init__(self, core: ControllerCore) -> None:
        self.c = core
        self._packer: sequence.PackTransition | None = None
        self._sequence: sequence.Sequence | None = None
        self._transition: _Transition | None = None

    def step(self) -> None:
        """Move one state towards the request (study §9.2): direct start-up, or OpenSHC's sequence mode
        (pack/unpack in joint space, stepped start-up and shut-down, :mod:`shc_cli.control.sequence`)."""
        if self.c.state == RobotState.UNKNOWN:
            packed, unpacked = self._configurations
            last = packed[-1] if len(packed) else unpacked
            estimate = sequence.estimate_state(self.c.model.joints, last, unpacked, self.c.robot.start_up.sequence)
            self.c.state = RobotState.READY if estimate.ready else RobotState.PACKED
            self.c.transition_pending = False
            return
        target = self.c.state + (1 if self.c.requested > self.c.state else -1)
        done = False
        if self.c.state == RobotState.PACKED and target == RobotState.READY:
            if not self.c.robot.start_up.sequence:
                if self._direct_move(None):
                    self.c.default_joints = self.c.model.joints.copy()
                    self.c.generate_limits()
                    done = True
            else:
                done = self._pack(sequence.PackDirection.UNPACK)
        elif self.c.state == RobotState.READY and target == RobotState.PACKED and self.c.robot.start_up.sequence:
            done = self._pack(sequence.PackDirection.PACK)
        elif self.c.state == RobotState.READY and target == RobotState.RUNNING:
            done = not self.c.robot.start_up.sequence or self._run_sequence(sequence.SequenceKind.START_UP)
            if done and self.c.robot.start_up.sequence:
                self.c.walker = None  # leg steppers re-created at the identity tips, as OpenSHC's walker init
                self.c.default_joints = self.c.model.joints.copy()
                self.c.generate_limits()
        elif self.c.state == RobotState.RUNNING and target == RobotState.READY and (
                self.c.robot.start_up.sequence or self.c.direct_shutdown):
            if self.c.walker is not None and self.c.walker.state != WalkState.STOPPED:
                self.c.stop_walking()
            else:
                done = not self.c.robot.start_up.sequence or self._run_sequence(sequence.SequenceKind.SHUT_DOWN)
        elif self.c.state == RobotState.READY and target == RobotState.PACKED and self.c.direct_shutdown:
            done = self._direct_move(self.c.rest_joints)
            if done:
                self.c.walker = None  # the next start-up begins at the identity tips, as the first one
        else:
            self.c.transition_pending = False  # refused: direct mode only goes PACKED → READY → RUNNING
            return
        if done:
            self.c.state = RobotState(target)
            if self.c.state == self.c.requested:
                self.c.transition_pending = False

    @property
    def _configurations(self) -> tuple[FloatArray, FloatArray]:
        return sequence.joint_configurations(self.c.robot, self.c.model.chains.joints)

    def _pack(self, direction: sequence.PackDirection) -> bool:
        """One cycle of packing or unpacking in joint space; True when the last configuration is reached."""
        if self._packer is None:
            self._packer = sequence.PackTransition(*self._configurations, self.c.dt)
        step = self._packer.step(direction, self.c.model.joints, self.c.parameters["step_frequency"])
        self.c.model.joints = step.joints
        self.c.model.tips = self.c.model.chains.tips(self.c.model.joints)
        return step.progress == sequence.PROGRESS_COMPLETE

    def _run_sequence(self, kind: sequence.SequenceKind) -> bool:
        """Iterations of the start-up or shut-down sequence for this cycle; True when complete.

        OpenSHC advances the shut-down two iterations per cycle (study §14 quirk 8: the transition handler runs
        twice in RUNNING); shc runs one, unless ``openshc_double_shutdown`` asks for OpenSHC's behaviour.
        """
        if self._sequence is None:
            self._sequence = sequence.Sequence(len(self.c.stance), self.c.dt)
        repeats = 2 if kind is sequence.SequenceKind.SHUT_DOWN and self.c.openshc_double_shutdown else 1
        for _ in range(repeats):
            defaults = (self.c.walker.legs.vectors[:, stepping.DEFAULT] if self.c.walker is not None
                        else self.c.identity_walker_tips)
            plan = self._sequence.begin(kind, self.c.model.tips, self.c.poser.current.inverse_transform(defaults),
                                        self.c.parameters["step_frequency"], self.c.parameters["swing_height"])
            ik = self.c.robot.ik
            self.c.model.step_ik(plan.targets, self.c.dt, ik.clamp_joint_positions, ik.clamp_joint_velocities,
                               active=plan.active)
            self.c.poser_tips = np.where(plan.active[:, None], plan.targets, self.c.poser_tips)
            if self._sequence.finish(self.c.model.proximity) == sequence.PROGRESS_COMPLETE:
                return True
        return False

    def _direct_move(self, target: FloatArray | None) -> bool:
        """Move in joint space to ``target`` over ``time_to_start`` — or, with ``None``, the direct start-up: plan
        the stance by IK on the first cycle, then move there; True when done."""
        if self._transition is None:
            if target is None:
                target = plan_direct_startup(self.c.robot, self.c.model.chains, self.c.default_joints)
            steps = transition_iterations(self.c.model.joints, target, self.c.model.chains.max_vel,
                                          self.c.robot.start_up.time_to_start, self.c.dt)
            self._transition = _Transition(self.c.model.joints.copy(), target, 0, steps)
        move = self._transition
        move.count += 1
        nodes = np.stack([move.origin, move.origin, move.target, move.target])
        self.c.model.joints = cubic(nodes, move.count * (1.0 / move.steps))
        self.c.model.tips = self.c.model.chains.tips(self.c.model.joints)
        if move.count >= move.steps:
            self._transition = None
            return True
        return False
