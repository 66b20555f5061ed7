"""The state the controller's collaborators share (:class:`ControllerCore`), as a protocol.

:class:`~shc_cli.control.controller.Controller` holds this state and is the façade; its collaborators — the robot
state machine (:mod:`shc_cli.control.transitions`), the walking (:mod:`shc_cli.control.walking`), the posing
(:mod:`shc_cli.control.posing`), the leg manipulation (:mod:`shc_cli.control.manipulation`) and the odometry feed
(:mod:`shc_cli.control.odometry_feed`) — each keep their own state and read or write this shared part through the
protocol, so none of them imports the controller.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:

    from shc_cli.control.admittance import AdmittanceController
    from shc_cli.control.autopose import AutoPoser
    from shc_cli.control.gait import StepCycle
    from shc_cli.control.leg_failure import LegFailure
    from shc_cli.control.pose import PoseController, PoseReset
    from shc_cli.control.robot_model import Model
    from shc_cli.control.sensing import PostureController, Sensors
    from shc_cli.control.speed_shares import ShareSource
    from shc_cli.control.states import RobotState
    from shc_cli.control.walk import WalkController
    from shc_cli.model.chains import FloatArray
    from shc_cli.model.workspace import Workplane
    from shc_cli.spec.autopose import AutoPoseSet
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot


class ControllerCore(Protocol):
    """The controller's shared state (see :class:`~shc_cli.control.controller.Controller` for each attribute)."""

    robot: Robot
    dt: float
    gait: Gait
    cycle: StepCycle
    cycles: int
    model: Model
    default_joints: FloatArray
    rest_joints: FloatArray
    state: RobotState
    requested: RobotState
    transition_pending: bool
    direct_shutdown: bool
    openshc_double_shutdown: bool
    stance: dict[str, tuple[float, float]]
    identity_walker_tips: FloatArray
    planes: dict[str, Workplane]
    walkspace: Workplane
    walker: WalkController | None
    poser: PoseController
    poser_tips: FloatArray
    autoposer: AutoPoser | None
    pose_sets: dict[str, AutoPoseSet]
    pose_input: tuple[float, ...]
    pose_reset: PoseReset
    posture: PostureController | None
    admittance: AdmittanceController | None
    uses_sensors: bool
    sensors: Sensors | None
    parameters: dict[str, float]
    pending_gait: Gait | None
    pending_parameters: list[tuple[str, float]]
    velocity_input: FloatArray
    angular_input: float
    failure: LegFailure | None
    scheduled_failure: LegFailure | None
    speed_shares: ShareSource | None

    def stop_walking(self) -> None:
        """Zero the velocity inputs (OpenSHC's forced stop before gait, leg-state and plan changes)."""

    def generate_limits(self) -> None:
        """Workspaces, walkspace and limits from the default configuration; (re)create the walker."""
