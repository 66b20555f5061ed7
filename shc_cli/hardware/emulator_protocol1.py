"""Buses of emulated Dynamixel Protocol 1.0 servos (AX-12A/AX-18A, MX with 1.0 firmware) or Feetech STS servos
behind a pseudo-terminal, for testing without hardware; written from the vendors' documents.

Sources: ROBOTIS e-Manual "DYNAMIXEL Protocol 1.0" (packet, checksum, instructions, status error bits, Status
Return Level) and the AX-12A and MX-64(1.0) control tables; Feetech's SMS/STS memory table and its protocol
manual (same framing and checksum as Protocol 1.0; SYNC READ 0x82; Response Status Level at 8; sign-magnitude speed
(bit 15) and load (bit 10)). Nothing here is taken from shc's bus code: the emulator is what it is tested against.

``Protocol1Emulator(servos).start()`` opens a pty pair; open ``emulator.port`` with dynamixel-sdk's Protocol 1.0
handler or feetech-servo-sdk as if it were the USB adapter. Each servo has its control table and a first-order
position response while its torque is on (``present += (goal − present)·(1 − e^(−Δt/τ))``, capped at the model's
no-load speed); with ``dynamics`` (a robot file's ``[servo]`` table) a load-free servo joint of that model instead
(:mod:`shc_cli.backends.servo_joint`, as the Protocol 2.0 emulator's), whose motor current is reported as Present
Load (0.1 % steps of the datasheet's stall current, what the host's bus reads back as current), MX(1.0) Current
(4.5 mA steps about 2048) and Feetech Present Current (6.5 mA steps, its magnitude). With ``wire_time`` the
bus keeps the baud rate's time line: an instruction ends its bytes' time after it arrives, each status packet
goes out the servo's Return Delay Time after the bus fell silent plus its own bytes' time; ``latency_s`` adds a
USB adapter's turnaround to each answered instruction.

Faults per servo (:class:`Faults`, changed at any time): no reply, the next k replies dropped, a corrupt checksum,
error bits (voltage, overheating, overload: in every status packet while set; a bit in Shutdown also turns the
torque off), overload at the next goal write, vanishing after a number of packets, replies later than
``late_reply_s``.

Choices where the documents leave room (each marked ``choice``): a write outside an item's range is refused with
the Range Error bit (Protocol 1.0) and not applied; a Goal Position outside the angle limits gets the Angle Limit
Error bit and is not applied; writes to read-only items get the Range Error bit; BULK READ replies come in the
order listed, and a listed servo that does not answer stops the chain (the e-Manual: each servo waits for the
previous one's status packet); Feetech SYNC READ replies come in the order listed and skip a silent servo; Lock
(Feetech 55) does not block writes (it only keeps them from flash, which is not emulated).
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import threading
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from shc_cli.hardware import protocol1 as p1
from shc_cli.hardware.emulator import line_speed_matches, serve_promptly

if TYPE_CHECKING:
    from shc_cli.backends.servo_joint import FreeJoints
    from shc_cli.spec.robot import Servo

Vendor = Literal["dynamixel", "feetech"]


@dataclass(frozen=True)
class Item:
    """One control-table item (little-endian)."""

    address: int
    size: int
    name: str
    writable: bool
    default: int = 0
    low: int = 0
    high: int = 0


def _ax_table(model_number: int, ticks: int, mx: bool) -> list[Item]:
    """e-Manual AX-12A control table; ``mx``: the MX(1.0) one (D/I/P gains at 26–28, Current at 68)."""
    items = [
        Item(0, 2, "Model Number", False, model_number), Item(2, 1, "Firmware Version", False, 36 if mx else 24),
        Item(3, 1, "ID", True, 1, 0, 253), Item(4, 1, "Baud Rate", True, 34 if mx else 1, 0, 254),
        Item(5, 1, "Return Delay Time", True, 250, 0, 254), Item(6, 2, "CW Angle Limit", True, 0, 0, ticks - 1),
        Item(8, 2, "CCW Angle Limit", True, ticks - 1, 0, ticks - 1),
        Item(11, 1, "Temperature Limit", True, 70 if not mx else 80, 0, 99),
        Item(12, 1, "Min Voltage Limit", True, 60, 50, 160), Item(13, 1, "Max Voltage Limit", True, 140, 50, 160),
        Item(14, 2, "Max Torque", True, 1023, 0, 1023), Item(16, 1, "Status Return Level", True, 2, 0, 2),
        Item(17, 1, "Alarm LED", True, 36, 0, 127), Item(18, 1, "Shutdown", True, 36, 0, 127),
        Item(24, 1, "Torque Enable", True, 0, 0, 1), Item(25, 1, "LED", True, 0, 0, 1),
        Item(30, 2, "Goal Position", True, 0, 0, ticks - 1), Item(32, 2, "Moving Speed", True, 0, 0, 1023),
        Item(34, 2, "Torque Limit", True, 1023, 0, 1023), Item(36, 2, "Present Position", False),
        Item(38, 2, "Present Speed", False), Item(40, 2, "Present Load", False),
        Item(42, 1, "Present Voltage", False, 120), Item(43, 1, "Present Temperature", False, 32),
        Item(44, 1, "Registered", False), Item(46, 1, "Moving", False), Item(47, 1, "Lock", True, 0, 0, 1),
        Item(48, 2, "Punch", True, 32, 0, 1023),
    ]
    if mx:
        items += [Item(26, 1, "D Gain", True, 0, 0, 254), Item(27, 1, "I Gain", True, 0, 0, 254),
                  Item(28, 1, "P Gain", True, 32, 0, 254), Item(68, 2, "Current", False, 2048),
                  Item(73, 1, "Goal Acceleration", True, 0, 0, 254)]
    else:
        items += [Item(26, 1, "CW Compliance Margin", True, 1, 0, 255),
                  Item(27, 1, "CCW Compliance Margin", True, 1, 0, 255),
                  Item(28, 1, "CW Compliance Slope", True, 32, 1, 254),
                  Item(29, 1, "CCW Compliance Slope", True, 32, 1, 254)]
    return items


def _sts_table(model_number: int) -> list[Item]:
    """Feetech SMS/STS memory table (EEPROM 0–39, SRAM 40–70)."""
    return [
        Item(0, 1, "Firmware Major Version", False, 3), Item(1, 1, "Firmware Minor Version", False, 10),
        Item(3, 2, "Servo Version (model number)", False, model_number), Item(5, 1, "ID", True, 1, 0, 253),
        Item(6, 1, "Baud Rate", True, 0, 0, 7), Item(7, 1, "Return Delay Time", True, 0, 0, 254),
        Item(8, 1, "Response Status Level", True, 1, 0, 1), Item(9, 2, "Min Angle Limit", True, 0, 0, 4094),
        Item(11, 2, "Max Angle Limit", True, 4095, 1, 4095), Item(13, 1, "Max Temperature Limit", True, 70, 0, 100),
        Item(14, 1, "Max Input Voltage", True, 80, 0, 254), Item(15, 1, "Min Input Voltage", True, 40, 0, 254),
        Item(16, 2, "Max Torque", True, 1000, 0, 1000), Item(18, 1, "Phase", True, 12, 0, 254),
        Item(19, 1, "Unloading Condition", True, 44, 0, 254), Item(20, 1, "LED Alarm Condition", True, 47, 0, 254),
        Item(21, 1, "P Coefficient", True, 32, 0, 254), Item(22, 1, "D Coefficient", True, 32, 0, 254),
        Item(23, 1, "I Coefficient", True, 0, 0, 254), Item(24, 2, "Minimum Startup Force", True, 16, 0, 1000),
        Item(26, 1, "CW Dead Zone", True, 1, 0, 32), Item(27, 1, "CCW Dead Zone", True, 1, 0, 32),
        Item(28, 2, "Protection Current", True, 500, 0, 511), Item(30, 1, "Angular Resolution", True, 1, 1, 100),
        Item(31, 2, "Position Correction", True, 0, 0, 4095), Item(33, 1, "Operating Mode", True, 0, 0, 3),
        Item(34, 1, "Protective Torque", True, 20, 0, 100), Item(35, 1, "Protection Time", True, 200, 0, 254),
        Item(36, 1, "Overload Torque", True, 80, 0, 100), Item(40, 1, "Torque Enable", True, 0, 0, 128),
        Item(41, 1, "Acceleration", True, 0, 0, 254), Item(42, 2, "Goal Position", True, 0, 0, 65535),
        Item(44, 2, "Goal Time", True, 0, 0, 65535), Item(46, 2, "Goal Speed", True, 0, 0, 65535),
        Item(48, 2, "Torque Limit", True, 1000, 0, 1000), Item(55, 1, "Lock", True, 0, 0, 1),
        Item(56, 2, "Present Position", False), Item(58, 2, "Present Speed", False),
        Item(60, 2, "Present Load", False), Item(62, 1, "Present Voltage", False, 74),
        Item(63, 1, "Present Temperature", False, 30), Item(64, 1, "Async Write Flag", False),
        Item(65, 1, "Servo Status", False), Item(66, 1, "Moving", False), Item(69, 2, "Present Current", False),
    ]


@dataclass(frozen=True)
class EmulatedModel:
    """What the emulator needs of a model: its table and units."""

    name: str
    vendor: Vendor
    items: tuple[Item, ...]
    resolution: int
    range_degrees: float
    no_load_rpm: float
    bulk_read: bool = False


EMULATED_MODELS = {
    "AX-12A": EmulatedModel("AX-12A", "dynamixel", tuple(_ax_table(12, 1024, False)), 1024, 300.0, 59.0),
    "AX-18A": EmulatedModel("AX-18A", "dynamixel", tuple(_ax_table(18, 1024, False)), 1024, 300.0, 97.0),
    "MX-64(1.0)": EmulatedModel("MX-64(1.0)", "dynamixel", tuple(_ax_table(310, 4096, True)), 4096, 360.0, 63.0,
                                True),
    "MX-106(1.0)": EmulatedModel("MX-106(1.0)", "dynamixel", tuple(_ax_table(320, 4096, True)), 4096, 360.0, 45.0,
                                 True),
    "STS3215": EmulatedModel("STS3215", "feetech", tuple(_sts_table(777)), 4096, 360.0, 52.0),
}
"""By name (model numbers: e-Manual control tables; STS3215: 777, the word at address 3 low byte first)."""

# addresses the emulator itself acts on, per vendor
_ADDR = {
    "dynamixel": {"id": 3, "delay": 5, "cw": 6, "ccw": 8, "level": 16, "shutdown": 18, "torque": 24, "goal": 30,
                  "position": 36, "speed": 38, "load": 40, "moving": 46},
    "feetech": {"id": 5, "delay": 7, "cw": 9, "ccw": 11, "level": 8, "shutdown": 19, "torque": 40, "goal": 42,
                "position": 56, "speed": 58, "load": 60, "moving": 66},
}
OVERLOAD, OVERHEATING, VOLTAGE = 32, 4, 1
"""Error bits both vendors use for these conditions."""
RANGE_ERROR, ANGLE_ERROR, CHECKSUM_ERROR, INSTRUCTION_ERROR = 8, 2, 16, 64


@dataclass
class Faults:
    """Injectable faults of one servo (the test thread may change them at any time)."""

    no_reply: bool = False
    corrupt_checksum: bool = False
    error_bits: int = 0
    """Conditions reported in every status packet (voltage 1, overheating 4, overload 32)."""
    overload_at_goal: bool = False
    """Overload at the next Goal Position write."""
    vanish_after_packets: int | None = None
    late_reply_s: float = 0.0
    """Extra delay of every status packet [s] (longer than the host's timeout: a late reply)."""
    drop_replies: int = 0
    """The next this many status packets of the servo are not sent (each a missed reply; then it answers again)."""


class EmulatedServo:
    """One servo: its control table, motion and faults."""

    def __init__(self, servo_id: int, model: EmulatedModel, clock: Callable[[], float], time_constant: float,
                 position: int | None = None, dynamics: Servo | None = None) -> None:
        self.model = model
        self.addr = _ADDR[model.vendor]
        self.items = {item.address: item for item in model.items}
        self.owner = {item.address + k: item for item in model.items for k in range(item.size)}
        self.table = bytearray(max(self.owner) + 1)
        for item in model.items:
            self.set(item.address, item.default)
        self.set(self.addr["id"], servo_id)
        self.key = servo_id
        self.clock = clock
        self.time_constant = time_constant
        self.position = float(model.resolution // 2 if position is None else position)
        self.joint: FreeJoints | None = None
        """The load-free joint of ``dynamics`` (None: the first-order lag)."""
        self.stall_current = 1.0
        """The datasheet's stall current [A]: Present Load's full scale with ``dynamics``."""
        if dynamics is not None:
            from shc_cli.backends.servo_joint import FreeJoints
            from shc_cli.spec.servo_models import DATASHEETS

            self.joint = FreeJoints(dynamics, 1, self.position / self.ticks_per_radian)
            sheet = DATASHEETS.get(model.name)
            self.stall_current = sheet.stall_current if sheet is not None else float(dynamics.current_limit)
        self.set(self.addr["goal"], round(self.position))
        self.faults = Faults()
        self.conditions = 0
        self.packets_seen = 0
        self.rejected: list[tuple[int, bytes, int]] = []
        """(address, data, error bits) of every refused write."""
        self._updated = clock()
        self.advance()

    @property
    def ticks_per_radian(self) -> float:
        return self.model.resolution * 360.0 / self.model.range_degrees / (2.0 * math.pi)

    def get(self, address: int) -> int:
        item = self.items[address]
        return int.from_bytes(self.table[address:address + item.size], "little")

    def set(self, address: int, value: int) -> None:
        item = self.items[address]
        self.table[address:address + item.size] = (value % (1 << (8 * item.size))).to_bytes(item.size, "little")

    @property
    def servo_id(self) -> int:
        return self.table[self.addr["id"]]

    @property
    def torque_on(self) -> bool:
        return self.table[self.addr["torque"]] != 0

    @property
    def vanished(self) -> bool:
        limit = self.faults.vanish_after_packets
        return limit is not None and self.packets_seen > limit

    @property
    def error_byte(self) -> int:
        """The conditions every status packet reports."""
        return (self.conditions | self.faults.error_bits) & 0x7F

    def protect(self, bits: int) -> None:
        """A condition appears; a bit in Shutdown (Feetech: Unloading Condition) turns the torque off."""
        self.conditions |= bits
        if bits & self.table[self.addr["shutdown"]]:
            self.table[self.addr["torque"]] = 0

    def read(self, address: int, length: int) -> tuple[int, bytes]:
        self.advance()
        if length == 0 or address + length > len(self.table):
            return RANGE_ERROR, b""  # choice: beyond the table
        return 0, bytes(self.table[address:address + length])

    def write(self, address: int, data: bytes) -> int:
        """Checks and applies a write; returns the error bits (0: applied)."""
        self.advance()
        error = self._check(address, data)
        if error:
            self.rejected.append((address, bytes(data), error))
            return error
        self.table[address:address + len(data)] = data
        goal = self.addr["goal"]
        if address <= goal < address + len(data) and self.faults.overload_at_goal:
            self.protect(OVERLOAD)
        if address <= self.addr["torque"] < address + len(data) and self.table[self.addr["torque"]]:
            self.conditions &= ~OVERLOAD  # torque on again clears the overload (e-Manual: set Torque Enable)
        return 0

    def _check(self, address: int, data: bytes) -> int:
        end = address + len(data)
        if not data or any(a not in self.owner for a in range(address, end)):
            return RANGE_ERROR  # choice: undefined addresses
        at = address
        while at < end:
            item = self.owner[at]
            if item.address < address or item.address + item.size > end:
                return RANGE_ERROR  # choice: a write covers whole items
            value = int.from_bytes(data[at - address:at - address + item.size], "little")
            if not item.writable or not item.low <= value <= item.high:
                return RANGE_ERROR
            if item.address == self.addr["goal"]:
                low, high = self.get(self.addr["cw"]), self.get(self.addr["ccw"])
                if self.model.vendor == "feetech":
                    value = -(value & 0x7FFF) if value & 0x8000 else value
                if (low or high) and not low <= value <= high:
                    return ANGLE_ERROR
            at = item.address + item.size
        return 0

    def advance(self) -> None:
        """First-order motion towards the goal since the last access (torque on), and the present values."""
        now = self.clock()
        elapsed, self._updated = now - self._updated, now
        goal_raw = self.get(self.addr["goal"])
        goal = float(-(goal_raw & 0x7FFF) if self.model.vendor == "feetech" and goal_raw & 0x8000 else goal_raw)
        before = self.position
        if self.joint is not None:
            self._move(goal, elapsed)
            return
        if self.torque_on and elapsed > 0:
            ticks_per_turn = self.model.resolution * 360.0 / self.model.range_degrees
            cap = self.model.no_load_rpm / 60.0 * ticks_per_turn * elapsed
            step = (goal - before) * (1.0 - math.exp(-elapsed / self.time_constant))
            self.position = before + max(-cap, min(cap, step))
        self.position = max(0.0, min(self.model.resolution - 1.0, self.position))
        speed = (self.position - before) / elapsed if elapsed > 0 else 0.0  # [ticks/s]
        load = max(-1000.0, min(1000.0, (goal - self.position) * 20.0)) if self.torque_on else 0.0  # [0.1 %]
        self.set(self.addr["position"], round(self.position))
        if self.model.vendor == "feetech":
            self.set(self.addr["speed"], _magnitude(round(speed), 15))  # steps/s, bit 15 the sign
            self.set(self.addr["load"], _magnitude(round(load), 10))
            self.table[65] = self.error_byte
            self.set(69, round(abs(load) * 0.4))
        else:
            ticks_per_turn = self.model.resolution * 360.0 / self.model.range_degrees
            unit = 0.111 if self.model.resolution == 1024 else 0.114  # [rpm]
            self.set(self.addr["speed"], _magnitude(round(speed / ticks_per_turn * 60.0 / unit), 10))
            self.set(self.addr["load"], _magnitude(round(load), 10))
            if 68 in self.items:
                self.set(68, 2048 + round(load))
        self.table[self.addr["moving"]] = int(abs(goal - self.position) > 1.0 and self.torque_on)

    def _move(self, goal: float, elapsed: float) -> None:
        """The load-free joint over ``elapsed`` [s] towards ``goal`` [ticks], its state into the table (a joint
        driven past the ends of the range stops there)."""
        joint, per_radian = self.joint, self.ticks_per_radian
        assert joint is not None
        if elapsed > 0:
            joint.advance(goal / per_radian, elapsed, self.torque_on)
        ticks = float(joint.position[0]) * per_radian
        if not 0.0 <= ticks <= self.model.resolution - 1.0:
            ticks = max(0.0, min(self.model.resolution - 1.0, ticks))
            joint.position[:], joint.speed[:] = ticks / per_radian, 0.0
        self.position = ticks
        speed = float(joint.speed[0]) * per_radian  # [ticks/s]
        amps = float(joint.current[0])
        load = max(-1000.0, min(1000.0, amps / self.stall_current * 1000.0))  # [0.1 %]
        self.set(self.addr["position"], round(self.position))
        if self.model.vendor == "feetech":
            self.set(self.addr["speed"], _magnitude(round(speed), 15))
            self.set(self.addr["load"], _magnitude(round(load), 10))
            self.table[65] = self.error_byte
            self.set(69, min(65535, round(abs(amps) / 0.0065)))
        else:
            unit = 0.111 if self.model.resolution == 1024 else 0.114  # [rpm]
            rpm = speed / (per_radian * 2.0 * math.pi) * 60.0
            self.set(self.addr["speed"], _magnitude(round(rpm / unit), 10))
            self.set(self.addr["load"], _magnitude(round(load), 10))
            if 68 in self.items:
                self.set(68, max(0, min(4095, 2048 + round(amps / 0.0045))))
        self.table[self.addr["moving"]] = int(abs(goal - self.position) > 1.0 and self.torque_on)

    def answers(self, instruction: int) -> bool:
        """Status Return Level: Dynamixel 0 PING only, 1 PING and READ, 2 all; Feetech 0 PING and READ, 1 all."""
        level = self.table[self.addr["level"]]
        if instruction == p1.PING:
            return True
        if instruction in (p1.READ, p1.SYNC_READ, p1.BULK_READ):
            return level >= 1 or self.model.vendor == "feetech"
        return level >= (1 if self.model.vendor == "feetech" else 2)


def _magnitude(value: int, bit: int) -> int:
    """Sign-magnitude: ``bit`` set for a negative value."""
    return (-value | (1 << bit)) if value < 0 else value


class Protocol1Emulator:
    """Servos on one emulated Protocol 1.0 (or Feetech) bus behind a pseudo-terminal.

    Args:
        servos: servo id → model name (:data:`EMULATED_MODELS`), all of one vendor.
        baud: the bus's bit rate [bit/s] (for ``wire_time``).
        wire_time: keep the bus's time line (instruction and status bytes at ``baud``, 10 bits per byte).
        latency_s: a USB adapter's turnaround added before each answered instruction's first status [s].
        time_constant: the position response's time constant [s].
        clock: the servos' clock [s].
        positions: power-up present positions [ticks] by id (default the middle of the range).
        dynamics: the servo model of every servo (a robot file's ``[servo]`` table: load-free servo joints), or
            None for the first-order lag.
        check_baud: packets sent at a line speed other than ``baud`` go unheard (as on a real bus).
    """

    def __init__(self, servos: dict[int, str], baud: int = 1_000_000, wire_time: bool = False,
                 latency_s: float = 0.0, time_constant: float = 0.03, clock: Callable[[], float] = time.monotonic,
                 positions: dict[int, int] | None = None, dynamics: Servo | None = None,
                 check_baud: bool = False) -> None:
        self.servos = {i: EmulatedServo(i, EMULATED_MODELS[name], clock, time_constant, (positions or {}).get(i),
                                        dynamics) for i, name in sorted(servos.items())}
        vendors = {servo.model.vendor for servo in self.servos.values()}
        if len(vendors) > 1:
            raise ValueError("one vendor per bus")
        self.vendor: Vendor = vendors.pop() if vendors else "dynamixel"
        self.baud, self.wire_time, self.latency_s = baud, wire_time, latency_s
        self.check_baud = check_baud
        self.packets: list[p1.Packet] = []
        """Every instruction packet received with a good checksum, in order."""
        self.checksum_errors = 0
        self.lock = threading.RLock()
        self._master, self._slave = os.openpty()
        tty.setraw(self._master)
        tty.setraw(self._slave)
        self.port = os.ttyname(self._slave)
        self._wake_r, self._wake_w = os.pipe()
        self._stop = False
        self._thread = threading.Thread(target=self._serve, name="protocol1-emulator", daemon=True)

    def start(self) -> Protocol1Emulator:
        self._thread.start()
        return self

    def stop(self) -> None:
        if self._stop:
            return
        self._stop = True
        os.write(self._wake_w, b"x")
        self._thread.join(timeout=5.0)
        for fd in (self._master, self._slave, self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)

    def __enter__(self) -> Protocol1Emulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def faults(self, servo_id: int) -> Faults:
        return self.servos[servo_id].faults

    def goal(self, servo_id: int) -> int:
        with self.lock:
            servo = self.servos[servo_id]
            return servo.get(servo.addr["goal"])

    def position(self, servo_id: int) -> int:
        with self.lock:
            servo = self.servos[servo_id]
            servo.advance()
            return round(servo.position)

    def protect(self, servo_id: int, bits: int = OVERLOAD) -> None:
        """The servo's own protection trips now (overload by default): the bits go into every status packet and
        a bit in Shutdown turns its torque off."""
        with self.lock:
            self.servos[servo_id].protect(bits)

    def torque_on(self, servo_id: int) -> bool:
        with self.lock:
            return self.servos[servo_id].torque_on

    # -- the wire ------------------------------------------------------------------------------------------

    def _serve(self) -> None:
        serve_promptly()
        buffer = bytearray()
        while not self._stop:
            ready, _, _ = select.select([self._master, self._wake_r], [], [], 0.5)
            if self._wake_r in ready or self._master not in ready:
                continue
            try:
                chunk = os.read(self._master, 4096)
            except OSError:
                return
            arrived = time.monotonic()
            if self.check_baud and not line_speed_matches(self._slave, self.baud):
                continue
            buffer += chunk
            while True:
                try:
                    incoming = p1.parse(buffer)
                except p1.PacketError:
                    self.checksum_errors += 1
                    continue
                if incoming is None:
                    break
                with self.lock:
                    self.packets.append(incoming)
                    replies = self._handle(incoming)
                size = len(incoming.params) + 6
                self._transmit(replies, arrived + (size * 10.0 / self.baud if self.wire_time else 0.0))

    def _transmit(self, replies: list[tuple[EmulatedServo, bytes]], bus_free: float) -> None:
        """Each status packet its servo's Return Delay Time after the bus fell silent (plus its bytes' time). A
        chain's packets go out together when the last is due: the host has them all at the same time as on the wire,
        and the thread wakes once (a loaded computer's scheduling would stretch a packet-by-packet chain)."""
        if replies and self.latency_s:
            bus_free += self.latency_s
        due = bus_free
        for servo, data in replies:
            delay = servo.table[servo.addr["delay"]] * 2e-6 + servo.faults.late_reply_s
            due += delay + (len(data) * 10.0 / self.baud if self.wire_time else 0.0)
        if not replies:
            return
        wait = due - time.monotonic()
        if wait > 0.002:
            time.sleep(wait - 0.001)
        while time.monotonic() < due:  # the last millisecond spun: a sleep of microseconds overshoots
            pass
        with contextlib.suppress(OSError):
            os.write(self._master, b"".join(data for _, data in replies))

    def _status(self, servo: EmulatedServo, error: int = 0, params: bytes = b"") -> list[tuple[EmulatedServo, bytes]]:
        if servo.faults.no_reply or servo.vanished:
            return []
        if servo.faults.drop_replies > 0:
            servo.faults.drop_replies -= 1
            return []
        data = bytearray(p1.status(servo.servo_id, error | servo.error_byte, params))
        if servo.faults.corrupt_checksum:
            data[-1] ^= 0xFF
        return [(servo, bytes(data))]

    def _handle(self, incoming: p1.Packet) -> list[tuple[EmulatedServo, bytes]]:
        listening = [s for s in self.servos.values() if not s.vanished]
        by_id = {s.servo_id: s for s in listening}
        instruction, params = incoming.instruction, incoming.params
        broadcast = incoming.servo == p1.BROADCAST
        for servo in listening:
            if broadcast or servo.servo_id == incoming.servo:
                servo.packets_seen += 1
        if broadcast:
            return self._broadcast(instruction, params, by_id)
        target = by_id.get(incoming.servo)
        if target is None or target.vanished:
            return []
        if instruction == p1.PING:
            return self._status(target)
        if instruction == p1.READ and len(params) == 2:
            error, data = target.read(params[0], params[1])
            return self._status(target, error, data) if target.answers(p1.READ) else []
        if instruction == p1.WRITE and len(params) >= 2:
            error = target.write(params[0], params[1:])
            return self._status(target, error) if target.answers(p1.WRITE) else []
        return self._status(target, INSTRUCTION_ERROR) if target.answers(instruction) else []

    def _broadcast(self, instruction: int, params: bytes, by_id: dict[int, EmulatedServo]
                   ) -> list[tuple[EmulatedServo, bytes]]:
        """Broadcast instructions: no status packet, except the reads' chains."""
        replies: list[tuple[EmulatedServo, bytes]] = []
        if instruction == p1.WRITE and len(params) >= 2:
            for each in by_id.values():
                each.write(params[0], params[1:])
        elif instruction == p1.SYNC_WRITE and len(params) >= 3:
            address, length = params[0], params[1]
            for at in range(2, len(params) - length, 1 + length):
                servo: EmulatedServo | None = by_id.get(params[at])
                if servo is not None:
                    servo.write(address, params[at + 1:at + 1 + length])
        elif instruction == p1.SYNC_READ and self.vendor == "feetech" and len(params) >= 3:
            address, length = params[0], params[1]
            for servo_id in params[2:]:
                servo = by_id.get(servo_id)
                if servo is not None:
                    error, data = servo.read(address, length)
                    replies += self._status(servo, error, data)
        elif instruction == p1.BULK_READ and self.vendor == "dynamixel" and len(params) >= 4 and params[0] == 0:
            for at in range(1, len(params) - 2, 3):
                length, servo_id, address = params[at], params[at + 1], params[at + 2]
                servo = by_id.get(servo_id)
                if servo is None or not servo.model.bulk_read:
                    break  # the next servo waits for this one's status packet: the chain stops
                error, data = servo.read(address, length)
                answer = self._status(servo, error, data)
                if not answer:
                    break
                replies += answer
        return replies
