"""The physics backend of ``simulate``: a physics engine world advanced one control period per cycle.

The engine object has the interface of :class:`shc_cli.backends.pybullet_.world.World` (``command(targets)``,
``step()``, ``read() -> Reading``, ``release_stand()``, ``close()``, ``physics_time``, ``substeps``, ``stand``);
:func:`open_world` is the one place it is constructed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.control.sensing import Sensors
from shc_cli.loop.runlog import joint_slots

if TYPE_CHECKING:
    from shc_cli.control.controller import CycleOutput
    from shc_cli.spec.robot import Robot

@dataclass(frozen=True)
class WorldOptions:
    """How the simulated world is built (``shc simulate`` options).

    Attributes:
        terrain: the terrain spec (:func:`shc_cli.backends.terrain.parse_terrain`).
        substeps: physics steps per control period.
        airborne: hold the body in the air (scenarios SA, WA).
        friction: lateral friction of feet and terrain.
        restitution: restitution of feet and terrain.
        seed: seed of every random thing.
        imu_noise: IMU noise standard deviation (rad/s, m/s²).
        start_pose: ``"unpacked"`` or ``"packed"``.
        gui: open the engine's GUI.
        stand: start up held on a removable stand.
        engine: the physics engine (:data:`shc_cli.backends.engine.ENGINES`).
    """

    terrain: Any
    substeps: int
    airborne: bool = False
    friction: float = 0.9
    restitution: float = 0.0
    seed: int = 0
    imu_noise: float = 0.0
    start_pose: str = "unpacked"
    gui: bool = False
    stand: bool = False
    engine: str = "pybullet"


def open_world(robot: Robot, options: WorldOptions) -> Any:
    """The physics world of a run, its robot spawned in the start pose (the one place an engine is built)."""
    from shc_cli.backends.engine_registry import open_engine
    from shc_cli.control.sequence import joint_configurations
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    packed, unpacked = joint_configurations(robot, chains.joints)
    initial = np.clip(packed[-1] if options.start_pose == "packed" and len(packed) else unpacked, chains.lower,
                      chains.upper)
    return open_engine(options.engine, robot, options.terrain, robot.time_delta, options.substeps, options.airborne,
                       initial, options.friction, options.restitution, options.seed, options.imu_noise, options.gui,
                       options.stand)


class SimulatedBackend:
    """A physics world as a backend: targets to the servos, the physics sub-steps, the sensors.

    Args:
        robot: the robot.
        world: the engine world (:func:`open_world`).
    """

    kind = "simulate"

    def __init__(self, robot: Robot, world: Any) -> None:
        self.robot, self.world = robot, world
        self.rows, self.cols = joint_slots(robot)
        self.reading: Any = None
        self.total_power = 0.0
        """Total servo power of the last reading [W]."""
        self._running = False
        self._first = True  # the spawn reading is not fed to the controller (it starts from its joints)

    def start(self) -> np.ndarray:
        self.reading = self.world.read()
        return np.asarray(self.reading.joints)

    def begin(self) -> None:
        """The world is ready."""

    def sensors(self, wanted: bool) -> Sensors | None:
        """The controller's view of the last reading (``None`` when it has no use for it, and at the start)."""
        reading = self.reading
        if not wanted or reading is None or self._first:
            return None
        return Sensors(reading.orientation, reading.angular_rate, reading.joints, reading.joint_efforts,
                       reading.foot_forces, reading.foot_contact, reading.body_height)

    def apply(self, out: CycleOutput) -> np.ndarray:
        self.world.command(out.joints)
        self._running = out.robot_state.name == "RUNNING"
        return out.joints

    def advance(self) -> None:
        self.world.step()

    def read(self) -> Any:
        world = self.world
        self.reading = reading = world.read()
        self._first = False
        if self._running and world.stand is not None:
            world.release_stand()  # started up on the stand: now on its own feet
        return reading

    def measured_row(self, reading: Any) -> np.ndarray:
        rows, cols = self.rows, self.cols
        power = reading.servo_power[rows, cols]
        self.total_power = total = float(power.sum())
        return np.concatenate((reading.joints[rows, cols], reading.joint_efforts[rows, cols], power,
                               reading.foot_forces, reading.foot_contact, reading.position, reading.rpy,
                               reading.linear_velocity, reading.angular_velocity, reading.orientation,
                               reading.angular_rate, reading.linear_acceleration, (reading.body_height, total)))

    def fault(self) -> str | None:
        return None

    def close(self, faulted: bool = False) -> None:
        self.world.close()

    def __enter__(self) -> SimulatedBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
