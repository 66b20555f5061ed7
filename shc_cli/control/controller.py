"""The one controller: robot state machine, walking, posing and IK, advanced only by :meth:`Controller.step`.

Pure computation (no I/O, no clock, no globals). ``plan``, ``simulate`` and ``run-hw`` feed it a
:class:`Command` each control cycle (and, later, sensor readings) and send its joint targets to their
backend. The order inside one cycle is OpenSHC's main loop (study §10.1): pose update, state
transition, then in RUNNING the walk update, the tip pose generator and one IK step per leg.
Commands given at cycle ``c`` are what OpenSHC's callbacks would have received before loop ``c``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from shc_cli.control import stepping
from shc_cli.control.admittance import AdmittanceController
from shc_cli.control.autopose import AutoPoser
from shc_cli.control.gait import step_cycle
from shc_cli.control.leg_failure import LegFailure, walk_phase
from shc_cli.control.manipulation import MAX_MANUAL_LEGS as MAX_MANUAL_LEGS
from shc_cli.control.manipulation import LegManipulator
from shc_cli.control.odometry import LegOdometry
from shc_cli.control.odometry_feed import OdometryFeed
from shc_cli.control.pose import PoseController, PoseReset
from shc_cli.control.posing import Posing
from shc_cli.control.robot_model import Model as Model  # re-exported: the controller's interface
from shc_cli.control.sensing import PostureController, Sensors
from shc_cli.control.speed_shares import ShareSource
from shc_cli.control.states import LegMode as LegMode
from shc_cli.control.states import RobotState as RobotState  # re-exported: the controller's interface
from shc_cli.control.step_plane import TerrainMap
from shc_cli.control.transitions import StateMachine
from shc_cli.control.walk import WalkController, WalkState
from shc_cli.control.walking import Walking
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.workspace import Workplane
from shc_cli.spec.autopose import AutoPoseSet
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import ADJUSTABLE, ADJUSTABLE_ADMITTANCE, ADJUSTABLE_WALKER, Robot

UNDEFINED = float(2147483647)
"""OpenSHC's 'undefined position' value, published before a tip has been posed."""


@dataclass
class Command:
    """Inputs of one control cycle (what OpenSHC receives on its remote topics).

    Attributes:
        velocity: body velocity input (x, y, yaw) in the robot's input mode (throttle −1..1, or m/s, rad/s).
        state_request: desired robot state; each request moves the robot one state towards it.
        pose_velocity: manual posing input (x, y, z, roll, pitch, yaw), each −1..1.
        pose_reset: manual pose reset mode.
        gait: a gait to switch to; the robot stops, changes gait and walks on when inputs ask for it.
        cruise: switch cruise control on (True) or off (False); None leaves it as it is.
        parameters: run-time parameter changes ``{name: value}`` (clamped to the parameter's range); one is
            applied per cycle, in the given order, as OpenSHC does. Names: see :data:`~shc_cli.spec.robot.ADJUSTABLE`.
        leg_toggle: a leg id to switch between walking and manual manipulation (at most two manual legs);
            the robot stops first, then every leg steps so the chosen one is lifted (study §9.5).
        tip_velocity: per manual leg, a velocity input (x, y, z) each −1..1: in ``tip_control`` the tip moves at
            input × ``max_translation_velocity`` in base_link axes; in ``joint_control`` (3-DOF legs) y drives
            the coxa and x the tibia at input × ``max_rotation_velocity``.
        tip_position: per manual leg, an absolute tip position in base_link [m] (``tip_control``).
    """

    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    state_request: RobotState | None = None
    pose_velocity: tuple[float, float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    pose_reset: PoseReset = PoseReset.NO_RESET
    gait: Gait | None = None
    cruise: bool | None = None
    parameters: dict[str, float] = field(default_factory=dict)
    leg_toggle: str | None = None
    tip_velocity: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    tip_position: dict[str, tuple[float, float, float]] = field(default_factory=dict)
    terrain: TerrainMap | None = None
    """The height map and the body's pose in it (a depth sensor's, :mod:`shc_cli.control.step_plane`): OpenSHC's
    step-plane input for footholds, swing clearance and body height; ``None`` walks blind, as OpenSHC."""



# Enum members bound once: attribute access on an Enum class is slow, and these are read every cycle.
_UNKNOWN, _RUNNING = RobotState.UNKNOWN, RobotState.RUNNING
_STOPPED = WalkState.STOPPED
_MANUAL, _WALKING_TO_MANUAL = LegMode.MANUAL, LegMode.WALKING_TO_MANUAL



@dataclass
class CycleOutput:
    """Everything one cycle produces; arrays are over legs in id order.

    Attributes:
        joints: desired joint positions ``(L, n)`` [rad].
        joint_velocities: desired joint velocities ``(L, n)`` [rad/s].
        walker_tips: walker tips in the walk-plane frame ``(L, 3)`` [m].
        poser_tips: IK targets in base_link ``(L, 3)`` [m] (:data:`UNDEFINED` before the first posing).
        model_tips: tips after IK (FK of ``joints``) in base_link ``(L, 3)`` [m].
        stance_progress: 0..1 in stance, −1 otherwise ``(L,)``.
        swing_progress: 0..1 in swing, −1 otherwise ``(L,)``.
        velocity: desired body velocity (x [m/s], y [m/s], yaw rate [rad/s]).
        pose: body pose (x, y, z [m], roll, pitch, yaw [rad]) in the walk plane.
        robot_state: robot state after the cycle.
        walk_state: walk state after the cycle.
        ik_deviations: legs whose tip missed its target by more than 5 mm this cycle.
        ik_clamped: legs with a joint clamped to a limit this cycle.
        joint_speed_limited: legs with a joint whose commanded motion this cycle was limited to ``max_vel``: by the
            IK's velocity clamp (OpenSHC's ``clamp_joint_velocities``) or by shc's per-cycle joint speed guard
            (:meth:`Model.limit_speed`, docs/deviations.md).
        odometry: the body's estimated planar pose (x [m], y [m], yaw [rad]) in the odom frame (the robot's start
            pose: origin at its start position, x along its start heading), from leg odometry fused with the IMU
            (:mod:`shc_cli.control.odometry`); an shc addition, OpenSHC has none.
    """

    joints: FloatArray
    joint_velocities: FloatArray
    walker_tips: FloatArray
    poser_tips: FloatArray
    model_tips: FloatArray
    stance_progress: FloatArray
    swing_progress: FloatArray
    velocity: tuple[float, float, float]
    pose: tuple[float, float, float, float, float, float]
    robot_state: RobotState
    walk_state: WalkState
    ik_deviations: int = 0
    ik_clamped: int = 0
    joint_speed_limited: int = 0
    odometry: tuple[float, float, float] = (0.0, 0.0, 0.0)


class Controller:
    """OpenSHC's high-level controller for one robot.

    Args:
        robot: the robot description.
        gait: the gait to walk with.
        joints: initial joint positions ``(L, n)`` [rad]; default ``clamp(0, min, max)`` (OpenSHC without feedback).
        openshc_double_shutdown: run the shut-down sequence at OpenSHC's doubled speed (its quirk, see
            docs/deviations.md); by default each sequence iteration takes one control cycle.
        pose_sets: auto-pose sets by gait name (used when ``robot.pose.auto``); the caller loads them
            (``shc_cli.spec.autopose``), so the controller stays free of I/O.
        failure: failed legs held at their pose every cycle and left out of the walkspace
            (:mod:`shc_cli.control.leg_failure`; ``robot`` and ``gait`` already re-planned for the legs left).
        direct_shutdown: without a start-up sequence, let the robot go back down as well (an shc extension for
            ``run-hw``; OpenSHC's direct mode refuses): RUNNING → READY stops walking, READY → PACKED moves the
            joints back to ``joints`` (where the robot started, e.g. lying on the ground) in ``time_to_start``.

    A façade over its collaborators, each holding one concern and working on the state the controller holds
    (:class:`~shc_cli.control.core.ControllerCore`): :attr:`states` the robot state machine
    (:mod:`shc_cli.control.transitions`), :attr:`walking` limits, gait and parameter changes, cruise, step planes,
    admittance and leg failures (:mod:`shc_cli.control.walking`), :attr:`posing` the body pose
    (:mod:`shc_cli.control.posing`), :attr:`manipulation` the manual legs (:mod:`shc_cli.control.manipulation`) and
    :attr:`feed` the leg odometry (:mod:`shc_cli.control.odometry_feed`).
    """

    def __init__(self, robot: Robot, gait: Gait, joints: FloatArray | None = None,
                 openshc_double_shutdown: bool = False, pose_sets: dict[str, AutoPoseSet] | None = None,
                 direct_shutdown: bool = False, failure: LegFailure | None = None,
                 speed_shares: ShareSource | None = None) -> None:
        self.robot = robot
        self.failure = failure if failure is None or failure.at_s is None else None
        self.scheduled_failure = failure if failure is not None and failure.at_s is not None else None
        """Failures declared mid-walk (``LEG@T``): at ``at_s`` seconds of walking the controller changes to their
        re-planned gait as it changes gaits (the walker stops with every foot down), then holds the failed legs."""
        self.speed_shares = speed_shares
        """Shares of OpenSHC's speed limits per gait (a run gives :func:`shc_cli.control.verified_limits.source_for`
        of its robot); None: OpenSHC's (also with a failed leg: the limits are the walking legs' walkspace)."""
        if self.speed_shares is not None:
            self.speed_shares(gait)  # verified now, before a loop runs (another gait: when it is first chosen)
        self.direct_shutdown = direct_shutdown
        self.pose_sets = pose_sets or {}
        self.openshc_double_shutdown = openshc_double_shutdown
        self.gait = gait
        self.dt = robot.time_delta
        chains = Chains.from_robot(robot)
        start = chains.default_joints() if joints is None else np.array(joints, dtype=float)
        self.model: Model = Model(chains, start.copy(), np.zeros_like(start), robot.ik.limit_avoidance_cap)
        self.rest_joints = start.copy()
        """Where a direct shut-down takes the joints (the initial joints) [rad]."""
        self.default_joints = chains.default_joints()
        self.state = RobotState.UNKNOWN
        self.requested = RobotState.UNKNOWN
        self.transition_pending = False
        self.cycle = step_cycle(gait, robot.walker.step_frequency.default, self.dt)
        self.stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}
        self.planes: dict[str, Workplane] = {}
        self.walkspace: Workplane = {}
        self.walker: WalkController | None = None
        walker_spec, pose_spec = robot.walker, robot.pose
        self.poser = PoseController(
            walker_spec.body_clearance,
            np.array([pose_spec.max_translation.x, pose_spec.max_translation.y, pose_spec.max_translation.z]),
            np.array([pose_spec.max_rotation.roll, pose_spec.max_rotation.pitch, pose_spec.max_rotation.yaw]),
            pose_spec.max_translation_velocity, pose_spec.max_rotation_velocity, self.dt, pose_spec.manual,
        )
        self.poser_tips = np.full((len(robot.legs), 3), UNDEFINED)
        self.manipulation = LegManipulator(self, len(robot.legs), self.dt)
        self.autoposer: AutoPoser | None = None
        if robot.pose.auto and gait.name in self.pose_sets:
            self.autoposer = AutoPoser(self.pose_sets[gait.name], gait, self.cycle, list(robot.legs), self.dt)
        self.identity_walker_tips = np.array([[x, y, 0.0] for x, y in self.stance.values()])
        self.velocity_input = np.zeros(2)
        self.angular_input = 0.0
        self.pose_input: tuple[float, ...] = (0.0,) * 6
        self._throttle = robot.walker.velocity_input_mode == "throttle"
        self.pose_reset = PoseReset.NO_RESET
        self.cycles = 0
        self.joint_speed_limited_cycles = 0
        """Cycles in which a joint's commanded speed was limited (:attr:`CycleOutput.joint_speed_limited`)."""
        self.pending_gait: Gait | None = None
        self.pending_parameters: list[tuple[str, float]] = []
        walker_spec, admittance = robot.walker, robot.admittance
        self.sensors: Sensors | None = None
        pose_spec, posture_spec = robot.pose, robot.posture
        self.posture: PostureController | None = None
        if posture_spec.enabled:
            self.posture = PostureController(
                posture_spec.kz, posture_spec.ka, posture_spec.kb,
                posture_spec.reference_height, self.cycle.period, posture_spec.plane,
                max_z=posture_spec.max_height_correction, max_angle=posture_spec.max_angle_correction)
        adm = robot.admittance
        self.admittance: AdmittanceController | None = None
        if adm.enabled:
            self.admittance = AdmittanceController(
                len(robot.legs), adm.virtual_mass.default, adm.virtual_stiffness.default,
                adm.virtual_damping_ratio.default, adm.force_gain.default, adm.integrator_step_time,
                adm.swing_stiffness_scaler, adm.load_stiffness_scaler, adm.dynamic_stiffness)
        self.uses_sensors = (pose_spec.imu or pose_spec.inclination or posture_spec.enabled or adm.enabled
                             or robot.walker.rough_terrain_mode)
        self.terrain: TerrainMap | None = None
        """This cycle's height map (:attr:`Command.terrain`)."""
        self.parameters = {name: getattr(walker_spec, name).default for name in ADJUSTABLE_WALKER}
        self.parameters.update({name: getattr(admittance, name).default for name in ADJUSTABLE_ADMITTANCE})
        self._walker_tips: FloatArray | None = None
        """This cycle's walker tips (a copy) once the running cycle has posed them: the output shows the same."""
        self.states = StateMachine(self)
        self.walking = Walking(self)
        self.posing = Posing(self)
        self.feed = OdometryFeed(self)

    # -- what other packages read of the collaborators -----------------------------------------------------------

    @property
    def leg_modes(self) -> np.ndarray:
        """Each leg's :class:`LegMode` (:class:`~shc_cli.control.manipulation.LegManipulator`)."""
        return self.manipulation.leg_modes

    @property
    def pending_toggle(self) -> int | None:
        """The leg whose walking ↔ manual toggle is in progress, if any."""
        return self.manipulation.pending_toggle

    @property
    def odometry(self) -> LegOdometry:
        """Leg odometry (an shc addition): read by :attr:`CycleOutput.odometry`."""
        return self.feed.odometry

    @property
    def contacts(self) -> np.ndarray:
        """Feet on the ground by the force thresholds (touchdown/lift-off), updated when sensors report forces."""
        return self.posing.contacts

    def declare_failure(self, failure: LegFailure) -> None:
        """Failed legs from this cycle on (a detected fault): held at once (``locked``: where they are), the
        re-planned gait requested as a gait change (the walker stops, then walks on it)."""
        self.walking.declare_failure(failure)

    def generate_limits(self) -> None:
        """Workspaces, walkspace and limits from the default configuration; (re)create the walker."""
        self.walking.generate_limits()

    def _update_odometry(self, sensors: Sensors | None, stance: np.ndarray) -> tuple[float, float, float]:
        return self.feed.update(sensors, stance)

    # -- inputs ------------------------------------------------------------------------------------------------

    def _receive(self, command: Command) -> None:
        """Take a command as OpenSHC's topic callbacks would (before this cycle's loop)."""
        scaler = self.robot.walker.body_velocity_scaler
        vx, vy, wz = command.velocity
        vx, vy = float(vx) * scaler, float(vy) * scaler
        size = math.sqrt(vx * vx + vy * vy)
        if self._throttle and size > 1.0:  # throttle inputs are clipped to norm 1 on arrival
            vx, vy = vx / size, vy / size
        self.terrain = command.terrain
        if self.state == _RUNNING:
            self.velocity_input = np.array([vx, vy])
            self.angular_input = float(wz) * scaler
            self.pose_input = command.pose_velocity
            self.pose_reset = command.pose_reset
            if command.gait is not None and self.pending_gait is None:
                self.pending_gait = command.gait
            for name, value in command.parameters.items():
                if name not in ADJUSTABLE:
                    raise ValueError(f"unknown adjustable parameter '{name}' (one of {', '.join(ADJUSTABLE)})")
                self.pending_parameters.append((name, float(value)))
            if command.cruise is not None:
                self.walking.set_cruise(command.cruise)
            manipulation = self.manipulation
            if command.leg_toggle is not None or command.tip_velocity or command.tip_position \
                    or manipulation.tip_velocities or manipulation.tip_positions:
                manipulation.receive(command)
        if command.state_request is not None and not self.transition_pending:
            self.requested = command.state_request
            if self.state == _UNKNOWN or command.state_request != self.state:
                self.transition_pending = True

    # -- the cycle ---------------------------------------------------------------------------------------------

    def step(self, command: Command | None = None, sensors: Sensors | None = None) -> CycleOutput:
        """Advance one control period and return this cycle's outputs.

        ``sensors``: what the backend measured during the last period (IMU, joints, foot forces, body height);
        the feedback features (IMU and inclination posing, ATHENA posture control) read it only when the robot
        uses them (:attr:`uses_sensors`); the leg odometry reads it every cycle.
        """
        self.cycles += 1
        self.sensors = sensors if self.uses_sensors else None
        self._receive(command or Command())
        before = self.model.start_cycle(self.dt)
        if self.state != _UNKNOWN:
            self.posing.update(self.manipulation.forced_pose_reset)
        deviations = clamped = 0
        if self.transition_pending and self.state != _RUNNING:
            self.states.step()  # in RUNNING the running cycle handles it first (study §9.4)
        if self.state == _RUNNING:
            deviations, clamped = self._running()
        if self.scheduled_failure is not None:
            self.walking.schedule_failure(self.scheduled_failure)
        if self.failure is not None:
            self.walking.hold_failed(self.failure)
        limited = self.model.limit_speed(before)
        if limited:
            self.joint_speed_limited_cycles += 1
        out = self._output(deviations, clamped)
        out.joint_speed_limited = limited
        out.odometry = self.feed.update(sensors, out.stance_progress >= 0.0)
        return out

    def _running(self) -> tuple[int, int]:
        """One RUNNING cycle (study §9.4): gait change, cruise control, parameter changes, then walk, pose
        the tips and one IK step per leg — unless the cycle was spent on a change while stopped."""
        assert self.walker is not None
        walking_, manipulation = self.walking, self.manipulation
        update = True
        if self.transition_pending:
            self.states.step()
            if self.state != _RUNNING or self.walker is None:
                return 0, 0
            update = False
        elif self.pending_gait is not None:
            walking_.change_gait()
            update = False
        elif manipulation.pending_toggle is not None:
            manipulation.toggle_leg(manipulation.pending_toggle)
            update = False
        elif walking_.cruise_on and self.cycles * self.dt < walking_.cruise_end:
            self.velocity_input, self.angular_input = walking_.cruise_velocity[0].copy(), walking_.cruise_velocity[1]
        if self.pending_parameters:
            walking_.adjust_parameter()
        if not (update or self.walker.state != _STOPPED):
            return 0, 0
        self.walker.swing_height = self.parameters["swing_height"]
        self.walker.swing_width = self.parameters["swing_width"]
        auto = self.autoposer
        walking = manipulation.manual_legs == 0
        sensing = self.sensors is not None and (self.sensors.foot_forces is not None
                                                or self.sensors.foot_contact is not None)
        self.walker.step_plane = None if self.terrain is None else walking_.step_plane(self.terrain)
        self.walker.update(self.velocity_input, self.angular_input, self.poser.walk_plane_pose.position,
                           legs_walking=walking, posing_complete=auto is None or auto.posing_complete,
                           contacts=self.posing.contacts if sensing else None, step_depth=self.parameters["step_depth"])
        if not walking:
            manipulation.update_manual_legs()
        walker_tips = self._walker_tips = self.walker.legs.tips()  # as the cycle's output will show them
        if auto is None:
            self.poser_tips = self.poser.posed_tips(walker_tips)
        else:
            self.poser_tips = self.poser.posed_tips(walker_tips, auto.body_pose, auto.leg_poses)
        if not walking:  # manipulated legs take their walker tip as it is (already in base_link)
            modes = manipulation.leg_modes
            manual = (modes == _MANUAL) | (modes == _WALKING_TO_MANUAL)
            self.poser_tips[manual] = self.walker.legs.vectors[manual, stepping.CURRENT]
        if self.failure is not None:
            self.poser_tips = self.failure.posed(self.poser_tips, walk_phase(self.walker))
        if self.admittance is not None:
            walking_.apply_admittance(self.admittance, manipulation.leg_modes)
        ik = self.robot.ik
        return self.model.step_ik(self.poser_tips, self.dt, ik.clamp_joint_positions, ik.clamp_joint_velocities,
                                  None if self.failure is None else self.failure.active())

    def stop_walking(self) -> None:
        """OpenSHC forces a stop before gait, leg-state and plan changes by zeroing the velocity inputs."""
        self.velocity_input = np.zeros(2)
        self.angular_input = 0.0

    def _output(self, deviations: int, clamped: int) -> CycleOutput:
        if self.walker is not None:
            legs = self.walker.legs
            walker_tips = legs.tips() if self._walker_tips is None else self._walker_tips
            stance = legs.floats[:, stepping.STANCE_PROGRESS].copy()
            swing = legs.floats[:, stepping.SWING_PROGRESS].copy()
            velocity = self.walker.desired_velocity()
            walk_state = self.walker.state
        else:
            walker_tips = self.identity_walker_tips.copy()
            stance = swing = np.full(len(self.stance), -1.0)
            velocity, walk_state = (0.0, 0.0, 0.0), WalkState.STOPPED
        self._walker_tips = None
        pose = self.poser.current
        roll, pitch, yaw = pose.euler()
        x, y, z = pose.position.tolist()
        # The model's arrays and the poser tips are replaced, never modified in place, each cycle: the output
        # can share them without copies.
        return CycleOutput(
            joints=self.model.joints,
            joint_velocities=self.model.joint_velocities,
            walker_tips=walker_tips,
            poser_tips=self.poser_tips,
            model_tips=self.model.tips,
            stance_progress=stance,
            swing_progress=swing,
            velocity=velocity,
            pose=(x, y, z, roll, pitch, yaw),
            robot_state=self.state,
            walk_state=walk_state,
            ik_deviations=deviations,
            ik_clamped=clamped,
        )
