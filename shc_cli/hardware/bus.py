"""The robot's servos on a Dynamixel Protocol 2.0 bus, through the official dynamixel-sdk.

Joint angles ↔ ticks: ``ticks = zero_ticks + direction · q · ticks_per_revolution / 2π``. One sync read per cycle
(present current, velocity and position: addresses 126–135, 10 bytes per servo) and one sync write (goal position).
dynamixel-sdk's GroupSyncRead drops each servo's status error byte, so the sync read is sent with it and the
replies are received one by one with ``PacketHandler.readRx``, which keeps the error byte: its alert bit flags a
hardware error in the same cycle, and only then is Hardware Error Status (address 70) read to name it. The SDK
does not byte-stuff what it sends, so every goal payload is checked for ``FF FF FD`` (impossible for positions
below 65,535 ticks, checked anyway).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from shc_cli.errors import ShcError
from shc_cli.hardware import protocol2 as p2
from shc_cli.hardware.models import MODELS, ServoModel, hardware_error_names
from shc_cli.spec.robot import Robot

STATE_ADDRESS, STATE_LENGTH = 126, 10
"""Present current (2), velocity (4), position (4), contiguous in the X/MX 2.0 control table."""


class HardwareError(ShcError):
    """The bus or a servo is missing, wrong or failing (one line, exit 2)."""


@dataclass(frozen=True)
class Slot:
    """One joint's servo: where it is in the controller's ``(L, n)`` arrays and on the bus."""

    key: str
    leg: int
    joint: int
    servo_id: int
    model: ServoModel
    direction: int
    zero: int


@dataclass
class BusState:
    """One sync read: per joint (controller order) position [rad], velocity [rad/s], current [mA]; per servo (slot
    order) whether it answered and whether its status carried the hardware-error alert bit."""

    positions: np.ndarray
    velocities: np.ndarray
    currents: np.ndarray
    answered: np.ndarray
    alerts: np.ndarray


class ServoBus:
    """Every joint's servo on one bus.

    Args:
        robot: the robot (its ``[hardware]`` table).
        port: serial device (a USB2Dynamixel/U2D2, or an emulator's pty).
        baud: baud rate; default ``hardware.baud``.
    """

    def __init__(self, robot: Robot, port: str, baud: int | None = None) -> None:
        hardware = robot.hardware
        if not hardware.servos:
            raise HardwareError(f"{robot.name}: no [hardware.servos] table (map every joint to a servo id)")
        self.robot, self.port_name, self.baud = robot, port, baud or hardware.baud
        self.ticks = hardware.ticks_per_revolution
        self.slots = [Slot(f"{leg}_{joint}", i, k, hardware.servos[f"{leg}_{joint}"].id,
                           MODELS[hardware.servos[f"{leg}_{joint}"].model or hardware.model],
                           hardware.servos[f"{leg}_{joint}"].direction, hardware.servos[f"{leg}_{joint}"].zero_ticks)
                      for i, (leg, spec) in enumerate(robot.legs.items()) for k, joint in enumerate(spec.joints)]
        self.shape = (len(robot.legs), max(len(leg.joints) for leg in robot.legs.values()))
        self._rows = np.array([s.leg for s in self.slots])
        self._cols = np.array([s.joint for s in self.slots])
        self._direction = np.array([s.direction for s in self.slots], dtype=float)
        self._zero = np.array([s.zero for s in self.slots], dtype=float)
        self._port: Any = None
        self._handler: Any = None
        self.retries = 0
        """Sync reads repeated because a reply was missing or corrupt."""

    # -- opening and checking --------------------------------------------------------------------------------

    def open(self) -> None:
        from dynamixel_sdk import GroupSyncRead, PacketHandler, PortHandler

        port = PortHandler(self.port_name)
        try:
            opened = port.openPort()
        except Exception as error:  # pyserial raises several types; all mean "cannot open"
            reason = "no such device" if not os.path.exists(self.port_name) else str(error) or type(error).__name__
            raise HardwareError(f"{self.port_name}: cannot open the serial port: {reason} "
                                "(give the servo bus adapter with --port, e.g. /dev/ttyUSB0)") from None
        if not opened or not port.setBaudRate(self.baud):
            raise HardwareError(f"{self.port_name}: cannot open the serial port at {self.baud} baud "
                                "(check --port and --baud or hardware.baud)")
        self._port, self._handler = port, PacketHandler(2.0)
        self._state_reader = GroupSyncRead(port, self._handler, STATE_ADDRESS, STATE_LENGTH)
        self._error_reader = GroupSyncRead(port, self._handler, self.slots[0].model.hardware_error_status, 1)
        for slot in self.slots:
            self._state_reader.addParam(slot.servo_id)
            self._error_reader.addParam(slot.servo_id)

    def close(self) -> None:
        if self._port is not None:
            self._port.closePort()
            self._port = None

    def check(self) -> list[str]:
        """Every problem that must stop a start: missing servos, wrong models, hardware errors (one text each)."""
        from dynamixel_sdk import COMM_SUCCESS

        found, result = self._handler.broadcastPing(self._port)
        problems = []
        if result != COMM_SUCCESS and not found:
            return [f"no servo answers a broadcast ping on {self.port_name} at {self.baud} baud"]
        for slot in self.slots:
            if slot.servo_id not in found:
                problems.append(f"{slot.key}: servo {slot.servo_id} does not answer")
            elif slot.model.model_number and found[slot.servo_id][0] != slot.model.model_number:
                problems.append(f"{slot.key}: servo {slot.servo_id} is model number {found[slot.servo_id][0]}, "
                                f"not a {slot.model.name} ({slot.model.model_number})")
        if not problems:
            problems += [f"{key}: hardware error ({', '.join(names)})" for key, names in self.hardware_errors().items()]
        return problems

    # -- the cycle -------------------------------------------------------------------------------------------

    def read_state(self) -> BusState:
        """One sync read of current, velocity and position of every servo, keeping each status packet's error byte
        (its alert bit says a Hardware Error Status bit is set). A read that misses a reply is repeated once at once,
        after clearing the port, before the servos from that one on count as missing."""
        from dynamixel_sdk import COMM_SUCCESS

        count = len(self.slots)
        raw = np.zeros((count, STATE_LENGTH), dtype=np.uint8)
        answered = np.zeros(count, dtype=bool)
        alerts = np.zeros(count, dtype=bool)
        for attempt in range(2):
            self._state_reader.txPacket()
            for index, slot in enumerate(self.slots):
                data, result, error = self._handler.readRx(self._port, slot.servo_id, STATE_LENGTH)
                if result != COMM_SUCCESS:
                    break
                raw[index] = data
                answered[index] = True
                alerts[index] = bool(error & p2.ERROR_ALERT)
            if answered.all() or attempt:
                break
            self._port.clearPort()
            self.retries += 1
            answered[:] = False
        current = raw[:, 0:2].copy().view("<i2")[:, 0].astype(float)
        velocity = raw[:, 2:6].copy().view("<i4")[:, 0].astype(float)
        ticks = raw[:, 6:10].copy().view("<i4")[:, 0].astype(float)
        currents = current * np.array([s.model.current_unit_ma for s in self.slots])
        positions = self._direction * (ticks - self._zero) * (2.0 * math.pi / self.ticks)
        rpm = np.array([s.model.velocity_unit_rpm for s in self.slots])
        velocities = self._direction * velocity * rpm * (2.0 * math.pi / 60.0)
        return BusState(self.padded(positions), self.padded(velocities), self.padded(currents), answered, alerts)

    def hardware_errors(self) -> dict[str, list[str]]:
        """Servos whose Hardware Error Status is set (or that did not answer its read), by joint."""
        from dynamixel_sdk import COMM_SUCCESS

        reader = self._error_reader
        if reader.txRxPacket() != COMM_SUCCESS:
            self._port.clearPort()
            self.retries += 1
            reader.txRxPacket()
        out: dict[str, list[str]] = {}
        for slot in self.slots:
            if not reader.isAvailable(slot.servo_id, slot.model.hardware_error_status, 1):
                out[slot.key] = ["no reply"]
                continue
            bits = reader.getData(slot.servo_id, slot.model.hardware_error_status, 1)
            if bits:
                out[slot.key] = hardware_error_names(bits) or [f"bits {bits:#04x}"]
        return out

    def write_goals(self, joints: np.ndarray) -> None:
        """One sync write of every goal position ``(L, n)`` [rad]."""
        from dynamixel_sdk import GroupSyncWrite

        values = joints[self._rows, self._cols]
        ticks = np.rint(self._zero + self._direction * values * (self.ticks / (2.0 * math.pi))).astype(np.int64)
        model = self.slots[0].model
        writer = GroupSyncWrite(self._port, self._handler, model.goal_position, 4)
        payload = bytearray()
        for slot, tick in zip(self.slots, ticks.tolist(), strict=True):
            data = int(tick).to_bytes(4, "little", signed=True)
            writer.addParam(slot.servo_id, data)
            payload += bytes([slot.servo_id]) + data
        if p2.needs_stuffing(bytes(payload)):
            raise HardwareError("a goal payload contains FF FF FD, which dynamixel-sdk would send unstuffed")
        writer.txPacket()

    def torque(self, on: bool) -> None:
        """Torque enable (or disable) on every servo, one sync write."""
        from dynamixel_sdk import GroupSyncWrite

        writer = GroupSyncWrite(self._port, self._handler, self.slots[0].model.torque_enable, 1)
        for slot in self.slots:
            writer.addParam(slot.servo_id, bytes([1 if on else 0]))
        writer.txPacket()

    def padded(self, values: np.ndarray) -> np.ndarray:
        out = np.zeros(self.shape)
        out[self._rows, self._cols] = values
        return out

    def wire_time(self) -> float:
        """Seconds one cycle's sync read (instruction + every status) and sync write occupy a real bus at this baud
        (10 bits per byte on the wire; return delays not counted)."""
        count = len(self.slots)
        read = 14 + count + count * (11 + STATE_LENGTH)
        write = 14 + count * 5
        return (read + write) * 10.0 / self.baud


def _signed(value: int, bits: int) -> int:
    return value - (1 << bits) if value >= 1 << (bits - 1) else value
