"""The one table of ``shc simulate``'s options: name, type, default, bounds, unit and help (:data:`SIMULATE`).

:class:`~shc_cli.domain.config.SimulationConfig` checks every value against it once (:func:`check_bounds`) — so the
command line, the Python API (``shc_cli.api.simulate``), sweep points and study trials refuse the same values with
the same line — and warns about legal but degenerate ones (:func:`degenerate`). ``tests/test_option_table.py`` fails
when the command line's options, :class:`~shc_cli.domain.config.SimulationConfig`'s fields, the API's
:class:`~shc_cli.domain.config.SimulationOptions` or the sweep/study options differ from this table in names or
defaults. Plain data only (imported by ``shc_cli.cli`` for its help texts: no numpy, no pydantic).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

__all__ = ["SIMULATE", "Option", "check_bounds", "degenerate"]


@dataclass(frozen=True, slots=True)
class Option:
    """One option.

    Attributes:
        name: the Python name (``--name-with-dashes`` on the command line).
        type: the value's type (``None`` allowed when the default is ``None``).
        default: the default value.
        help: what it does (the command line's help text).
        unit: the unit of a number (``""``: none).
        low: the smallest value allowed (numbers; ``None``: no bound).
        high: the largest value allowed.
        low_open: ``low`` itself is not allowed (a value must be above it).
        warn_at: legal values at which the run is degenerate, each with the warning.
        example: a good value for the one-line fix.
    """

    name: str
    type: type
    default: object
    help: str
    unit: str = ""
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    warn_at: tuple[tuple[float, str], ...] = ()
    example: str = ""

    @property
    def cli_help(self) -> str:
        """The command line's help: :attr:`help` and, for a bounded number, its range and unit."""
        bounded = self.low is not None or self.high is not None
        return f"{self.help} Range: {self.range_text().removeprefix('in ')}." if bounded else self.help

    @property
    def flag(self) -> str:
        """The command-line flag, ``--imu-noise``."""
        return "--" + self.name.replace("_", "-")

    def range_text(self) -> str:
        """The allowed range in words, e.g. ``"in [0, 1]"``, ``"in (0, 3600] s"``."""
        unit = f" {self.unit}" if self.unit else ""
        if self.low is not None and self.high is not None:
            return f"in {'(' if self.low_open else '['}{_number(self.low)}, {_number(self.high)}]{unit}"
        if self.low is not None:
            return f"{'above' if self.low_open else 'at least'} {_number(self.low)}{unit}"
        if self.high is not None:
            return f"at most {_number(self.high)}{unit}"
        return "finite"


def _number(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else f"{value:g}"


MAX_SEED = 2**32 - 1
"""The largest seed (numpy's legacy generators take 0 .. 2³² − 1)."""

SIMULATE: dict[str, Option] = {option.name: option for option in (
    Option("robot", str, "bullet", "Robot file or bundled robot name."),
    Option("gait", str, None, "Gait name or file (default: the robot's gait)."),
    Option("velocity", str, "1,0,0", "Constant velocity input VX,VY,WZ."),
    Option("duration", float, None, "Seconds to run after start-up (default 20).", "s", 0.0, 1e6, True,
           example="10"),
    Option("commands", Path, None, "Command timeline: CSV 'cycle,vx,vy,wz' or a TOML plan script."),
    Option("path", Path, None, "Walk the waypoints of a path file by the odometry, then stop."),
    Option("out", Path, None, "Run directory (default runs/<timestamp>-simulate)."),
    Option("plots", bool, True, "Write trajectory.png, power.png and contacts.png."),
    Option("terrain", str, "flat",
           "flat, ramp:DEG, blocks[:LOW,HIGH[,SIZE]], stairs[-down]:RISE,RUN, heightfield:FILE[,SCALE] "
           "or slope|steps|obstacles|stones|gaps:D (docs/terrains.md)"),
    Option("scenario", str, "WG", "WG walk ground, SG stance ground, WA walk air, SA stance air."),
    Option("physics_rate", float, 400.0, "Physics steps per second (whole multiple of control).", "Hz", 0.0, 1e5,
           True, example="400"),
    Option("friction", float, 0.9, "Lateral friction of feet and terrain (the coefficient between them is its "
           "square; 0 = ice: the feet slide).", "", 0.0, 10.0,
           warn_at=((0.0, "friction 0: the feet slide freely, so the run's distance and speed are sliding, not "
                           "walking (give e.g. --friction 0.9)"),), example="0.9"),
    Option("restitution", float, 0.0, "Restitution of feet and terrain, 0 (no bounce) to 1 (elastic).", "", 0.0,
           1.0, example="0"),
    Option("seed", int, 0, "Seed of every random thing (terrain, sensor noise).", "", 0, MAX_SEED, example="0"),
    Option("imu_noise", float, 0.0, "IMU noise standard deviation (rad/s, m/s²).", "rad/s, m/s²", 0.0, 100.0,
           example="0.01"),
    Option("imu_yaw_bias", float, 0.0, "IMU gyro yaw-rate bias (deg/s): the rate reads it, the orientation's yaw "
           "drifts by it.", "deg/s", -90.0, 90.0, example="0.5"),
    Option("start", str, "unpacked", "Spawn pose: unpacked or packed."),
    Option("gui", bool, False, "Open the PyBullet GUI (needs a display)."),
    Option("stand", bool, None, "Start up held at standing height on a stand, or on the ground."),
    Option("posture", str, None, "ATHENA posture control with gains, e.g. kz=0.8,ka=0.6,kb=0 (plane=...)."),
    Option("imu_posing", bool, None, "OpenSHC IMU levelling [default: robot file]."),
    Option("inclination", str, None, "Inclination posing: off, openshc or support_centroid [default: robot file]."),
    Option("admittance", bool, None, "Admittance control [default: robot file]."),
    Option("fail_leg", str, None, "Failed legs, LEG[:MODE][@T] (repeatable, or comma-separated), MODE "
           "retracted (default: folded clear of the ground) or locked (held where walking begins); from the start, "
           "or T s after walking starts; the gait is re-planned for the legs left."),
    Option("fail_on_fall", bool, False, "Exit with code 4 when the robot fell."),
    Option("overwrite", bool, False, "Replace an existing run directory at --out (when the new run finishes)."),
    Option("engine", str, "mujoco", "Physics engine: mujoco or pybullet."),
    Option("live", bool, False, "Stream the run while it happens to a Foxglove WebSocket server on 127.0.0.1."),
    Option("live_port", int, 8765, "Port of the --live server (0: any free port).", "", 0, 65535, example="8765"),
    Option("realtime", bool, False, "Pace the simulation to the wall clock."),
    Option("input_mode", str, "timeline", "timeline, commands:FILE, stdin, keyboard or gamepad[:DEVICE]."),
    Option("watchdog", float, 0.5, "stdin: seconds without a line before the velocity goes to 0.", "s", 0.0, 3600.0,
           True, example="0.5"),
    Option("policy", Path, None, "A policy file (.npz, shc_cli.loop.policy.file) acting on the controller once it "
           "runs: gait parameters or residual tip offsets within their ranges (docs/gym.md)."),
    Option("perception", str, "off", "off (blind, as OpenSHC) or rays: a simulated depth sensor's height map "
           "shapes footholds, swing height and body height (docs/terrain-adaptation.md)."),
)}
"""Every option of ``shc simulate``, in its order."""


def check_bounds(name: str, value: object) -> str | None:
    """The problem with ``value`` for option ``name`` (not a finite number, or outside the table's bounds), or
    ``None`` when it is fine (also for options without bounds and for ``None``)."""
    option = SIMULATE.get(name)
    if option is None or value is None or option.type not in (int, float) or isinstance(value, bool):
        return None
    if not isinstance(value, (int, float)):
        return None  # the type check is the model's
    if not math.isfinite(value):
        return f"{value!r} is not a finite number"
    below = option.low is not None and (value <= option.low if option.low_open else value < option.low)
    above = option.high is not None and value > option.high
    if below or above:
        return f"{value!r} is out of range: {option.name} must be {option.range_text()}"
    return None


def degenerate(name: str, value: object) -> str | None:
    """The warning for a legal but degenerate value of option ``name`` (friction 0), or ``None``."""
    option = SIMULATE.get(name)
    if option is None or not isinstance(value, (int, float)):
        return None
    return next((text for at, text in option.warn_at if value == at), None)
