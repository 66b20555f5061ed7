"""The posing of the controller: the body pose of each cycle (OpenSHC ``updateCurrentPose``, study §7) from the
manual inputs, auto posing and the sensor-driven terms (ATHENA posture, inclination, IMU), and the feet's contact
state. A collaborator of :class:`~shc_cli.control.controller.Controller`: it keeps the IMU poser and the contact
detector and works on the controller's shared state (:class:`~shc_cli.control.core.ControllerCore`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from shc_cli.control import stepping
from shc_cli.control.autopose import AutoPoser
from shc_cli.control.pose import Pose, PoseReset
from shc_cli.control.sensing import (
    ContactDetector,
    ImuPoser,
    Sensors,
    inclination_pose,
    support_centroid_pose,
)
from shc_cli.control.states import RobotState, WalkState

if TYPE_CHECKING:
    from shc_cli.control.core import ControllerCore

_RUNNING = RobotState.RUNNING
_STOPPED = WalkState.STOPPED
_IMMEDIATE_ALL = PoseReset.IMMEDIATE_ALL


class Posing:
    """The body pose of each cycle and the contact state of the feet."""

    def __init__(self, core: ControllerCore) -> None:
        self.c = core
        robot, dt = core.robot, core.dt
        pose_spec, adm = robot.pose, robot.admittance
        self.imu_poser = ImuPoser((pose_spec.rotation_pid_gains.p, pose_spec.rotation_pid_gains.i,
                                   pose_spec.rotation_pid_gains.d),
                                  (pose_spec.max_rotation.roll, pose_spec.max_rotation.pitch), dt) \
            if pose_spec.imu else None
        self.contact_detector = ContactDetector(len(robot.legs), adm.touchdown_threshold, adm.liftoff_threshold)
        self.contacts = np.zeros(len(robot.legs), dtype=bool)
        """Feet on the ground by the force thresholds (touchdown/lift-off), updated when sensors report forces."""

    def update(self, forced_reset: bool) -> None:
        """The body pose of this cycle, from the previous cycle's leg states (OpenSHC ``updateCurrentPose``)."""
        c = self.c
        if c.walker is None:
            progress, planes, normals = np.empty(0), np.empty((0, 3)), np.empty((0, 3))
        else:
            legs = c.walker.legs
            progress = legs.floats[:, stepping.SWING_PROGRESS]
            planes, normals = legs.vectors[:, stepping.PLANE], legs.vectors[:, stepping.NORMAL]
        if c.state == _RUNNING:
            reset = _IMMEDIATE_ALL if forced_reset else c.pose_reset
            c.poser.update_manual(c.pose_input, reset)
        auto = None
        if c.autoposer is not None:
            self._update_auto_pose(c.autoposer)
            auto = c.autoposer.body_pose
        feedback: tuple[Pose | None, ...] = ()
        if c.uses_sensors:
            auto, feedback = self._feedback_poses(auto)
        c.poser.update_current_pose(progress, c.gait.swing_phase, c.gait.phase_offset, planes, normals, auto,
                                    feedback)

    def _feedback_poses(self, auto: Pose | None) -> tuple[Pose | None, tuple[Pose | None, ...]]:
        """The sensor-driven pose terms of this cycle: ATHENA posture, inclination, IMU (replacing auto)."""
        sensors = self.c.sensors or Sensors()
        spec = self.c.robot.pose
        posture = None
        if sensors.foot_forces is not None:
            self.contacts = self.contact_detector.update(sensors.foot_forces)
        elif sensors.foot_contact is not None:
            self.contacts = np.asarray(sensors.foot_contact, dtype=bool)
        if self.c.posture is not None:
            walking = self.c.state == _RUNNING and self.c.walker is not None and self.c.walker.state != _STOPPED
            feet = self.c.model.chains.tips(sensors.joints) if sensors.joints is not None else self.c.model.tips
            contacts = self.contacts if sensors.foot_forces is not None or sensors.foot_contact is not None else None
            posture = self.c.posture.update(walking, feet, contacts, sensors.body_height)
        manual = self.c.poser.manual_pose() if self.c.poser.manual_enabled else Pose()
        inclination = None
        if spec.inclination and sensors.orientation is not None:
            limits = (spec.max_translation.x, spec.max_translation.y)
            clearance = self.c.robot.walker.body_clearance
            if spec.inclination_mode == "openshc":
                intended = manual.add(auto) if auto is not None else manual
                inclination = inclination_pose(sensors.orientation, intended, clearance, limits)
            elif self.c.walker is not None:
                stance = self.c.walker.legs.floats[:, stepping.STANCE_PROGRESS] >= 0.0
                tips = self.c.walker.legs.vectors[stance, stepping.CURRENT]
                inclination = support_centroid_pose(sensors.orientation, tips, np.asarray(self.c.robot.body.com),
                                                     clearance, limits)
        if spec.imu and self.c.state == _RUNNING and sensors.orientation is not None \
                and sensors.angular_rate is not None:
            assert self.imu_poser is not None
            auto = self.imu_poser.update(sensors.orientation, sensors.angular_rate, manual)
        return auto, (posture, inclination)

    def _update_auto_pose(self, autoposer: AutoPoser) -> None:
        legs = len(self.c.stance)
        if self.c.walker is None:
            autoposer.update(int(WalkState.STOPPED), True, np.zeros(legs, dtype=np.int64),
                             np.full(legs, stepping.FORCE_STOP))
            return
        arrays = self.c.walker.legs
        stride = arrays.vectors[autoposer.reference_leg, stepping.STRIDE]
        autoposer.update(int(self.c.walker.state), not np.any(stride), arrays.integers[:, stepping.PHASE],
                         arrays.integers[:, stepping.STATE])

