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

from shc_cli.control import sequence, stepping
from shc_cli.control.admittance import AdmittanceController, tip_forces_from_efforts
from shc_cli.control.autopose import AutoPoser
from shc_cli.control.bezier import cubic
from shc_cli.control.gait import StepCycle, step_cycle
from shc_cli.control.leg_failure import LegFailure, walk_phase
from shc_cli.control.limits import Limits, generate_limits
from shc_cli.control.manipulation import MAX_MANUAL_LEGS as MAX_MANUAL_LEGS
from shc_cli.control.manipulation import LegManipulation
from shc_cli.control.odometry import LegOdometry, euler_yaw_rate
from shc_cli.control.pose import Pose, PoseController, PoseReset
from shc_cli.control.sensing import (
    ContactDetector,
    ImuPoser,
    PostureController,
    Sensors,
    inclination_pose,
    support_centroid_pose,
)
from shc_cli.control.speed_guard import SpeedGuard
from shc_cli.control.speed_shares import ShareSource
from shc_cli.control.startup import plan_direct_startup, transition_iterations
from shc_cli.control.states import LegMode as LegMode
from shc_cli.control.states import RobotState as RobotState  # re-exported: the controller's interface
from shc_cli.control.step_plane import StepPlanes, StepPlaneSettings, TerrainMap
from shc_cli.control.walk import WalkController, WalkState
from shc_cli.model import kernels
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.workspace import Workplane, plane_at, search_workspaces, volumetric_workspaces, walkspace
from shc_cli.spec.autopose import AutoPoseSet
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import ADJUSTABLE, ADJUSTABLE_ADMITTANCE, ADJUSTABLE_WALKER, Perception, Robot

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



_OFF_TARGET = tuple(int(not flags & 1) for flags in range(8))
"""Per IK flags value (bit 0 on target, bits 1–2 a position or a velocity clamped): 1 if the leg missed its target."""
_CLAMPED = tuple(int(flags & 6 != 0) for flags in range(8))
"""Per IK flags value: 1 if a joint of the leg was clamped."""
_SPEED_CLAMPED = tuple(int(flags & 4 != 0) for flags in range(8))
"""Per IK flags value: 1 if the IK clamped a joint of the leg to its speed limit (``clamp_joint_velocities``)."""

# Enum members bound once: attribute access on an Enum class is slow, and these are read every cycle.
_UNKNOWN, _RUNNING = RobotState.UNKNOWN, RobotState.RUNNING
_STOPPED = WalkState.STOPPED
_WALKING_LEG = int(LegMode.WALKING)
_IMMEDIATE_ALL = PoseReset.IMMEDIATE_ALL


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


@dataclass
class _Transition:
    """A joint-space transition in progress (cubic Bézier from ``origin`` to ``target``)."""

    origin: FloatArray
    target: FloatArray
    count: int = 0
    steps: int = 1


@dataclass
class Model:
    """The robot model the controller drives: desired joints and the tips they put the legs at."""

    chains: Chains
    joints: FloatArray
    joint_velocities: FloatArray
    avoidance_cap: float = 0.0
    """``ik.limit_avoidance_cap`` (0: OpenSHC's IK step, :func:`~shc_cli.model.kernels.ik_step_one`)."""
    tips: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        self.tips = self.chains.tips(self.joints)
        self._flags = np.zeros(self.chains.size, dtype=np.int64)
        self._frames = np.empty((self.chains.size, self.chains.d.shape[1] + 1, 4, 4))
        self._frames_q = np.full(self.chains.d.shape, np.nan)
        """Each leg's frames of the joints ``_frames_q`` (:func:`~shc_cli.model.kernels.ik_step_frames_kernel`)."""
        self._proximity = np.ones(self.chains.size)
        self._last_targets: FloatArray | None = None
        """The tip targets of the last IK step (how far each target moved feeds ``avoidance_cap``'s blend)."""
        self._no_motion = np.zeros(self.chains.size)
        self._flags[:] = 1
        self.guard: SpeedGuard | None = None
        """The joint speed guard, once :meth:`start_cycle` has been given the control period."""

    def start_cycle(self, dt: float) -> FloatArray:
        """Begin a control cycle: returns the joints it starts from (the last command), for :meth:`limit_speed`."""
        if self.guard is None or self.guard.dt != dt:
            self.guard = SpeedGuard(self.chains, dt)
        self.guard.limited[:] = 0
        return self.joints

    def limit_speed(self, before: FloatArray) -> int:
        """The last step of every cycle (:mod:`shc_cli.control.speed_guard`): no joint moves further than
        ``max_vel·dt`` from ``before``; returns the legs whose joint speed was limited this cycle (by the guard or by
        the IK's velocity clamp)."""
        assert self.guard is not None
        limited = self.guard.apply(before, self.joints, self.joint_velocities)
        if limited is not None:
            self.joints, self.joint_velocities, self.tips = limited
        return int(self.guard.limited.sum())

    def step_ik(self, targets: FloatArray, dt: float, clamp_positions: bool, clamp_velocities: bool,
                active: np.ndarray | None = None) -> tuple[int, int]:
        """One OpenSHC IK step of every leg (or of the ``active`` legs) towards ``targets`` (base_link) [m].

        The step of :func:`shc_cli.model.ik.ik_step`, called directly on the model's own arrays (no input copies, no
        :class:`~shc_cli.model.ik.StepResult`): this is the per-cycle hot path, ≈ 8 µs against ≈ 12 µs for
        ``ik_step`` on 6 legs, so it does not go through that wrapper; and each leg's frames of its last result are
        kept, which its next step starts from (:func:`~shc_cli.model.kernels.ik_step_frames_kernel`). Legs not active
        keep their joints, velocities and tips. Returns (legs off target by > 5 mm, legs with a clamped joint);
        :attr:`proximity` then holds OpenSHC's ``applyIK`` result per leg.
        """
        c = self.chains
        joints, velocities, tips = np.empty_like(self.joints), np.empty_like(self.joints), np.empty_like(self.tips)
        last = self._last_targets
        motion = self._no_motion if last is None else np.sqrt(((targets - last) ** 2).sum(axis=1))
        self._last_targets = np.array(targets, dtype=float)
        kernels.ik_step_frames_kernel(c.base, c.d, c.theta, c.r, c.alpha, c.lower, c.upper, c.max_vel, self.joints,
                                      self.joint_velocities, self.tips, targets, dt, clamp_positions,
                                      clamp_velocities, joints, velocities, tips, self._flags, self._proximity,
                                      self._frames, self._frames_q, motion, 1.0, self.avoidance_cap)
        flags = self._flags.tolist()
        if active is not None:
            keep = ~np.asarray(active, dtype=bool)
            joints[keep], velocities[keep], tips[keep] = self.joints[keep], self.joint_velocities[keep], self.tips[keep]
            flags = [1 if kept else f for kept, f in zip(keep.tolist(), flags, strict=True)]
        self.joints, self.joint_velocities, self.tips = joints, velocities, tips
        if clamp_velocities and self.guard is not None:
            self.guard.clamped_by_ik(np.fromiter(map(_SPEED_CLAMPED.__getitem__, flags), np.int64, len(flags)))
        return sum(map(_OFF_TARGET.__getitem__, flags)), sum(map(_CLAMPED.__getitem__, flags))

    @property
    def proximity(self) -> FloatArray:
        """OpenSHC's ``applyIK`` result of the last step per leg: limit proximity, or 0 if the tip missed its
        target by more than 5 mm on an axis."""
        return np.where((self._flags & 1) != 0, self._proximity, 0.0)


class Controller(LegManipulation):
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
        self._walking_cycles = 0
        self.speed_shares = speed_shares
        """Shares of OpenSHC's speed limits per gait (a run gives :func:`shc_cli.control.verified_limits.source_for`
        of its robot); None: OpenSHC's (also with a failed leg: the limits are the walking legs' walkspace)."""
        if self.speed_shares is not None:
            self.speed_shares(gait)  # verified now, before a loop runs (another gait: when it is first chosen)
        self.direct_shutdown = direct_shutdown
        self.pose_sets = pose_sets or {}
        self.openshc_double_shutdown = openshc_double_shutdown
        self._packer: sequence.PackTransition | None = None
        self._sequence: sequence.Sequence | None = None
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
        self._transition: _Transition | None = None
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
        self.leg_modes = np.full(len(robot.legs), int(LegMode.WALKING))
        self._manual_legs = 0
        """Legs not in WALKING mode (kept with :attr:`leg_modes`)."""
        self.pending_toggle: int | None = None
        self.tip_velocities: dict[int, np.ndarray] = {}
        self.tip_positions: dict[int, np.ndarray] = {}
        self._manipulator = sequence.StepToPosition(len(robot.legs), self.dt)
        self._forced_pose_reset = False
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
        self.cruise_on = False
        self.cruise_velocity = (np.zeros(2), 0.0)
        self.cruise_end = math.inf
        walker_spec, admittance = robot.walker, robot.admittance
        self.sensors: Sensors | None = None
        pose_spec, posture_spec = robot.pose, robot.posture
        self.imu_poser = ImuPoser((pose_spec.rotation_pid_gains.p, pose_spec.rotation_pid_gains.i,
                                   pose_spec.rotation_pid_gains.d),
                                  (pose_spec.max_rotation.roll, pose_spec.max_rotation.pitch), self.dt) \
            if pose_spec.imu else None
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
        self._step_planes: StepPlanes | None = None
        self.contact_detector = ContactDetector(len(robot.legs), adm.touchdown_threshold, adm.liftoff_threshold)
        self.contacts = np.zeros(len(robot.legs), dtype=bool)
        """Feet on the ground by the force thresholds (touchdown/lift-off), updated when sensors report forces."""
        self.parameters = {name: getattr(walker_spec, name).default for name in ADJUSTABLE_WALKER}
        self.parameters.update({name: getattr(admittance, name).default for name in ADJUSTABLE_ADMITTANCE})
        self.odometry = LegOdometry(self.dt)
        """Leg odometry (an shc addition): read by :attr:`CycleOutput.odometry`."""
        self._stance_before = np.zeros(len(robot.legs), dtype=bool)
        self._walker_tips: FloatArray | None = None
        """This cycle's walker tips (a copy) once the running cycle has posed them: the output shows the same."""
        self._measured_feet = np.empty((len(robot.legs), 3))
        """The feet of the measured joints [m] (the odometry reads them; it keeps only its levelled copy)."""

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
                self._set_cruise(command.cruise)
            if command.leg_toggle is not None or command.tip_velocity or command.tip_position or self.tip_velocities \
                    or self.tip_positions:
                self._receive_manipulation(command)
        if command.state_request is not None and not self.transition_pending:
            self.requested = command.state_request
            if self.state == _UNKNOWN or command.state_request != self.state:
                self.transition_pending = True

    # -- the cycle ---------------------------------------------------------------------------------------------

    def _set_cruise(self, on: bool) -> None:
        """Cruise control (study §6): hold the configured (or the current) velocity, optionally for a time."""
        if on and not self.cruise_on:
            cruise, scaler = self.robot.cruise, self.robot.walker.body_velocity_scaler
            if cruise.force_velocity:
                self.cruise_velocity = (np.array(cruise.linear, dtype=float) * scaler, cruise.angular * scaler)
            else:
                self.cruise_velocity = (self.velocity_input.copy(), self.angular_input)
            limit = cruise.time_limit
            self.cruise_end = self.cycles * self.dt + limit if limit > 0.0 else math.inf
        self.cruise_on = on

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
            self._update_pose()
        deviations = clamped = 0
        if self.transition_pending and self.state != _RUNNING:
            self._transition_state()  # in RUNNING the running cycle handles it first (study §9.4)
        if self.state == _RUNNING:
            deviations, clamped = self._running()
        if self.scheduled_failure is not None:
            self._schedule_failure(self.scheduled_failure)
        if self.failure is not None:
            self._hold_failed(self.failure)
        limited = self.model.limit_speed(before)
        if limited:
            self.joint_speed_limited_cycles += 1
        out = self._output(deviations, clamped)
        out.joint_speed_limited = limited
        out.odometry = self._update_odometry(sensors, out.stance_progress >= 0.0)
        return out

    def _update_odometry(self, sensors: Sensors | None, stance: np.ndarray) -> tuple[float, float, float]:
        """One cycle of leg odometry (:mod:`shc_cli.control.odometry`).

        Measured joints (``sensors.joints``) are the feet at the start of this cycle: the motion since the last
        reading is the previous cycle's, so the feet in stance then are used; commanded joints are this cycle's
        targets, used with this cycle's stance. Foot contact, where measured, must hold at both readings; measured
        foot forces weigh the feet. Roll and pitch come from the IMU or else the commanded body pose; the IMU's
        heading change (of its orientation; of its angular rate × dt without one) is fused.
        """
        if sensors is None:
            self._stance_before = stance
            roll, pitch, _ = self.poser.current.euler()
            return self.odometry.cycle(self.model.tips, roll, pitch, stance)
        if sensors.joints is not None:  # Chains.tips's kernel, into a buffer of the odometry's
            c, feet = self.model.chains, self._measured_feet
            kernels.tips_kernel(c.base, c.d, c.theta, c.r, c.alpha, np.ascontiguousarray(sensors.joints, dtype=float),
                                feet)
            use = self._stance_before
        else:
            feet, use = self.model.tips, stance
        self._stance_before = stance
        orientation, turn, roll, pitch = sensors.orientation, None, 0.0, 0.0
        if orientation is None:
            roll, pitch, _ = self.poser.current.euler()
            if sensors.angular_rate is not None:
                turn = euler_yaw_rate(roll, pitch, np.asarray(sensors.angular_rate, dtype=float)) * self.dt
        commanded = self.walker.desired_angular if self.walker is not None else 0.0
        return self.odometry.cycle(feet, roll, pitch, use, turn, sensors.foot_forces, orientation,
                                   sensors.foot_contact, commanded)

    def _update_pose(self) -> None:
        """The body pose of this cycle, from the previous cycle's leg states (OpenSHC ``updateCurrentPose``)."""
        if self.walker is None:
            progress, planes, normals = np.empty(0), np.empty((0, 3)), np.empty((0, 3))
        else:
            legs = self.walker.legs
            progress = legs.floats[:, stepping.SWING_PROGRESS]
            planes, normals = legs.vectors[:, stepping.PLANE], legs.vectors[:, stepping.NORMAL]
        if self.state == _RUNNING:
            reset = _IMMEDIATE_ALL if self._forced_pose_reset else self.pose_reset
            self.poser.update_manual(self.pose_input, reset)
        auto = None
        if self.autoposer is not None:
            self._update_auto_pose(self.autoposer)
            auto = self.autoposer.body_pose
        feedback: tuple[Pose | None, ...] = ()
        if self.uses_sensors:
            auto, feedback = self._feedback_poses(auto)
        self.poser.update_current_pose(progress, self.gait.swing_phase, self.gait.phase_offset, planes, normals,
                                       auto, feedback)

    def _feedback_poses(self, auto: Pose | None) -> tuple[Pose | None, tuple[Pose | None, ...]]:
        """The sensor-driven pose terms of this cycle: ATHENA posture, inclination, IMU (replacing auto)."""
        sensors = self.sensors or Sensors()
        spec = self.robot.pose
        posture = None
        if sensors.foot_forces is not None:
            self.contacts = self.contact_detector.update(sensors.foot_forces)
        elif sensors.foot_contact is not None:
            self.contacts = np.asarray(sensors.foot_contact, dtype=bool)
        if self.posture is not None:
            walking = self.state == _RUNNING and self.walker is not None and self.walker.state != _STOPPED
            feet = self.model.chains.tips(sensors.joints) if sensors.joints is not None else self.model.tips
            contacts = self.contacts if sensors.foot_forces is not None or sensors.foot_contact is not None else None
            posture = self.posture.update(walking, feet, contacts, sensors.body_height)
        manual = self.poser.manual_pose() if self.poser.manual_enabled else Pose()
        inclination = None
        if spec.inclination and sensors.orientation is not None:
            limits = (spec.max_translation.x, spec.max_translation.y)
            clearance = self.robot.walker.body_clearance
            if spec.inclination_mode == "openshc":
                intended = manual.add(auto) if auto is not None else manual
                inclination = inclination_pose(sensors.orientation, intended, clearance, limits)
            elif self.walker is not None:
                stance = self.walker.legs.floats[:, stepping.STANCE_PROGRESS] >= 0.0
                tips = self.walker.legs.vectors[stance, stepping.CURRENT]
                inclination = support_centroid_pose(sensors.orientation, tips, np.asarray(self.robot.body.com),
                                                     clearance, limits)
        if spec.imu and self.state == _RUNNING and sensors.orientation is not None \
                and sensors.angular_rate is not None:
            assert self.imu_poser is not None
            auto = self.imu_poser.update(sensors.orientation, sensors.angular_rate, manual)
        return auto, (posture, inclination)

    def _update_auto_pose(self, autoposer: AutoPoser) -> None:
        legs = len(self.stance)
        if self.walker is None:
            autoposer.update(int(WalkState.STOPPED), True, np.zeros(legs, dtype=np.int64),
                             np.full(legs, stepping.FORCE_STOP))
            return
        arrays = self.walker.legs
        stride = arrays.vectors[autoposer.reference_leg, stepping.STRIDE]
        autoposer.update(int(self.walker.state), not np.any(stride), arrays.integers[:, stepping.PHASE],
                         arrays.integers[:, stepping.STATE])

    def _transition_state(self) -> None:
        """Move one state towards the request (study §9.2): direct start-up, or OpenSHC's sequence mode
        (pack/unpack in joint space, stepped start-up and shut-down, :mod:`shc_cli.control.sequence`)."""
        if self.state == RobotState.UNKNOWN:
            packed, unpacked = self._configurations
            last = packed[-1] if len(packed) else unpacked
            estimate = sequence.estimate_state(self.model.joints, last, unpacked, self.robot.start_up.sequence)
            self.state = RobotState.READY if estimate.ready else RobotState.PACKED
            self.transition_pending = False
            return
        target = self.state + (1 if self.requested > self.state else -1)
        done = False
        if self.state == RobotState.PACKED and target == RobotState.READY:
            if not self.robot.start_up.sequence:
                if self._direct_move(None):
                    self.default_joints = self.model.joints.copy()
                    self._generate_limits()
                    done = True
            else:
                done = self._pack(sequence.PackDirection.UNPACK)
        elif self.state == RobotState.READY and target == RobotState.PACKED and self.robot.start_up.sequence:
            done = self._pack(sequence.PackDirection.PACK)
        elif self.state == RobotState.READY and target == RobotState.RUNNING:
            done = not self.robot.start_up.sequence or self._run_sequence(sequence.SequenceKind.START_UP)
            if done and self.robot.start_up.sequence:
                self.walker = None  # leg steppers re-created at the identity tips, as OpenSHC's walker init
                self.default_joints = self.model.joints.copy()
                self._generate_limits()
        elif self.state == RobotState.RUNNING and target == RobotState.READY and (
                self.robot.start_up.sequence or self.direct_shutdown):
            if self.walker is not None and self.walker.state != WalkState.STOPPED:
                self._stop_walking()
            else:
                done = not self.robot.start_up.sequence or self._run_sequence(sequence.SequenceKind.SHUT_DOWN)
        elif self.state == RobotState.READY and target == RobotState.PACKED and self.direct_shutdown:
            done = self._direct_move(self.rest_joints)
            if done:
                self.walker = None  # the next start-up begins at the identity tips, as the first one
        else:
            self.transition_pending = False  # refused: direct mode only goes PACKED → READY → RUNNING
            return
        if done:
            self.state = RobotState(target)
            if self.state == self.requested:
                self.transition_pending = False

    @property
    def _configurations(self) -> tuple[FloatArray, FloatArray]:
        return sequence.joint_configurations(self.robot, self.model.chains.joints)

    def _pack(self, direction: sequence.PackDirection) -> bool:
        """One cycle of packing or unpacking in joint space; True when the last configuration is reached."""
        if self._packer is None:
            self._packer = sequence.PackTransition(*self._configurations, self.dt)
        step = self._packer.step(direction, self.model.joints, self.parameters["step_frequency"])
        self.model.joints = step.joints
        self.model.tips = self.model.chains.tips(self.model.joints)
        return step.progress == sequence.PROGRESS_COMPLETE

    def _run_sequence(self, kind: sequence.SequenceKind) -> bool:
        """Iterations of the start-up or shut-down sequence for this cycle; True when complete.

        OpenSHC advances the shut-down two iterations per cycle (study §14 quirk 8: the transition handler runs
        twice in RUNNING); shc runs one, unless ``openshc_double_shutdown`` asks for OpenSHC's behaviour.
        """
        if self._sequence is None:
            self._sequence = sequence.Sequence(len(self.stance), self.dt)
        repeats = 2 if kind is sequence.SequenceKind.SHUT_DOWN and self.openshc_double_shutdown else 1
        for _ in range(repeats):
            defaults = (self.walker.legs.vectors[:, stepping.DEFAULT] if self.walker is not None
                        else self.identity_walker_tips)
            plan = self._sequence.begin(kind, self.model.tips, self.poser.current.inverse_transform(defaults),
                                        self.parameters["step_frequency"], self.parameters["swing_height"])
            ik = self.robot.ik
            self.model.step_ik(plan.targets, self.dt, ik.clamp_joint_positions, ik.clamp_joint_velocities,
                               active=plan.active)
            self.poser_tips = np.where(plan.active[:, None], plan.targets, self.poser_tips)
            if self._sequence.finish(self.model.proximity) == sequence.PROGRESS_COMPLETE:
                return True
        return False

    def _direct_move(self, target: FloatArray | None) -> bool:
        """Move in joint space to ``target`` over ``time_to_start`` — or, with ``None``, the direct start-up: plan
        the stance by IK on the first cycle, then move there; True when done."""
        if self._transition is None:
            if target is None:
                target = plan_direct_startup(self.robot, self.model.chains, self.default_joints)
            steps = transition_iterations(self.model.joints, target, self.model.chains.max_vel,
                                          self.robot.start_up.time_to_start, self.dt)
            self._transition = _Transition(self.model.joints.copy(), target, 0, steps)
        move = self._transition
        move.count += 1
        nodes = np.stack([move.origin, move.origin, move.target, move.target])
        self.model.joints = cubic(nodes, move.count * (1.0 / move.steps))
        self.model.tips = self.model.chains.tips(self.model.joints)
        if move.count >= move.steps:
            self._transition = None
            return True
        return False

    def _generate_limits(self) -> None:
        """Workspaces, walkspace and limits from the default configuration; (re)create the walker."""
        clearance = self.robot.walker.body_clearance
        identity = np.array([[x, y, -clearance] for x, y in self.stance.values()])
        if self.robot.walker.rough_terrain_mode:  # OpenSHC: the volumetric workspace, its layer at the stance
            layers = volumetric_workspaces(self.model.chains, self.default_joints, identity, self.dt)
            self.planes = {leg: plane_at(stack, 0.0) for leg, stack in layers.items()}
        else:
            self.planes = search_workspaces(self.model.chains, self.default_joints, identity, self.dt).planes
        planes = self.planes if self.failure is None else self.failure.walking(self.planes)
        self.walkspace = walkspace(planes, self.stance, self.robot.walker.overlapping_walkspaces)
        limits = self._limits_for(self.cycle)
        walker_spec = self.robot.walker
        if self.walker is None:
            self.walker = WalkController(self.stance, self.cycle, limits, self.dt, walker_spec.swing_height.default,
                                         walker_spec.swing_width.default, walker_spec.velocity_input_mode,
                                         walker_spec.rough_terrain_mode)
        else:
            self.walker.set_cycle(self.cycle, limits)

    def declare_failure(self, failure: LegFailure) -> None:
        """Failed legs from this cycle on (a detected fault): held at once (``locked``: where they are), the
        re-planned gait requested as a gait change (the walker stops, then walks on it)."""
        failure.at_s = 0.0
        self.failure = self.scheduled_failure = failure

    def _schedule_failure(self, failure: LegFailure) -> None:
        """Count walking cycles; at the failure's time request its re-planned gait (:meth:`_change_gait` then
        installs the failure)."""
        if self.state == _RUNNING and self.walker is not None and (self._walking_cycles
                                                                  or self.walker.state != _STOPPED):
            self._walking_cycles += 1
        assert failure.at_s is not None and failure.gait is not None
        due = self._walking_cycles * self.dt >= failure.at_s
        if due and self.pending_gait is None and self.gait is not failure.gait:
            self.pending_gait = failure.gait

    def _install_failure(self, failure: LegFailure) -> None:
        """The declared failure from now on: the walking legs' walkspace and OpenSHC's limits of it."""
        self.failure, self.scheduled_failure, self.speed_shares = failure, None, None
        self.walkspace = walkspace(failure.walking(self.planes), self.stance, self.robot.walker.overlapping_walkspaces)

    def _hold_failed(self, failure: LegFailure) -> None:
        """Failed legs back at their held pose (before the joint speed guard, which paces the first move)."""
        held = failure.hold(self.model.joints, self.state == _RUNNING)
        if held is not None:
            velocities = self.model.joint_velocities.copy()
            velocities[failure.index] = 0.0
            tips = self.model.tips.copy()
            tips[failure.index] = failure.tips(held)
            self.model.joints, self.model.joint_velocities, self.model.tips = held, velocities, tips

    def _running(self) -> tuple[int, int]:
        """One RUNNING cycle (study §9.4): gait change, cruise control, parameter changes, then walk, pose
        the tips and one IK step per leg — unless the cycle was spent on a change while stopped."""
        assert self.walker is not None
        update = True
        if self.transition_pending:
            self._transition_state()
            if self.state != _RUNNING or self.walker is None:
                return 0, 0
            update = False
        elif self.pending_gait is not None:
            self._change_gait()
            update = False
        elif self.pending_toggle is not None:
            self._toggle_leg(self.pending_toggle)
            update = False
        elif self.cruise_on and self.cycles * self.dt < self.cruise_end:
            self.velocity_input, self.angular_input = self.cruise_velocity[0].copy(), self.cruise_velocity[1]
        if self.pending_parameters:
            self._adjust_parameter()
        if not (update or self.walker.state != _STOPPED):
            return 0, 0
        self.walker.swing_height = self.parameters["swing_height"]
        self.walker.swing_width = self.parameters["swing_width"]
        auto = self.autoposer
        walking = self._manual_legs == 0
        sensing = self.sensors is not None and (self.sensors.foot_forces is not None
                                                or self.sensors.foot_contact is not None)
        self.walker.step_plane = None if self.terrain is None else self._step_plane(self.terrain)
        self.walker.update(self.velocity_input, self.angular_input, self.poser.walk_plane_pose.position,
                           legs_walking=walking, posing_complete=auto is None or auto.posing_complete,
                           contacts=self.contacts if sensing else None, step_depth=self.parameters["step_depth"])
        if not walking:
            self._update_manual_legs()
        walker_tips = self._walker_tips = self.walker.legs.tips()  # as the cycle's output will show them
        if auto is None:
            self.poser_tips = self.poser.posed_tips(walker_tips)
        else:
            self.poser_tips = self.poser.posed_tips(walker_tips, auto.body_pose, auto.leg_poses)
        if not walking:  # manipulated legs take their walker tip as it is (already in base_link)
            manual = (self.leg_modes == LegMode.MANUAL) | (self.leg_modes == LegMode.WALKING_TO_MANUAL)
            self.poser_tips[manual] = self.walker.legs.vectors[manual, stepping.CURRENT]
        if self.failure is not None:
            self.poser_tips = self.failure.posed(self.poser_tips, walk_phase(self.walker))
        if self.admittance is not None:
            self._apply_admittance(self.admittance)
        ik = self.robot.ik
        return self.model.step_ik(self.poser_tips, self.dt, ik.clamp_joint_positions, ik.clamp_joint_velocities,
                                  None if self.failure is None else self.failure.active())

    def _step_plane(self, terrain: TerrainMap) -> tuple[FloatArray, FloatArray]:
        """This cycle's step-plane input from the map (:mod:`shc_cli.control.step_plane`)."""
        assert self.walker is not None
        if self._step_planes is None:
            spec = self.robot.perception or Perception()
            self._step_planes = StepPlanes(len(self.stance), StepPlaneSettings(
                spec.edge_margin, spec.edge_step, spec.max_shift, spec.clearance_margin, spec.max_clearance,
                spec.max_slope, self.robot.body.size[0], self.robot.body.size[1], spec.lookahead))
            self.walker.max_plane_slope, self.walker.floor_deadband = spec.max_slope, spec.edge_step
        legs, cycle, walk = self.walker.legs, self.walker.cycle, self.walker.desired_velocity()
        pose = self.poser.current
        planes = self._step_planes
        self.walker.body_floor = planes.body_floor  # (the last cycle's: the walk plane is fitted after the legs)
        vectors = legs.vectors
        return planes.update(terrain, vectors[:, stepping.DEFAULT] + 0.5 * vectors[:, stepping.STRIDE],
                             vectors[:, stepping.CURRENT], pose.position, pose.rotation,
                             legs.floats[:, stepping.SWING_PROGRESS], self.parameters["swing_height"], walk[:2],
                             cycle.swing_period / cycle.period / cycle.frequency)

    def _apply_admittance(self, admittance: AdmittanceController) -> None:
        """Raise each walking leg's tip target by its admittance offset (paper eq. 20, z_d = z_r − Δz)."""
        assert self.walker is not None
        sensors = self.sensors or Sensors()
        spec = self.robot.admittance
        if spec.use_joint_effort and sensors.joint_efforts is not None:
            joints = sensors.joints if sensors.joints is not None else self.model.joints
            chains = self.model.chains
            leg_forces = tip_forces_from_efforts(chains.jacobians(joints), sensors.joint_efforts)
            # τ_motor = −Jᵀ·G holds a ground force G on the foot: G = −F, in base_link through the leg frames.
            force_z = -np.einsum("lj,lj->l", chains.base[:, 2, :3], leg_forces)
        elif sensors.foot_forces is not None:
            force_z = np.asarray(sensors.foot_forces, dtype=float)
        else:
            force_z = np.zeros(len(self.stance))
        legs = self.walker.legs
        swinging = legs.floats[:, stepping.SWING_PROGRESS] >= 0.0
        height = max(self.parameters["swing_height"], 1e-6)
        reach = np.where(swinging, np.clip(np.abs(legs.vectors[:, stepping.CURRENT, 2]
                                                  - legs.vectors[:, stepping.DEFAULT, 2]) / height, 0.0, 1.0), -1.0)
        admittance.mass = self.parameters["virtual_mass"]
        admittance.stiffness = self.parameters["virtual_stiffness"]
        admittance.damping_ratio = self.parameters["virtual_damping_ratio"]
        admittance.force_gain = self.parameters["force_gain"]
        delta = admittance.update(force_z, reach, self.walker.state != _STOPPED)
        walking = self.leg_modes == _WALKING_LEG
        self.poser_tips = self.poser_tips.copy()
        self.poser_tips[walking, 2] += delta[walking]

    def _stop_walking(self) -> None:
        """OpenSHC forces a stop before gait, leg-state and plan changes by zeroing the velocity inputs."""
        self.velocity_input = np.zeros(2)
        self.angular_input = 0.0

    def _change_gait(self) -> None:
        """Switch gait once stopped: new step cycle, limits and offsets (study §4.3); bipod included."""
        assert self.walker is not None and self.pending_gait is not None
        if self.walker.state != WalkState.STOPPED:
            self._stop_walking()
            return
        self.gait = self.pending_gait
        self.pending_gait = None
        if self.scheduled_failure is not None and self.gait is self.scheduled_failure.gait:
            self._install_failure(self.scheduled_failure)
        self.cycle = step_cycle(self.gait, self.parameters["step_frequency"], self.dt)
        self.walker.set_cycle(self.cycle, self._limits_for(self.cycle))
        self._reset_auto_pose()
        if self.posture is not None:
            self.posture.period = max(self.cycle.period, 2)

    def _reset_auto_pose(self) -> None:
        """New step cycle or gait: re-synchronise auto posing (OpenSHC does this on gait changes only; doing
        it on step-frequency changes too fixes study §14 quirk 18)."""
        if not self.robot.pose.auto:
            return
        pose_set = self.pose_sets.get(self.gait.name)
        if self.autoposer is not None:
            self.autoposer.reset(self.cycle, self.gait, pose_set)
        elif pose_set is not None:
            self.autoposer = AutoPoser(pose_set, self.gait, self.cycle, list(self.robot.legs), self.dt)

    def _limits_for(self, cycle: StepCycle) -> Limits:
        """Limits for ``cycle``; the angular lever arm is leg 0's current default tip, re-read every time."""
        first = self.walker.legs.vectors[0, stepping.DEFAULT] if self.walker else self.identity_walker_tips[0]
        limits = generate_limits(self.walkspace, cycle, self.dt, math.hypot(first[0], first[1]))
        return limits if self.speed_shares is None else self.speed_shares(self.gait).apply(limits)

    def _adjust_parameter(self) -> None:
        """Apply the first pending parameter change (study §9.6). A new step frequency waits until the
        walker has slowed to within the new speed limits, then re-phases the legs."""
        assert self.walker is not None
        name, value = self.pending_parameters[0]
        spec = getattr(self.robot.walker, name, None) or getattr(self.robot.admittance, name)
        value = min(max(value, spec.min), spec.max)
        if name == "step_frequency":
            cycle = step_cycle(self.gait, value, self.dt)
            limits = self._limits_for(cycle)
            self.walker.install_speed_limits(limits)
            if not self.walker.within_limits_for(limits, self.velocity_input, self.angular_input):
                return  # slow down to a safe speed first
            self.cycle = cycle
            self.walker.set_cycle(cycle, limits, rephase=True)
            self._reset_auto_pose()
            if self.posture is not None:
                self.posture.period = max(self.cycle.period, 2)
        elif name == "stance_span_modifier":
            self._set_stance_span(value)
        self.parameters[name] = value
        self.pending_parameters.pop(0)

    def _set_stance_span(self, modifier: float) -> None:
        """Widen (+) or narrow (−) the stance by a share of each leg's lateral workspace radius (study §5.5);
        it takes effect when the legs next return to their defaults (a stop)."""
        assert self.walker is not None
        span = []
        for leg, (_, y) in self.stance.items():
            left = y > 0.0
            radius = self.planes[leg][90 if left else 270]
            span.append(radius * modifier * (1.0 if left else -1.0))
        self.walker.legs.floats[:, stepping.SPAN_CHANGE] = span

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
