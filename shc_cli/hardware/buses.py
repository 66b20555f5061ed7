"""The bus for a robot's servos, by their models' family: Dynamixel Protocol 2.0 (:class:`ServoBus`), Dynamixel
Protocol 1.0 (:class:`Protocol1Bus`) or Feetech STS (:class:`FeetechBus`) — one interface for ``run-hw``."""

from __future__ import annotations

from shc_cli.hardware.bus import HardwareError, ServoBus
from shc_cli.hardware.models import FAMILY_NAMES, MODELS
from shc_cli.spec.robot import Robot


def families(robot: Robot) -> set[str]:
    """The protocol families of the robot's servos (see :data:`shc_cli.hardware.models.FAMILY_NAMES`)."""
    hardware = robot.hardware
    return {MODELS[servo.model or hardware.model].family for servo in hardware.servos.values()
            if (servo.model or hardware.model) in MODELS}


def servo_bus(robot: Robot, ports: list[str] | str, baud: int | None = None,
              profile_velocity: bool = False) -> ServoBus:
    """The bus object for the robot's servos (not opened). Raises :class:`HardwareError` for servos of several
    families (one run speaks one protocol for now; the robot file may put each protocol on its own bus, which
    ``validate`` checks, but run-hw does not yet drive two protocols at once)."""
    from shc_cli.hardware.bus_protocol1 import FeetechBus, Protocol1Bus

    found = families(robot)
    if len(found) > 1:
        names = " and ".join(sorted(FAMILY_NAMES[f] for f in found))
        raise HardwareError(f"{robot.name}: the servos speak {names}; run-hw drives one protocol at a time")
    family = found.pop() if found else "protocol2"
    if family == "protocol1":
        return Protocol1Bus(robot, ports, baud, profile_velocity)
    if family == "feetech":
        return FeetechBus(robot, ports, baud, profile_velocity)
    return ServoBus(robot, ports, baud, profile_velocity)
