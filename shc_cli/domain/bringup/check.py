"""``shc hw check``: every joint's present position against its limits and the standing pose — read only: no
goal, no torque enable, nothing written to the servos.

The standing pose is the joints OpenSHC's direct start-up ends in (:func:`shc_cli.control.startup.plan_direct_startup`
from the joint defaults), the pose run-hw brings the robot to first.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

from shc_cli.events import NOTICE, event

if TYPE_CHECKING:
    from shc_cli.hardware.bus import ServoBus
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class JointReading:
    """One joint: its servo's present position and where that is against the limits and the standing pose."""

    joint: str
    servo_id: int
    ticks: int
    angle: float
    """[rad], through the servo map (zero, direction) and the joint's offset."""
    low: float
    high: float
    standing: float
    """The standing pose's angle [rad]."""

    @property
    def within(self) -> bool:
        return self.low <= self.angle <= self.high

    @property
    def outside_by(self) -> float:
        """How far outside the limits [rad] (0 within)."""
        return max(self.low - self.angle, self.angle - self.high, 0.0)


@dataclass(frozen=True)
class CheckReport:
    robot: str
    port: str
    readings: list[JointReading]

    @property
    def outside(self) -> list[JointReading]:
        return [r for r in self.readings if not r.within]


def standing_joints(robot: Robot) -> dict[str, float]:
    """The standing pose's joint angles [rad] by ``<LEG>_<joint>``."""
    from shc_cli.control.startup import plan_direct_startup
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    q = plan_direct_startup(robot, chains, chains.default_joints())
    return {f"{leg}_{joint}": float(q[i, k]) for i, (leg, spec) in enumerate(robot.legs.items())
            for k, joint in enumerate(spec.joints)}


def open_checked(robot: Robot, ports: list[str], baud: int | None) -> ServoBus:
    """The robot's bus, opened, after run-hw's start check (every servo there, right model, no hardware error,
    position control, limits inside the servos'); raises :class:`~shc_cli.hardware.bus.HardwareError` with every
    problem (nothing is written)."""
    from shc_cli.hardware.bus import HardwareError
    from shc_cli.hardware.buses import servo_bus

    bus = servo_bus(robot, ports, baud)
    bus.open()
    try:
        problems = bus.check()
    except BaseException:
        bus.close()
        raise
    if problems:
        bus.close()
        from shc_cli.hardware.servo_io import ServoFault

        faults = [p for p in problems if ": hardware error (" in p]  # the servos' own protection: a fault
        raise (ServoFault if faults else HardwareError)(f"{bus.port_name}: " + "; ".join(faults or problems))
    return bus


def check(robot: Robot, ports: list[str], baud: int | None = None) -> CheckReport:
    """Read every servo once and compare (raises :class:`~shc_cli.hardware.servo_io.ServoFault` naming a servo
    that stops answering or reports its protection)."""
    from shc_cli.hardware.servo_io import ServoFault

    standing = standing_joints(robot)
    bus = open_checked(robot, ports, baud)
    try:
        event(log, NOTICE, "hw_check", "%s: %d servos answer on %s", robot.name, len(bus.slots), bus.port_name)
        state = bus.read_state()
        for index, reason in state.failures.items():
            slot = bus.slots[index]
            raise ServoFault(f"{slot.key} (servo {slot.servo_id}): {reason}")
        alerts = [bus.slots[i] for i, alert in enumerate(state.alerts) if alert]
        if alerts:
            errors = bus.hardware_errors()
            raise ServoFault("; ".join(f"{s.key} (servo {s.servo_id}): {', '.join(errors.get(s.key, ['alert']))}"
                                       for s in alerts))
        readings = []
        for index, slot in enumerate(bus.slots):
            angle = float(state.positions[slot.leg, slot.joint])
            ticks = bus.angle_to_ticks(index, angle)
            readings.append(JointReading(slot.key, slot.servo_id, ticks, angle, slot.limits[0], slot.limits[1],
                                         standing[slot.key]))
        return CheckReport(robot.name, bus.port_name, readings)
    finally:
        bus.close()
