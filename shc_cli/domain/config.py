"""Every option of one simulation (``shc simulate``), validated once: :class:`SimulationConfig`.

Built from the command line, the Python API, a sweep point or a study trial (:meth:`SimulationConfig.from_options`)
and passed down whole. A bad value is a one-line :class:`~shc_cli.errors.SpecError` naming the option.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, TypedDict

from pydantic import BaseModel, ConfigDict, ValidationError, field_validator, model_validator

from shc_cli.backends.engine_registry import DEFAULT_ENGINE, ENGINES, EngineName
from shc_cli.domain.options import SIMULATE, check_bounds, degenerate
from shc_cli.errors import Issue, SpecError, check_choice

if TYPE_CHECKING:
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.terrain import TerrainSpec
    from shc_cli.spec.robot import Robot

Scenario = Literal["SA", "WA", "SG", "WG"]
"""Paper §VII-A scenarios: stance air, walk air, stance ground, walk ground."""
SCENARIOS: dict[str, tuple[bool, bool]] = {"SA": (True, False), "WA": (True, True), "SG": (False, False),
                                           "WG": (False, True)}
"""Scenario → (body held in the air, walking)."""
StartPose = Literal["unpacked", "packed"]
InclinationMode = Literal["off", "openshc", "support_centroid"]
Velocity = str | tuple[float, float, float]
"""A velocity input ``"VX,VY,WZ"`` or ``(vx, vy, wz)`` in the robot's input mode (throttle −1..1 or m/s, rad/s)."""


MAX_IMU_YAW_BIAS = SIMULATE["imu_yaw_bias"].high
"""Largest simulated gyro yaw-rate bias ``--imu-yaw-bias`` accepts [deg/s] (a MEMS gyro's uncalibrated bias is a few
deg/s; beyond this it would be no gyro): the option table's bound (:mod:`shc_cli.domain.options`)."""


def _bad(option: str, problem: str, fix: str) -> SpecError:
    return SpecError([Issue(None, None, option, problem, fix)])


class SimulationConfig(BaseModel):
    """Every option of ``shc simulate`` (the same names, the same defaults), checked on construction: every number
    against the bounds of the one option table, :data:`shc_cli.domain.options.SIMULATE` (finite, in range).

    Attributes:
        robot: robot file or bundled name.
        gait: gait file or name (None: the robot's).
        velocity: constant velocity input ``"VX,VY,WZ"`` in the robot's input mode (a 3-tuple is accepted).
        duration: seconds to run after start-up (None: a timeline's length + 1 s, or 20 s) [s].
        commands: command timeline (CSV or TOML plan script).
        path: a path file the follower walks by the odometry (instead of ``velocity`` or ``commands``).
        out: run directory (None: ``runs/<timestamp>-simulate``).
        plots: write trajectory.png, power.png and contacts.png.
        terrain: ``flat``, ``ramp:DEG``, ``blocks[...]``, ``stairs:RISE,RUN`` or ``heightfield:FILE[,SCALE]``
            (parsed on construction: :attr:`terrain_spec`).
        scenario: WG, SG, WA or SA (lower case accepted).
        physics_rate: physics steps per second [Hz] (a whole multiple of the control rate: :meth:`substeps`).
        friction: lateral friction of feet and terrain.
        restitution: restitution of feet and terrain.
        seed: seed of every random thing.
        imu_noise: IMU noise standard deviation [rad/s, m/s²].
        imu_yaw_bias: the simulated IMU gyro's yaw-rate bias [deg/s] (finite, at most
            :data:`MAX_IMU_YAW_BIAS` in size): its rate reads it and its orientation's yaw drifts by it; 0 = none.
        start: spawn pose, ``unpacked`` or ``packed``.
        gui: open the physics GUI (needs a display).
        stand: start up on a stand (True), on the ground (False), or as ``start_up.simulation`` says (None).
        posture: ATHENA gains, e.g. ``"kz=0.8,ka=0.6,kb=0"`` (also ``plane=least_squares``); enables it.
        imu_posing: OpenSHC IMU posing on or off (None: as the robot file says).
        inclination: ``"off"``, ``"openshc"`` or ``"support_centroid"`` (None: as the robot file says).
        admittance: admittance control on or off (None: as the robot file says).
        fail_leg: failed legs from the start, ``LEG[:MODE]`` comma-separated (:mod:`shc_cli.control.leg_failure`).
        fail_on_fall: the command exits 4 when the robot fell.
        overwrite: replace an existing run directory at ``out`` when the run finishes.
        engine: the physics engine (:data:`~shc_cli.backends.engine_registry.ENGINES`).
        live: stream the run while it happens on a Foxglove WebSocket server on 127.0.0.1 (``shc_cli.live``).
        live_port: that server's port (0: any free port).
        realtime: pace the run to the wall clock (one control period of real time per cycle).
        input_mode: what drives the run after start-up: ``timeline`` (``velocity``/``commands``),
            ``commands:FILE``, or a person: ``stdin``, ``keyboard``, ``gamepad[:DEVICE]`` (these imply ``realtime``:
            :attr:`paced`; :mod:`shc_cli.loop.input_choice`).
        watchdog: stdin: seconds without a line before the velocities go to zero [s].
        policy: a policy file acting on the controller once it runs (:mod:`shc_cli.loop.policy.drive`).
        perception: ``off`` (blind, as OpenSHC) or ``rays``: a simulated depth sensor's height map is the
            controller's step-plane input (:mod:`shc_cli.loop.perception`).
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    robot: str = "bullet"
    gait: str | None = None
    velocity: str = "1,0,0"
    duration: float | None = None
    commands: Path | None = None
    path: Path | None = None
    out: Path | None = None
    plots: bool = True
    terrain: str = "flat"
    scenario: Scenario = "WG"
    physics_rate: float = 400.0
    friction: float = 0.9
    restitution: float = 0.0
    seed: int = 0
    imu_noise: float = 0.0
    imu_yaw_bias: float = 0.0
    start: StartPose = "unpacked"
    gui: bool = False
    stand: bool | None = None
    posture: str | None = None
    imu_posing: bool | None = None
    inclination: InclinationMode | None = None
    admittance: bool | None = None
    fail_leg: str | None = None
    fail_on_fall: bool = False
    overwrite: bool = False
    engine: EngineName = DEFAULT_ENGINE
    live: bool = False
    live_port: int = 8765
    realtime: bool = False
    input_mode: str = "timeline"
    watchdog: float = 0.5
    policy: Path | None = None
    perception: Literal["off", "rays"] = "off"

    def __init__(self, **options: Any) -> None:
        unknown = [key for key in options if key not in type(self).model_fields]
        if unknown:
            raise _bad(unknown[0], f"'{unknown[0]}' is not an option of simulate",
                       f"use one of {', '.join(type(self).model_fields)}")
        try:
            super().__init__(**options)
        except ValidationError as error:
            first = error.errors()[0]
            name = str(first["loc"][0]) if first["loc"] else ""
            raise _bad(f"--{name.replace('_', '-')}", f"{first['input']!r}: {first['msg']}",
                       f"see shc simulate --help for {name}") from None

    @classmethod
    def from_options(cls, options: Mapping[str, Any] | None = None, **changes: Any) -> SimulationConfig:
        """A config from option values by name (a sweep point's or a study trial's), ``changes`` over them.

        ``None`` values and an empty ``gait`` mean the default, as in sweep files."""
        merged = {**(options or {}), **changes}
        return cls(**{key: value for key, value in merged.items()
                      if value is not None and not (key == "gait" and value == "")})

    def replace(self, **changes: Any) -> SimulationConfig:
        """This config with some options changed (validated again)."""
        return type(self)(**{**self.model_dump(exclude_unset=True), **changes})

    @model_validator(mode="after")
    def _bounds(self) -> SimulationConfig:
        for name in type(self).model_fields:
            problem = check_bounds(name, getattr(self, name))
            if problem is not None:
                option = SIMULATE[name]
                raise _bad(option.flag, problem, f"give e.g. {option.flag} {option.example or option.default}")
        return self

    def warnings(self) -> list[str]:
        """Warnings for legal but degenerate values (friction 0: the feet slide), from the option table."""
        return [text for name in type(self).model_fields
                if (text := degenerate(name, getattr(self, name))) is not None]

    @field_validator("input_mode")
    @classmethod
    def _input(cls, value: str) -> str:
        from shc_cli.loop.input_choice import check_input

        return check_input(value)

    @property
    def paced(self) -> bool:
        """Paced to the wall clock: ``realtime``, or an input a person drives (a hand-driven simulation faster than
        real time could not be steered)."""
        from shc_cli.loop.input_choice import is_live

        return self.realtime or is_live(self.input_mode)

    @field_validator("velocity", mode="before")
    @classmethod
    def _velocity(cls, value: object) -> object:
        if isinstance(value, (tuple, list)):
            return ",".join(repr(float(v)) for v in value)
        return value

    @field_validator("engine", mode="before")
    @classmethod
    def _engine(cls, value: object) -> object:
        check_choice("--engine", value, ENGINES, "a physics engine")
        return value

    @field_validator("scenario", mode="before")
    @classmethod
    def _scenario(cls, value: object) -> object:
        scenario = value.upper() if isinstance(value, str) else value
        check_choice("--scenario", scenario, SCENARIOS, "a scenario",
                     "use SA (stance air), WA (walk air), SG (stance ground) or WG (walk ground)")
        return scenario

    @field_validator("start", mode="before")
    @classmethod
    def _start(cls, value: object) -> object:
        check_choice("--start", value, ("unpacked", "packed"), "a start pose")
        return value

    @field_validator("inclination", mode="before")
    @classmethod
    def _inclination(cls, value: object) -> object:
        if value is not None:
            check_choice("--inclination", value, ("off", "openshc", "support_centroid"), "a mode")
        return value

    @field_validator("posture")
    @classmethod
    def _posture(cls, value: str | None) -> str | None:
        if value is not None:
            parse_posture(value)
        return value

    @field_validator("terrain")
    @classmethod
    def _terrain(cls, value: str) -> str:
        from shc_cli.backends.terrain import parse_terrain

        parse_terrain(value)
        return value

    @property
    def terrain_spec(self) -> TerrainSpec:
        """The parsed terrain (a height-field file is read here)."""
        from shc_cli.backends.terrain import parse_terrain

        return parse_terrain(self.terrain)

    @property
    def airborne(self) -> bool:
        """The body is held in the air (scenarios SA, WA)."""
        return SCENARIOS[self.scenario][0]

    @property
    def walking(self) -> bool:
        """The scenario walks (WG, WA)."""
        return SCENARIOS[self.scenario][1]

    def substeps(self, robot: Robot) -> int:
        """Physics steps per control period; one-line SpecError unless :attr:`physics_rate` is a whole multiple
        of the robot's control rate."""
        substeps = round(self.physics_rate * robot.time_delta)
        if substeps < 1 or abs(substeps - self.physics_rate * robot.time_delta) > 1e-6:
            raise _bad("--physics-rate", f"{self.physics_rate:g} Hz is not a whole multiple of the control rate "
                       f"{1 / robot.time_delta:g} Hz", f"e.g. {4 / robot.time_delta:g} Hz")
        return substeps

    def stand_start(self, robot: Robot) -> bool:
        """Start up on the stand: :attr:`stand`, or the robot file's ``start_up.simulation`` when unset."""
        return robot.start_up.simulation == "stand" if self.stand is None else self.stand

    def apply_switches(self, robot: Robot) -> Robot:
        """The robot with the per-run switches (posture, imu_posing, inclination, admittance, and the start on a
        stand or on the ground: ``start_up.simulation``, so the run's ``robot.toml`` says how it started — what a
        replay of its log needs) applied."""
        pose, posture = robot.pose, robot.posture
        if self.imu_posing is not None:
            pose = pose.model_copy(update={"imu": self.imu_posing})
        if self.inclination is not None:
            on = self.inclination != "off"
            pose = pose.model_copy(update={"inclination": on, **({"inclination_mode": self.inclination} if on
                                                                   else {})})
        if self.posture is not None:
            posture = posture.model_copy(update={"enabled": True, **parse_posture(self.posture)})
        admittance = robot.admittance
        if self.admittance is not None:
            admittance = admittance.model_copy(update={"enabled": self.admittance})
        start_up = robot.start_up
        if self.stand is not None:
            start_up = start_up.model_copy(update={"simulation": "stand" if self.stand else "ground"})
        return robot.model_copy(update={"pose": pose, "posture": posture, "admittance": admittance,
                                        "start_up": start_up})

    def engine_options(self, robot: Robot) -> EngineOptions:
        """What the physics engine needs for ``robot`` (the robot after :meth:`apply_switches`)."""
        from shc_cli.backends.engine import EngineOptions

        return EngineOptions(terrain=self.terrain_spec, substeps=self.substeps(robot), fixed_base=self.airborne,
                             friction=self.friction, restitution=self.restitution, seed=self.seed,
                             imu_noise=self.imu_noise, start_pose=self.start, gui=self.gui,
                             stand=self.stand_start(robot), engine=self.engine,
                             imu_yaw_bias=math.radians(self.imu_yaw_bias))


def parse_posture(text: str) -> dict[str, Any]:
    """``kz=0.8,ka=0.6,kb=0[,plane=least_squares]`` → fields of ``[posture]``; one-line SpecError if bad."""
    out: dict[str, Any] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, _, value = part.partition("=")
        key = key.strip()
        if key in ("kz", "ka", "kb"):
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if not 0.0 <= number <= 1.0:
                raise _bad("--posture", f"{key}={value!r} is not a gain in [0, 1]", "e.g. --posture kz=0.8,ka=0.6,kb=0")
            out[key] = number
        elif key == "plane" and value in ("random_three", "least_squares"):
            out[key] = value
        else:
            raise _bad("--posture", f"'{part}' is not kz=, ka=, kb= or plane=",
                       "e.g. --posture kz=0.8,ka=0.6,kb=0 (plane=random_three|least_squares)")
    return out


class SimulationOptions(TypedDict, total=False):
    """The options of :class:`SimulationConfig` as keywords (for typed ``**options``, e.g. ``api.simulate``)."""

    gait: str | None
    velocity: Velocity
    duration: float | None
    commands: Path | str | None
    path: Path | str | None
    out: Path | str | None
    plots: bool
    terrain: str
    scenario: Scenario | str
    physics_rate: float
    friction: float
    restitution: float
    seed: int
    imu_noise: float
    imu_yaw_bias: float
    start: StartPose
    gui: bool
    stand: bool | None
    posture: str | None
    imu_posing: bool | None
    inclination: InclinationMode | None
    admittance: bool | None
    fail_leg: str | None
    fail_on_fall: bool
    overwrite: bool
    live: bool
    live_port: int
    realtime: bool
    input_mode: str
    watchdog: float
    engine: EngineName
    policy: Path | str | None
    perception: Literal["off", "rays"]
