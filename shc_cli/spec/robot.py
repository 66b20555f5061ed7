"""The robot description: pydantic models of a fully expanded robot file, in SI units.

A robot file (TOML) may use ``extends``, ``[templates.*]`` and ``mirror = "AR"``; those are
resolved by :mod:`shc_cli.spec.loading` before validation, so these models always describe what
the controller sees. Field names follow OpenSHC where one exists (study §11.1); the OpenSHC
parameter name is given in each description as ``[OpenSHC: name]``.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

MAX_JOINTS = 6
MIN_JOINTS = 1


class Strict(BaseModel):
    """Base of every spec model: unknown keys are errors, numbers stay numbers.

    Strict: a quoted ``"0.25"`` is not a number, ``"true"`` or ``1`` is not a boolean and ``true`` is not
    a number (an integer is still a valid float). Every float must be finite. Fixed-length lists are
    declared ``tuple[...]`` with ``strict=False`` on the field, since TOML arrays arrive as lists; their
    items stay strict.
    """

    model_config = ConfigDict(
        extra="forbid", frozen=True, strict=True, allow_inf_nan=False, validate_default=True
    )


Metres = Annotated[float, Field(allow_inf_nan=False)]
Radians = Annotated[float, Field(allow_inf_nan=False)]
Positive = Annotated[float, Field(gt=0, allow_inf_nan=False)]
NonNegative = Annotated[float, Field(ge=0, allow_inf_nan=False)]


class DH(Strict):
    """Classical (distal) Denavit–Hartenberg link: ``Rot_z(theta)·Trans_z(d)·Trans_x(r)·Rot_x(alpha)``."""

    d: Metres = Field(0.0, description="offset along the previous z axis [m]")
    theta: Radians = Field(0.0, description="constant angle about the previous z axis, added to the joint angle [rad]")
    r: Metres = Field(0.0, description="link length along the new x axis (DH a) [m]")
    alpha: Radians = Field(0.0, description="twist about the new x axis [rad]")


class Joint(DH):
    """One revolute joint and the DH link it moves (OpenSHC ``<LEG>_<joint>_joint_parameters`` + link)."""

    min: Radians = Field(description="lower position limit [rad]")
    max: Radians = Field(description="upper position limit [rad]")
    offset: Radians = Field(0.0, description="servo zero offset added to commands sent to hardware [rad]")
    packed: list[Radians] = Field(
        default_factory=list,
        description="packed configurations in order (OpenSHC packed_0, packed_1, ...); the last one is 'packed' [rad]",
    )
    unpacked: Radians = Field(0.0, description="the READY (unpacked) position [rad]")
    max_vel: Positive = Field(5.0, description="joint speed limit [rad/s]")
    mass: NonNegative | None = Field(None, description="mass of the link this joint moves [kg] (simulation)")

    @model_validator(mode="after")
    def _limits_ordered(self) -> Joint:
        if self.min >= self.max:
            raise ValueError(f"min ({self.min:g}) must be less than max ({self.max:g}); swap the two values")
        return self


class StanceXY(Strict):
    """Identity (default) tip position in the walk plane, z = 0 [OpenSHC: <LEG>_stance_position]."""

    x: Metres = Field(description="forward [m]")
    y: Metres = Field(description="left [m]")


class Leg(Strict):
    """One leg: the fixed base link, its joints from body to tip, and its stance position."""

    base: DH = Field(description="constant transform from base_link to the first joint's frame [OpenSHC: base link]")
    joints: dict[str, Joint] = Field(description="joints from body to tip, in order; 1 to 6 of them")
    stance: StanceXY = Field(description="default tip position in the walk plane [m]")
    foot_radius: NonNegative = Field(0.0, description="radius of the spherical foot at the tip [m] (simulation)")

    @field_validator("joints")
    @classmethod
    def _joint_count(cls, joints: dict[str, Joint]) -> dict[str, Joint]:
        """On the field, so the error points at the joints table (often a template's) and not the leg."""
        if not MIN_JOINTS <= len(joints) <= MAX_JOINTS:
            raise ValueError(f"a leg needs {MIN_JOINTS} to {MAX_JOINTS} joints, this one has {len(joints)}")
        return joints


class Adjustable(Strict):
    """A run-time adjustable parameter ``{default, min, max, step}`` (OpenSHC dynamic parameters)."""

    default: float = Field(description="value at start-up")
    min: float = Field(description="lowest value reachable at run time")
    max: float = Field(description="highest value reachable at run time")
    step: NonNegative = Field(description="increment of one adjustment")

    @model_validator(mode="after")
    def _default_inside(self) -> Adjustable:
        if self.min > self.max:
            raise ValueError(f"min ({self.min:g}) must not exceed max ({self.max:g})")
        if not self.min <= self.default <= self.max:
            raise ValueError(f"default ({self.default:g}) must lie in [min, max] = [{self.min:g}, {self.max:g}]")
        return self


def _adj(default: float, lo: float, hi: float, step: float) -> Adjustable:
    return Adjustable(default=default, min=lo, max=hi, step=step)


class Body(Strict):
    """The body (torso) as a box; its origin is base_link."""

    size: tuple[Positive, Positive, Positive] = Field(
        (0.3, 0.2, 0.05), strict=False, description="box length x, width y, height z [m]"
    )
    mass: Positive = Field(1.0, description="body mass without legs [kg]")
    com: tuple[Metres, Metres, Metres] = Field(
        (0.0, 0.0, 0.0), strict=False, description="centre of mass in base_link [m]"
    )
    inertia: tuple[NonNegative, NonNegative, NonNegative] | None = Field(
        None,
        strict=False,
        description="principal moments ixx, iyy, izz about the COM [kg·m²]; derived from the box if absent",
    )


class StoredShares(Strict):
    """Speed-limit shares a robot file keeps for one gait (:mod:`shc_cli.control.verified_limits`)."""

    linear: dict[str, Annotated[float, Field(gt=0.0, le=1.0)]] = Field(
        description="walkspace bearing [deg, as text: \"0\", \"45\", …] → share of its linear speed limit [ratio]")
    turn: Annotated[float, Field(gt=0.0, le=1.0)] = Field(description="share of the angular speed limit [ratio]")
    fingerprint: str = Field(description="hash of the robot and gait the shares were verified for (a robot or gait "
                                         "edited since: the shares are not used)")

    @field_validator("linear")
    @classmethod
    def _bearings(cls, linear: dict[str, float]) -> dict[str, float]:
        """Keys are whole bearings in degrees, 0 ≤ b < 360."""
        for key in linear:
            if not key.isdigit() or not 0 <= int(key) < 360:
                raise ValueError(f"bearing {key!r} must be a whole number of degrees, 0 to 359; e.g. \"45\"")
        return linear


class Walker(Strict):
    """Walk controller parameters (study §4–§6)."""

    gait: str = Field("tripod", description="initial gait: a bundled gait name or a path [OpenSHC: gait_type]")
    body_clearance: Positive = Field(0.1, description="body (base_link) height above the walk plane [m]")
    step_frequency: Adjustable = Field(
        _adj(1.0, 0.001, 2.0, 0.1), description="≈ 1 / swing duration [Hz]; cycle frequency ≈ this × swing share"
    )
    swing_height: Adjustable = Field(_adj(0.02, 0.01, 0.05, 0.005), description="swing apex height [m]")
    swing_width: Adjustable = Field(_adj(0.0, -0.3, 0.3, 0.01), description="outward shift of the swing apex [m]")
    step_depth: Adjustable = Field(_adj(0.0, 0.0, 0.0, 0.0), description="reactive target lowering (rough terrain) [m]")
    stance_span_modifier: Adjustable = Field(
        _adj(0.0, -1.0, 1.0, 0.1),
        description="fraction of the lateral workspace to widen (+) or narrow (−) stance [ratio]",
    )
    velocity_input_mode: Literal["throttle", "real"] = Field(
        "throttle", description="'throttle': inputs are −1..1 of the maximum; 'real': m/s and rad/s"
    )
    body_velocity_scaler: Positive = Field(1.0, description="multiplies velocity and cruise inputs [ratio]")
    overlapping_walkspaces: bool = Field(False, description="skip the neighbour-overlap walkspace limit")
    force_normal_touchdown: bool = Field(False, description="reshape the swing for a vertical final descent")
    gravity_aligned_tips: bool = Field(False, description=">3-DOF legs: keep the tip x axis along gravity")
    rough_terrain_mode: bool = Field(False, description="volumetric workspace and adaptive footholds")
    verify_speed_limits: bool = Field(
        False, description="scale OpenSHC's speed limits down per bearing until trial walks keep every joint off its "
                           "limits (shc, docs/deviations.md)")
    speed_shares: dict[str, StoredShares] = Field(
        default_factory=dict, description="per gait name: the shares of OpenSHC's speed limits that trial walks "
        "verified for this robot (docs/experiments/verify_speed_limits.py writes them; used when their fingerprint "
        "matches the robot and the gait, shc, docs/deviations.md)")

    @field_validator("step_frequency")
    @classmethod
    def _frequency_positive(cls, frequency: Adjustable) -> Adjustable:
        """A step cycle lasts 1 / frequency: every reachable frequency must be above 0 Hz."""
        if frequency.min <= 0:
            raise ValueError(f"min ({frequency.min:g}) must be above 0 Hz; e.g. min = 0.001")
        return frequency


class Cruise(Strict):
    """Cruise control (study §6)."""

    force_velocity: bool = Field(True, description="use the velocities below, else latch the current input")
    linear: tuple[float, float] = Field((1.0, 0.0), strict=False, description="cruise x, y (throttle or m/s)")
    angular: float = Field(0.0, description="cruise yaw rate (throttle or rad/s)")
    time_limit: NonNegative = Field(0.0, description="cruise duration, 0 = unlimited [s]")


class InverseKinematics(Strict):
    """IK options (study §2)."""

    clamp_joint_positions: bool = Field(True, description="clamp IK output to [min, max]")
    clamp_joint_velocities: bool = Field(True, description="clamp IK joint speed to max_vel")
    ignore_warnings: bool = Field(
        False, description="do not report IK deviation/clamping [OpenSHC: ignore_IK_warnings]"
    )
    limit_avoidance_cap: Annotated[float, Field(ge=0.0, lt=1.0)] = Field(
        0.5, description="each null-space limit-avoidance term corrects at most this share of its error per cycle "
        "(the velocity term: of the last cycle's joint motion; the position term: its gain); 0 = OpenSHC, whose "
        "fixed-length terms make standing joints alternate every cycle [ratio]"
    )


class XYZ(Strict):
    x: float
    y: float
    z: float


class RPY(Strict):
    roll: float
    pitch: float
    yaw: float


class PID(Strict):
    p: float
    i: float
    d: float


class Pose(Strict):
    """Body posing (study §7)."""

    manual: bool = Field(True, description="manual 6-DOF body posing [OpenSHC: manual_posing]")
    auto: bool = Field(False, description="cyclic auto posing [OpenSHC: auto_posing]")
    auto_pose_type: str = Field("auto", description="auto-pose set; 'auto' = the set named after the gait")
    inclination: bool = Field(False, description="shift the body against tilt [OpenSHC: inclination_posing]")
    inclination_mode: Literal["openshc", "support_centroid"] = Field(
        "openshc", description="'openshc': x = −h·tan(pitch), y = h·tan(roll) (study §7.5); 'support_centroid': "
        "put the gravity projection of the CoM on the stance feet's centroid (the paper's intent)")
    imu: bool = Field(False, description="roll/pitch PID levelling [OpenSHC: imu_posing]")
    rotation_pid_gains: PID = Field(PID(p=0.0, i=0.0, d=0.0), description="IMU posing PID gains")
    max_translation: XYZ = Field(XYZ(x=0.025, y=0.025, z=0.025), description="posing translation limits [m]")
    max_rotation: RPY = Field(RPY(roll=0.25, pitch=0.25, yaw=0.25), description="posing rotation limits [rad]")
    max_translation_velocity: Positive = Field(0.05, description="manual posing speed at input 1 [m/s]")
    max_rotation_velocity: Positive = Field(0.2, description="manual rotation speed at input 1 [rad/s]")


class Posture(Strict):
    """ATHENA posture control (seed 003 §4.2): ground plane from the feet in contact, height/pitch/roll corrections.

    Not part of OpenSHC; composed into the body pose after manual posing (``docs/terrain-adaptation.md``).
    """

    enabled: bool = Field(False, description="run the ATHENA posture controller")
    kz: Annotated[float, Field(ge=0.0, le=1.0)] = Field(0.0, description="height gain k_z (eq. 27) [ratio]")
    ka: Annotated[float, Field(ge=0.0, le=1.0)] = Field(0.0, description="pitch gain k_α (eq. 29) [ratio]")
    kb: Annotated[float, Field(ge=0.0, le=1.0)] = Field(0.0, description="roll gain k_β (eq. 29) [ratio]")
    plane: Literal["random_three", "least_squares"] = Field(
        "random_three", description="more than three feet down: a seeded random three (the paper) or all of them")
    reference_height: NonNegative = Field(
        0.0, description="height-sensor reading of the standing posture [m]; 0 = the first reading when walking "
        "starts (the sensor measures to the ground, the body clearance to the foot tips)")
    max_height_correction: Positive = Field(0.1, description="clamp of the accumulated height correction [m]")
    max_angle_correction: Positive = Field(0.5, description="clamp of the accumulated roll/pitch correction [rad]")


class StartUp(Strict):
    """Start-up behaviour (study §9.2–§9.3)."""

    sequence: bool = Field(
        False, description="stepped start-up/shut-down with pack/unpack [OpenSHC: start_up_sequence]"
    )
    time_to_start: Positive = Field(6.0, description="duration of the direct start-up [s]")
    simulation: Literal["ground", "stand"] = Field(
        "ground", description="where `shc simulate` starts the robot up: on its feet just above the ground, or "
        "held at standing height on a stand that is removed when it runs (OpenSHC's Gazebo launch)")


class Manipulation(Strict):
    """Manual leg manipulation (study §9.5)."""

    mode: Literal["tip_control", "joint_control"] = Field(
        "tip_control", description="[OpenSHC: leg_manipulation_mode]"
    )


class Admittance(Strict):
    """Admittance control (study §8)."""

    enabled: bool = Field(False, description="[OpenSHC: admittance_control]")
    dynamic_stiffness: bool = Field(True, description="swing/adjacent-leg stiffness scaling")
    use_joint_effort: bool = Field(False, description="estimate tip force from joint efforts (else foot sensors)")
    integrator_step_time: Positive = Field(0.5, description="virtual time advanced per control cycle [s]")
    virtual_mass: Adjustable = Field(_adj(10.0, 1.0, 100.0, 5.0), description="[kg]")
    virtual_stiffness: Adjustable = Field(_adj(12.0, 1.0, 50.0, 5.0), description="[N/m]")
    virtual_damping_ratio: Adjustable = Field(_adj(0.8, 0.1, 10.0, 0.05), description="[ratio]")
    force_gain: Adjustable = Field(_adj(0.1, 0.001, 100.0, 1.0), description="tip force multiplier [ratio]")
    load_stiffness_scaler: Positive = Field(5.0, description="stiffness factor of legs next to a swinging leg")
    swing_stiffness_scaler: Positive = Field(0.1, description="stiffness factor of a swinging leg")
    touchdown_threshold: NonNegative = Field(0.9, description="tip force above which touchdown is registered [N]")
    liftoff_threshold: NonNegative = Field(0.1, description="tip force below which contact is cleared [N]")


class Servo(Strict):
    """The joint actuators (every joint the same model) and their electrical model, for simulation.

    Electrical power per servo: ``P = idle_power + (τ/torque_constant)²·winding_resistance + max(τω, 0)
    + regenerative_efficiency·min(τω, 0)`` — electronics, copper loss, mechanical output; negative mechanical
    work (the load driving the motor) is dissipated, not returned, unless ``regenerative_efficiency`` > 0.
    """

    model: str = Field("generic", description="servo model name; a model with a datasheet (AX-12A, AX-18A, "
                       "XL430-W250, XM430-W350, MX-64, MX-106, STS3215, …) fills the fields below that are left unset")
    stall_torque: Positive = Field(8.4, description="torque limit passed to the physics engine [N·m]")
    no_load_speed: Positive = Field(4.7, description="speed limit passed to the physics engine [rad/s]")
    torque_constant: Positive = Field(1.6, description="output torque per ampere, gearbox included [N·m/A]")
    winding_resistance: Positive = Field(2.3, description="motor winding resistance [Ω]")
    idle_power: NonNegative = Field(0.9, description="electronics power of one powered servo [W]")
    regenerative_efficiency: Annotated[float, Field(ge=0.0, le=1.0)] = Field(
        0.0, description="share of negative mechanical power returned to the supply [ratio]")
    position_gain: Positive = Field(0.1, description="PyBullet position-control gain (Kp) [ratio]")
    velocity_gain: Positive = Field(1.0, description="PyBullet position-control velocity gain (Kd) [ratio]")
    control: Literal["position", "pd", "dynamixel"] = Field(
        "position", description="'position': PyBullet's position motor, stiff up to the stall torque; 'pd': a "
        "compliant proportional servo, torque = stiffness·error − damping·speed within ± stall torque (PyBullet's "
        "stable PD, implicit, every physics step): it sags under load as real servos do; 'dynamixel': the "
        "servo and gearbox model of shc_cli.backends.servo (firmware P gain in control-table units, supply "
        "voltage, back-EMF, gearbox friction) — its stiffness and damping follow from the fields below")
    stiffness: Positive = Field(5.0, description="'pd' control: torque per rad of position error [N·m/rad]")
    damping: NonNegative = Field(0.05, description="'pd' control: torque per rad/s of joint speed [N·m·s/rad]")
    supply_voltage: Positive = Field(12.0, description="'dynamixel': motor supply voltage [V]")
    position_p_gain: NonNegative = Field(
        850.0, description="'dynamixel': Position P Gain in control-table units (e-Manual: K_P = value/128 PWM "
        "units per position tick)")
    position_i_gain: NonNegative = Field(
        0.0, description="'dynamixel': Position I Gain in control-table units (e-Manual: K_I = value/65536 PWM units "
        "per position tick, summed every firmware period; factory value 0)")
    position_d_gain: NonNegative = Field(
        0.0, description="'dynamixel': Position D Gain in control-table units (e-Manual: K_D = value/16 PWM units per "
        "position tick of change per firmware period; factory value 0)")
    firmware_period: Positive = Field(
        0.001, description="'dynamixel': period of the firmware's position loop, which scales the I and D terms [s] "
        "(estimated: the e-Manual does not give it)")
    pwm_limit: Annotated[float, Field(gt=0, le=885)] = Field(
        885.0, description="'dynamixel': PWM Limit in control-table units (885 = 100 % of the supply voltage)")
    current_limit: Positive = Field(6.9, description="'dynamixel': Current Limit [A] (MX-106(2.0): 2047 × 3.36 mA)")
    ticks_per_revolution: Annotated[int, Field(gt=0)] = Field(4096, description="position ticks per turn")
    armature: NonNegative = Field(
        0.0, description="reflected rotor inertia at the output shaft [kg·m²] (engines that support it)")
    coulomb_friction: NonNegative = Field(
        0.0, description="gearbox Coulomb friction at the output shaft [N·m] (electrical model; dynamics where the "
        "engine supports it)")
    viscous_friction: NonNegative = Field(
        0.0, description="gearbox viscous friction at the output shaft [N·m·s/rad]")
    holding_ratio: Annotated[float, Field(ge=0.0, le=1.0)] = Field(
        1.0, description="motor torque needed to hold a static load, as a share of the load torque [ratio]: "
        "the gear train's static friction carries the rest (back-drivability); 1 = an ideal gearbox")
    static_speed: Positive = Field(
        0.05, description="joint speed below which a joint counts as holding still (holding_ratio applies) [rad/s]")

    @model_validator(mode="before")
    @classmethod
    def _datasheet(cls, data: object) -> object:
        """A model with a datasheet (:mod:`shc_cli.spec.servo_models`: AX-12A, AX-18A, XL430-W250, XM430-W350,
        MX-64, MX-106, STS3215, …) fills the fields the file leaves unset."""
        from shc_cli.spec.servo_models import servo_defaults

        if isinstance(data, dict) and isinstance(data.get("model"), str):
            return {**servo_defaults(data["model"]), **data}
        return data


class ServoMap(Strict):
    """Where one joint's servo is on the bus and how its ticks map to the joint angle."""

    joint: str | None = Field(None, description="the joint's name on the robot (its URDF joint, the name in "
                              "/joint_states) when it is not <LEG>_<joint>_joint; recordings with it replay")
    id: Annotated[int, Field(ge=0, le=252)] = Field(description="Dynamixel ID")
    bus: Annotated[int, Field(ge=0)] = Field(0, description="bus index (one port per bus; `run-hw --port` is bus 0)")
    model: str | None = Field(None, description="servo model, default hardware.model (e.g. 'MX-106', 'AX-12A', "
                              "'STS3215')")
    direction: Literal[1, -1] = Field(1, description="+1 if the servo turns with the joint angle, −1 if against it")
    zero_ticks: Annotated[int, Field(ge=0)] | None = Field(
        None, description="servo position [ticks] at joint angle 0 (default the middle of the model's range: 2048 "
        "for 4096-tick models, 512 for the AX series' 1024)")


MISSED_READS_FAULT = 3
"""Consecutive cycles without a servo's reading that are a run-hw fault unless ``hardware.missed_reads_fault`` says
otherwise (docs/commands.md, run-hw, Faults)."""


class Hardware(Strict):
    """The real robot's servo buses (``shc run-hw``): the servo model names the protocol (Dynamixel Protocol 2.0
    or 1.0, Feetech STS/SCS), units and control table (:mod:`shc_cli.hardware.models`)."""

    baud: Annotated[int, Field(gt=0)] = Field(1_000_000, description="bus baud rate [bit/s]")
    model: str = Field("MX-106", description="servo model of every joint unless its entry names another (e.g. "
                       "'MX-106', 'XM430-W350', 'AX-12A', 'MX-64(1.0)', 'STS3215')")
    ticks_per_revolution: Annotated[int, Field(gt=0)] = Field(
        4096, description="position ticks per turn of the 'generic' model (the others' follow from the model)")
    return_delay_us: Annotated[int, Field(ge=0, le=508)] | None = Field(
        0, description="Return Delay Time written to the servos at start-up [µs, multiple of 2] (None: leave as "
        "configured). Dynamixels ship with 500 µs: with 30 servos that alone is 15 ms per sync read")
    current_limit_ma: Annotated[float, Field(gt=0)] | None = Field(
        None, description="current limit written to the servos at start-up [mA] (None: leave as configured)")
    missed_reads_fault: Annotated[int, Field(ge=1, le=100)] | None = Field(
        None, description="consecutive cycles a servo's state read may fail (no reply or a corrupt one, after the "
        "cycle's retry) before run-hw stops on a fault; until then its last reading is used (bridged) and counted. "
        "1: the first failed cycle is a fault (None: MISSED_READS_FAULT, 3)")
    servos: dict[str, ServoMap] = Field(
        default_factory=dict, description="one entry per joint, keyed '<LEG>_<joint>' (e.g. AR_coxa)")


class Perception(Strict):
    """The simulated depth sensor and the robot-centred height map it feeds (``shc_cli.backends.height_map``);
    the defaults are a RealSense D435-like camera at the body's front, its depth image subsampled."""

    mount: tuple[Metres, Metres, Metres] = Field(
        (0.1, 0.0, 0.05), strict=False, description="sensor origin in the body frame (x forward, z up) [m]")
    pitch: Radians = Field(0.7854, description="down-tilt of the sensor's optical axis below the body's x axis [rad]")
    fov: tuple[Positive, Positive] = Field(
        (1.518, 1.012), strict=False, description="horizontal and vertical field of view [rad] (D435 depth: 87°, 58°)")
    resolution: tuple[Annotated[int, Field(ge=1, le=1024)], Annotated[int, Field(ge=1, le=1024)]] = Field(
        (32, 24), strict=False, description="rays across (columns) and down (rows) the field of view")
    range: tuple[NonNegative, Positive] = Field(
        (0.1, 3.0), strict=False, description="nearest and farthest distance the sensor reports [m]")
    noise: NonNegative = Field(0.005, description="standard deviation of each distance along its ray [m]")
    rate: Positive = Field(30.0, description="scans per second [Hz]")
    cell: Positive = Field(0.05, description="side of a height-map cell [m]")
    extent: Positive = Field(1.5, description="the height map reaches this far from the robot in x and y [m]")
    edge_margin: NonNegative = Field(
        0.05, description="a foothold keeps this far from a height change of more than edge_step [m]")
    edge_step: NonNegative = Field(0.03, description="a height change above this within edge_margin is an edge [m]")
    max_shift: NonNegative = Field(0.1, description="a foothold moves at most this far away from an edge [m]")
    clearance_margin: NonNegative = Field(
        0.04, description="a swing clears the highest point on its path by at least this [m]")
    max_clearance: Positive = Field(0.25, description="the highest swing clearance obstacles may ask for [m]")
    lookahead: NonNegative = Field(
        0.1, description="the body keeps its clearance above the highest ground under it and this far ahead [m]")
    max_slope: NonNegative = Field(
        0.25, description="the walk plane (and the body) follows the footholds' slope up to this (tan of pitch, roll)")

    @model_validator(mode="after")
    def _near_below_far(self) -> Perception:
        if self.range[0] >= self.range[1]:
            raise ValueError(f"range: nearest {self.range[0]} m must be below farthest {self.range[1]} m")
        return self


ADJUSTABLE_WALKER = ("step_frequency", "swing_height", "swing_width", "step_depth", "stance_span_modifier")
"""The ``[walker]`` parameters that can change while running (each an :class:`Adjustable`)."""
ADJUSTABLE_ADMITTANCE = ("virtual_mass", "virtual_stiffness", "virtual_damping_ratio", "force_gain")
"""The ``[admittance]`` parameters that can change while running (each an :class:`Adjustable`)."""
ADJUSTABLE = ADJUSTABLE_WALKER + ADJUSTABLE_ADMITTANCE
"""Parameters that can change while running (OpenSHC's dynamic parameters, study §9.6)."""


class Robot(Strict):
    """A fully expanded robot: what ``shc validate --show`` prints and the controller uses."""

    name: str = Field(description="short name, e.g. 'bullet'")
    description: str = Field("", description="one sentence for people")
    time_delta: Positive = Field(description="control period [s]")
    body: Body = Field(default_factory=Body)
    legs: dict[str, Leg] = Field(description="legs by id, in id order (clockwise from front right)")
    walker: Walker = Field(default_factory=Walker)
    cruise: Cruise = Field(default_factory=Cruise)
    ik: InverseKinematics = Field(default_factory=InverseKinematics)
    pose: Pose = Field(default_factory=Pose)
    start_up: StartUp = Field(default_factory=StartUp)
    posture: Posture = Field(default_factory=Posture)
    manipulation: Manipulation = Field(default_factory=Manipulation)
    admittance: Admittance = Field(default_factory=Admittance)
    servo: Servo = Field(default_factory=Servo)
    hardware: Hardware = Field(default_factory=Hardware)
    perception: Perception | None = Field(
        None, description="the simulated depth sensor and height map (None: the defaults of Perception when asked for)")

    @property
    def leg_ids(self) -> list[str]:
        return list(self.legs)

    def total_mass(self) -> float:
        """Body plus every link mass given in the file [kg]."""
        links = sum(j.mass or 0.0 for leg in self.legs.values() for j in leg.joints.values())
        return self.body.mass + links
