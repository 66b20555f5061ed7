"""The physics backend of ``simulate``: a physics engine world advanced one control period per cycle.

The engine object has the interface of :class:`shc_cli.backends.pybullet_.world.World` (``command(targets)``,
``step()``, ``read() -> Reading``, ``release_stand()``, ``close()``, ``physics_time``, ``substeps``, ``stand``);
:func:`open_world` is the one place it is constructed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from shc_cli.backends.base import Measured
from shc_cli.control.sensing import Sensors
from shc_cli.control.states import RobotState
from shc_cli.model.chains import JointSlots

if TYPE_CHECKING:
    from shc_cli.backends.engine import Engine, EngineOptions, Reading
    from shc_cli.control.controller import CycleOutput
    from shc_cli.spec.robot import Robot


def open_world(robot: Robot, options: EngineOptions) -> Engine:
    """The physics world of a run, its robot spawned in ``options.start_pose`` (the one place an engine is built)."""
    from shc_cli.backends.engine_registry import open_engine
    from shc_cli.control.sequence import joint_configurations
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    packed, unpacked = joint_configurations(robot, chains.joints)
    initial = np.clip(packed[-1] if options.start_pose == "packed" and len(packed) else unpacked, chains.lower,
                      chains.upper)
    return open_engine(robot, options, initial)


_RUNNING = RobotState.RUNNING


class SimulatedBackend:
    """A physics world as a backend: targets to the servos, the physics sub-steps, the sensors.

    Args:
        robot: the robot.
        world: the engine world (:func:`open_world`).
    """

    def __init__(self, robot: Robot, world: Engine) -> None:
        self.robot, self.world = robot, world
        self.slots = JointSlots.of(robot)
        self.reading: Reading | None = None
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
        self._running = out.robot_state is _RUNNING
        return out.joints

    def advance(self) -> None:
        self.world.step()

    def read(self) -> Reading:
        world = self.world
        self.reading = reading = world.read()
        self._first = False
        if self._running and world.stand is not None:
            world.release_stand()  # started up on the stand: now on its own feet
        return reading

    def measured(self, reading: Reading) -> Measured:
        """What ``reading`` measured; its joint arrays in servo order are views of the reading's where the robot's
        legs have no padding (read at once by the recorder, every cycle)."""
        order = self.slots.servo_order
        return Measured(order(reading.joints), order(reading.joint_efforts), order(reading.servo_power),
                        reading.foot_forces, reading.foot_contact, reading)

    def fault(self) -> str | None:
        return None

    def close(self, faulted: bool = False) -> None:
        self.world.close()

    def __enter__(self) -> SimulatedBackend:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
