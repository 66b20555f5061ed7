"""Leg manipulation (OpenSHC ``legStateToggle``, ``poseForLegManipulation``, ``WalkController::updateManual``,
study §9.5): up to two legs leave the walk, are lifted and moved by tip-velocity or tip-position inputs (or, on
3-DOF legs, joint inputs), and return.

A collaborator of :class:`~shc_cli.control.controller.Controller`: it keeps the legs' modes and the manual inputs and
works on the controller's shared state (:class:`~shc_cli.control.core.ControllerCore`).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol

import numpy as np

from shc_cli.control import sequence, stepping
from shc_cli.control.pose import Pose
from shc_cli.control.states import LegMode, WalkState
from shc_cli.model.ik import IK_TOLERANCE

if TYPE_CHECKING:
    from shc_cli.control.core import ControllerCore

MAX_MANUAL_LEGS = 2
"""At most this many legs can be manipulated at once (OpenSHC)."""


class ManipulationCommand(Protocol):
    """What the manipulation reads of the controller's :class:`~shc_cli.control.controller.Command` (a protocol, so
    this part of the controller does not import the controller)."""

    @property
    def leg_toggle(self) -> str | None: ...
    @property
    def tip_velocity(self) -> Mapping[str, tuple[float, float, float]]: ...
    @property
    def tip_position(self) -> Mapping[str, tuple[float, float, float]]: ...


_WALKING_LEG = int(LegMode.WALKING)


class LegManipulator:
    """Walking ↔ manual legs and the manual legs' motion."""

    def __init__(self, core: ControllerCore, legs: int, dt: float) -> None:
        self.c = core
        self.leg_modes = np.full(legs, _WALKING_LEG)
        self.manual_legs = 0
        """Legs not in WALKING mode (kept with :attr:`leg_modes`)."""
        self.pending_toggle: int | None = None
        self.tip_velocities: dict[int, np.ndarray] = {}
        self.tip_positions: dict[int, np.ndarray] = {}
        self._manipulator = sequence.StepToPosition(legs, dt)
        self.forced_pose_reset = False

    def receive(self, command: ManipulationCommand) -> None:
        legs = list(self.c.stance)
        if command.leg_toggle is not None and self.pending_toggle is None:
            if command.leg_toggle not in legs:
                raise ValueError(f"no leg '{command.leg_toggle}' to toggle (legs: {', '.join(legs)})")
            self.pending_toggle = legs.index(command.leg_toggle)
        self.tip_velocities = {legs.index(k): np.array(v, dtype=float) for k, v in command.tip_velocity.items()}
        self.tip_positions = {legs.index(k): np.array(v, dtype=float) for k, v in command.tip_position.items()}

    def toggle_leg(self, leg: int) -> None:
        """Walking ↔ manual for one leg, once stopped (OpenSHC ``legStateToggle``, study §9.5)."""
        assert self.c.walker is not None
        if self.c.walker.state != WalkState.STOPPED:
            self.c.stop_walking()
            return
        mode = LegMode(self.leg_modes[leg])
        if mode == LegMode.WALKING:
            if int((self.leg_modes == LegMode.MANUAL).sum()) < MAX_MANUAL_LEGS:
                self.leg_modes[leg] = LegMode.WALKING_TO_MANUAL
                self.manual_legs += 1
                self.c.walker.legs.floats[leg, stepping.SWING_PROGRESS] = -1.0
                self.c.walker.legs.floats[leg, stepping.STANCE_PROGRESS] = -1.0
            else:
                self.pending_toggle = None  # refused: OpenSHC allows two manual legs
        elif mode == LegMode.MANUAL:
            self.leg_modes[leg] = LegMode.MANUAL_TO_WALKING
        else:
            self.forced_pose_reset = True  # the manual body pose goes back to the default at once
            if self._pose_for_manipulation() == sequence.PROGRESS_COMPLETE:
                self.leg_modes[leg] = LegMode.MANUAL if mode == LegMode.WALKING_TO_MANUAL else LegMode.WALKING
                self.manual_legs -= int(self.leg_modes[leg] == _WALKING_LEG)
                self.pending_toggle = None
                self.forced_pose_reset = False

    def _pose_for_manipulation(self) -> int:
        """Every leg steps to its default tip; a leg going manual is raised to swing height above the body
        origin's plane, no lift (OpenSHC ``poseForLegManipulation``). Returns the smallest progress."""
        assert self.c.walker is not None
        height = self.c.parameters["swing_height"]
        duration = 1.0 / self.c.parameters["step_frequency"]
        body = self.c.poser.current
        walking_pose = Pose(body.position - self.c.poser.manual[:3], body.rotation)
        lifted_pose = Pose(np.array([0.0, 0.0, -height]))
        vectors = self.c.walker.legs.vectors
        rising = self.leg_modes == LegMode.WALKING_TO_MANUAL
        targets = np.empty((len(self.c.stance), 3))
        for leg in range(len(self.c.stance)):
            default = vectors[leg, stepping.DEFAULT]
            targets[leg] = (lifted_pose if rising[leg] else walking_pose).inverse_transform(default)
            if rising[leg]:
                vectors[leg, stepping.CURRENT] = targets[leg]
            elif self.leg_modes[leg] == LegMode.MANUAL_TO_WALKING:
                vectors[leg, stepping.CURRENT] = default
        lifted = self._manipulator.step(self.c.model.tips, targets, 0.0, duration, rising)  # no lift for this one
        stepping_legs = self._manipulator.step(self.c.model.tips, targets, height, duration, ~rising)
        progress = np.where(rising, lifted, stepping_legs)
        moving = progress != sequence.PROGRESS_COMPLETE
        if moving.any():
            ik = self.c.robot.ik
            self.c.poser_tips = np.where(moving[:, None], self._manipulator.current, self.c.poser_tips)
            self.c.model.step_ik(self._manipulator.current, self.c.dt, ik.clamp_joint_positions,
                               ik.clamp_joint_velocities, active=moving)
        return int(progress.min())

    def update_manual_legs(self) -> None:
        """Move manual legs by their inputs (OpenSHC ``WalkController::updateManual``, study §9.5)."""
        assert self.c.walker is not None
        vectors = self.c.walker.legs.vectors
        spec = self.c.robot
        for leg in np.flatnonzero(self.leg_modes == LegMode.MANUAL).tolist():
            velocity = self.tip_velocities.get(leg)
            if velocity is not None and np.any(velocity):
                joints = list(spec.legs.values())[leg].joints
                if spec.manipulation.mode == "joint_control" and len(joints) == 3:
                    step = spec.pose.max_rotation_velocity * self.c.dt
                    self.c.model.joints = self.c.model.joints.copy()  # outputs hold the previous array: never mutate
                    self.c.model.joints[leg, 0] += velocity[1] * step
                    self.c.model.joints[leg, 2] += velocity[0] * step
                    self.c.model.tips = self.c.model.chains.tips(self.c.model.joints)
                    vectors[leg, stepping.CURRENT] = self.c.model.tips[leg]
                elif spec.manipulation.mode == "tip_control":
                    error = self.c.poser_tips[leg] - self.c.model.tips[leg]
                    change = velocity * spec.pose.max_translation_velocity * self.c.dt
                    size = float(np.linalg.norm(error))
                    if size >= IK_TOLERANCE:  # at the edge of reach: back off along the error
                        change = float(np.linalg.norm(change)) * -(error / size)
                    vectors[leg, stepping.CURRENT] = vectors[leg, stepping.CURRENT] + change
            position = self.tip_positions.get(leg)
            if position is not None and np.any(position) and spec.manipulation.mode == "tip_control":
                vectors[leg, stepping.CURRENT] = position
