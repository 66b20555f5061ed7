"""A Dynamixel Protocol 2.0 servo bus on a pseudo-terminal, written from the ROBOTIS e-Manual alone.

Sources: the e-Manual page "DYNAMIXEL Protocol 2.0" (packet layout, byte stuffing, CRC-16, the instructions and
their worked examples, the error numbers) and the control tables of the MX-106(2.0) and XM430-W210 pages
(addresses, sizes, access, initial values, ranges, units). Nothing here comes from shc: the emulator is the
independent reference the tests hold ``shc run-hw`` and dynamixel-sdk to.

The bus is a pty pair; :attr:`EManualBus.port` is the slave path, which a host opens like a USB2Dynamixel. A
daemon thread reads the master end with a byte-stream state machine, executes each instruction packet on the
emulated servos and writes their status packets, each after the servo's Return Delay Time.

Units (the e-Manual's): time [s] in the API; Return Delay Time 2 µs per unit; positions in ticks (4096 per
revolution, 0.088°); velocities 0.229 rpm per unit; currents in the model's unit (3.36 mA for the MX-106(2.0),
2.69 mA for the XM430); PWM 0.113 % per unit; voltages 0.1 V per unit; temperatures 1 °C.

Choices where the e-Manual leaves room (documented, each marked ``choice`` in the code):

* Writes must cover whole control-table items: a write that starts or ends inside an item is refused with Data
  Length Error (the e-Manual's example of that error is "2 bytes of a 4-byte item"); a write that touches an
  undefined address is refused with Access Error (the e-Manual's definition of that error). A read that touches
  an undefined address (a gap such as 14–19) also gets Access Error by default, as the e-Manual defines it;
  ``undefined_reads="zero"`` instead reads gaps inside the table as 0 (which hosts reading across gaps rely on).
* MX(2.0): Profile Velocity above Velocity Limit(44) is a Data Limit Error (its e-Manual page: "cannot exceed
  Velocity Limit", range 0 ~ Velocity Limit); the X-series table gives 0 ~ 32,767 and only caps the motion.
* A write with several items is checked completely before anything is applied: one bad item refuses all.
* Status Return Level 1 ("only for READ") also answers SYNC READ and BULK READ, which are reads.
* In a SYNC READ or BULK READ chain each listed servo answers its Return Delay Time after the previous status
  packet (or the instruction) ended; a listed servo that does not answer is skipped by the next one.
* Writing Torque Enable = 1 while a Shutdown bit is set in Hardware Error Status fails with Result Fail
  (the e-Manual: only REBOOT re-enables torque after a shutdown). REBOOT is acknowledged, then executed at once.
* FACTORY RESET is accepted (options 0xFF, 0x01, 0x02; not activated for the broadcast ID with option 0xFF, as
  the e-Manual says for firmware 42+) but refused with Access Error while the torque is on (it writes EEPROM).
* Instructions whose parameter count does not fit their layout are answered (unicast) with Data Length Error
  and recorded as protocol violations; broadcast ones are dropped and recorded.
* Motion is a first-order lag (time constant ``motion_time_constant_s``) capped by the model's no-load speed
  and, when non-zero, by Profile Velocity; present current and PWM are plausible functions of the error.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import select
import threading
import time
import tty
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from types import TracebackType

from shc_cli.hardware.emulator import serve_promptly

# -- protocol constants (e-Manual, Protocol 2.0) ---------------------------------------------------------------

HEADER = bytes([0xFF, 0xFF, 0xFD, 0x00])
"""Header 1–3 and Reserved."""
BROADCAST_ID = 0xFE
MAX_ID = 0xFC
"""IDs 0–252 address one device; 253 and 255 are never used (they would look like a header)."""

PING, READ, WRITE, REG_WRITE, ACTION, FACTORY_RESET, REBOOT, CLEAR = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x10
STATUS, SYNC_READ, SYNC_WRITE, BULK_READ, BULK_WRITE = 0x55, 0x82, 0x83, 0x92, 0x93
INSTRUCTION_NAMES = {PING: "PING", READ: "READ", WRITE: "WRITE", REG_WRITE: "REG WRITE", ACTION: "ACTION",
                     FACTORY_RESET: "FACTORY RESET", REBOOT: "REBOOT", CLEAR: "CLEAR", STATUS: "STATUS",
                     SYNC_READ: "SYNC READ", SYNC_WRITE: "SYNC WRITE", BULK_READ: "BULK READ",
                     BULK_WRITE: "BULK WRITE"}

RESULT_FAIL, INSTRUCTION_ERROR, CRC_ERROR, DATA_RANGE_ERROR, DATA_LENGTH_ERROR, DATA_LIMIT_ERROR, ACCESS_ERROR = (
    0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07)
ALERT = 0x80
"""Status error byte: bit 7 Alert (Hardware Error Status is non-zero), bits 0–6 the error number."""

# Hardware Error Status / Shutdown bits.
INPUT_VOLTAGE_ERROR, OVERHEATING_ERROR, MOTOR_ENCODER_ERROR, ELECTRICAL_SHOCK_ERROR, OVERLOAD_ERROR = (
    0x01, 0x04, 0x08, 0x10, 0x20)

BAUD_RATES = {0: 9600, 1: 57600, 2: 115200, 3: 1_000_000, 4: 2_000_000, 5: 3_000_000, 6: 4_000_000, 7: 4_500_000}
"""Baud Rate(8) value → bits per second (X series and MX(2.0))."""

TICKS_PER_REV = 4096
VELOCITY_UNIT_RPM = 0.229
RETURN_DELAY_UNIT_S = 2e-6


# -- CRC and byte stuffing -------------------------------------------------------------------------------------

def _crc_table() -> tuple[int, ...]:
    """The e-Manual's CRC-16 table: polynomial x^16 + x^15 + x^2 + 1 (0x8005), MSB first."""
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else crc << 1
        table.append(crc & 0xFFFF)
    return tuple(table)


CRC_TABLE = _crc_table()


def crc16(data: bytes | bytearray, crc: int = 0) -> int:
    """The e-Manual's ``update_crc``: CRC-16/0x8005, initial value 0, no reflection, no final XOR."""
    for byte in data:
        crc = ((crc << 8) ^ CRC_TABLE[((crc >> 8) ^ byte) & 0xFF]) & 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    """Byte stuffing of the inspection range (Instruction through the last parameter): after every
    ``FF FF FD`` one extra ``FD``."""
    out = bytearray()
    for index, byte in enumerate(body):
        out.append(byte)
        if byte == 0xFD and index >= 2 and body[index - 1] == 0xFF and body[index - 2] == 0xFF:
            out.append(0xFD)
    return bytes(out)


def unstuff(body: bytes) -> bytes:
    """Removes byte stuffing: ``FF FF FD FD`` → ``FF FF FD`` (looking back in the received, stuffed bytes)."""
    out = bytearray()
    for index, byte in enumerate(body):
        if byte == 0xFD and index >= 3 and body[index - 3:index] == b"\xff\xff\xfd":
            continue
        out.append(byte)
    return bytes(out)


def unstuffed_headers(body: bytes) -> list[int]:
    """Offsets in a received (stuffed) inspection range where ``FF FF FD`` is *not* followed by the stuffing
    ``FD``: a sender that forgot to stuff."""
    found = []
    index = 0
    while index + 3 <= len(body):
        if body[index:index + 3] == b"\xff\xff\xfd":
            if index + 3 < len(body) and body[index + 3] == 0xFD:
                index += 4
                continue
            found.append(index)
            index += 3
            continue
        index += 1
    return found


def packet(packet_id: int, instruction: int, params: bytes = b"") -> bytes:
    """A complete packet as the e-Manual's "Processing Order of Transmission": stuff, then the length of the
    stuffed packet, then the CRC over everything before it."""
    body = stuff(bytes([instruction]) + bytes(params))
    length = len(body) + 2
    head = HEADER + bytes([packet_id, length & 0xFF, length >> 8]) + body
    crc = crc16(head)
    return head + bytes([crc & 0xFF, crc >> 8])


def status_packet(packet_id: int, error: int, params: bytes = b"") -> bytes:
    """A status packet (instruction 0x55): error byte, then the parameters."""
    return packet(packet_id, STATUS, bytes([error]) + bytes(params))


# -- the stream parser -----------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Packet:
    """One packet taken off the wire.

    Attributes:
        t: monotonic time the last byte was read [s].
        packet_id: Packet ID.
        instruction: Instruction byte (0x55 for a status packet).
        params: parameters with byte stuffing removed (for a status packet: the error byte first).
        raw: the packet as received, header to CRC.
        crc_ok: whether the CRC matched.
        unstuffed_at: offsets in the inspection range of ``FF FF FD`` sent without stuffing.
    """

    t: float
    packet_id: int
    instruction: int
    params: bytes
    raw: bytes
    crc_ok: bool
    unstuffed_at: tuple[int, ...] = ()

    @property
    def error(self) -> int:
        """A status packet's error byte."""
        return self.params[0]

    @property
    def data(self) -> bytes:
        """A status packet's parameters after the error byte."""
        return self.params[1:]


@dataclass(frozen=True)
class Violation:
    """A malformed packet or stray bytes received from the host.

    Attributes:
        t: monotonic time [s].
        description: what was wrong.
        raw: the bytes concerned.
    """

    t: float
    description: str
    raw: bytes


class Parser:
    """Byte-stream state machine: Header1 FF, Header2 FF, Header3 FD, Reserved 00, ID, LEN_L, LEN_H, then
    LEN bytes (Instruction, parameters, CRC_L, CRC_H).

    Bytes before a header are skipped (and reported), a packet may arrive in any number of pieces, a packet
    whose CRC fails is reported and its bytes after its first one are searched again for a header (so a wrong
    length cannot swallow the next packet), and a packet left incomplete for ``inter_byte_timeout_s`` is
    dropped and reported.

    Args:
        inter_byte_timeout_s: longest silence inside a packet [s].
    """

    _H1, _H2, _H3, _RSRV, _ID, _LEN_L, _LEN_H, _BODY = range(8)

    def __init__(self, inter_byte_timeout_s: float = 0.1) -> None:
        self.inter_byte_timeout_s = inter_byte_timeout_s
        self._state = self._H1
        self._raw = bytearray()  # bytes of the current packet (header onwards)
        self._skipped = bytearray()  # bytes consumed while looking for a header
        self._quiet = 0  # leading bytes of _skipped already reported (those of a bad packet searched again)
        self._length = 0
        self._last_byte_t = 0.0

    def feed(self, data: bytes, now: float) -> list[Packet | Violation]:
        """Consumes ``data`` received at ``now`` [s]; returns the packets completed and the violations found."""
        out: list[Packet | Violation] = []
        pending = bytearray(data)
        index = 0
        if data:
            self._last_byte_t = now
        while index < len(pending):
            if self._state == self._BODY:
                need = self._length - (len(self._raw) - 7)
                chunk = pending[index:index + need]
                self._raw += chunk
                index += len(chunk)
                if len(self._raw) - 7 == self._length:
                    result = self._complete(now)
                    out.append(result)
                    if isinstance(result, Violation):  # bad CRC: look for a header again after its first byte
                        pending = bytearray(result.raw[1:]) + pending[index:]
                        index = 0
                        self._skipped.clear()
                        self._quiet = len(result.raw) - 1
                continue
            byte = pending[index]
            index += 1
            self._step(byte, now, out)
        return out

    def _step(self, byte: int, now: float, out: list[Packet | Violation]) -> None:
        state = self._state
        if state <= self._RSRV:
            self._skipped.append(byte)
            if state == self._H1:
                self._state = self._H2 if byte == 0xFF else self._H1
            elif state == self._H2:
                self._state = self._H3 if byte == 0xFF else self._H1
            elif state == self._H3:
                self._state = self._RSRV if byte == 0xFD else self._H3 if byte == 0xFF else self._H1
            elif byte == 0x00:
                garbage = bytes(self._skipped[:-4][self._quiet:])
                if garbage:
                    out.append(Violation(now, f"{len(garbage)} byte(s) outside any packet before a header", garbage))
                self._skipped.clear()
                self._quiet = 0
                self._raw = bytearray(HEADER)
                self._state = self._ID
            else:  # FF FF FD FD is stuffing, not a header; FF FF FD FF may start one
                self._state = self._H2 if byte == 0xFF else self._H1
            return
        self._raw.append(byte)
        if state == self._ID:
            if byte in (0xFD, 0xFF):
                out.append(Violation(now, f"packet ID {byte:#04x} (never used: it looks like a header)",
                                     bytes(self._raw)))
                self._restart(bytes(self._raw[1:]), now, out)
                return
            self._state = self._LEN_L
        elif state == self._LEN_L:
            self._state = self._LEN_H
        else:
            self._length = self._raw[5] | (self._raw[6] << 8)
            if self._length < 3:
                out.append(Violation(now, f"length {self._length} < 3 (instruction + CRC)", bytes(self._raw)))
                self._restart(bytes(self._raw[1:]), now, out)
                return
            self._state = self._BODY

    def _restart(self, data: bytes, now: float, out: list[Packet | Violation]) -> None:
        """Searches the bytes of a reported bad packet, after its first one, for a header."""
        self._state, self._raw = self._H1, bytearray()
        self._skipped.clear()
        self._quiet = len(data)
        for byte in data:
            self._step(byte, now, out)

    def _complete(self, now: float) -> Packet | Violation:
        raw = bytes(self._raw)
        self._state, self._raw = self._H1, bytearray()
        crc = raw[-2] | (raw[-1] << 8)
        body = raw[7:-2]
        if crc16(raw[:-2]) != crc:
            return Violation(now, f"CRC {crc:#06x} received, {crc16(raw[:-2]):#06x} computed", raw)
        plain = unstuff(body)
        return Packet(now, raw[4], plain[0] if plain else -1, plain[1:], raw, True, tuple(unstuffed_headers(body)))

    def expire(self, now: float) -> Violation | None:
        """Drops an incomplete packet (or stray bytes) silent for longer than the inter-byte timeout."""
        if not self.busy or now - self._last_byte_t < self.inter_byte_timeout_s:
            return None
        raw = bytes(self._skipped[self._quiet:]) + bytes(self._raw)
        what = (f"incomplete packet: {len(self._raw)} of {self._length + 7} bytes" if self._state == self._BODY
                else f"{len(raw)} byte(s) outside any packet")
        self._state, self._raw, self._skipped, self._quiet = self._H1, bytearray(), bytearray(), 0
        return Violation(now, what, raw) if raw else None

    @property
    def busy(self) -> bool:
        """Whether bytes of an unfinished packet (or stray bytes) are held."""
        return self._state != self._H1 or len(self._skipped) > self._quiet


def parse_packets(data: bytes) -> list[Packet]:
    """Every well-formed packet in ``data`` (tests decode status packets with it)."""
    return [item for item in Parser().feed(data, 0.0) if isinstance(item, Packet)]


# -- models and the control table ------------------------------------------------------------------------------

@dataclass(frozen=True)
class Model:
    """A servo model's numbers.

    Attributes:
        name: model name.
        model_number: Model Number(0).
        firmware: Firmware Version(6).
        current_unit_ma: Present/Goal Current unit [mA].
        no_load_rpm: no-load speed at 12 V [rpm]: the emulated motor is never faster.
        velocity_limit: Velocity Limit(44) initial value [0.229 rpm].
        current_limit: Current Limit(38) initial value and maximum [current unit].
        acceleration_limit: whether the table has Acceleration Limit(40) (MX(2.0)).
        startup_configuration: whether the table has Startup Configuration(60) and Backup Ready(147) (X series).
        profile_velocity_limited: whether Profile Velocity above Velocity Limit is refused (MX(2.0)).
    """

    name: str
    model_number: int
    firmware: int
    current_unit_ma: float
    no_load_rpm: float
    velocity_limit: int
    current_limit: int
    acceleration_limit: bool
    startup_configuration: bool
    profile_velocity_limited: bool


MODELS = {
    "MX-106": Model("MX-106(2.0)", 321, 45, 3.36, 45.0, 360, 2047, True, False, True),
    "MX-64": Model("MX-64(2.0)", 311, 45, 3.36, 63.0, 285, 1941, True, False, True),
    "XM430-W210": Model("XM430-W210", 1030, 38, 2.69, 77.0, 330, 1193, False, True, False),
    "XM430-W350": Model("XM430-W350", 1020, 38, 2.69, 46.0, 200, 1193, False, True, False),
}
"""By name. MX-106(2.0) and XM430-W210 values from their e-Manual pages (firmware 38 is the Protocol 2.0
page's example); the others are plausible."""


@dataclass(frozen=True)
class Item:
    """One control-table item.

    Attributes:
        address: first byte.
        size: bytes (1, 2 or 4, little-endian).
        name: e-Manual data name.
        writable: RW (else R).
        default: initial value.
        low: smallest value accepted (Data Range Error below).
        high: largest value accepted (Data Range Error above).
        signed: two's complement.
    """

    address: int
    size: int
    name: str
    writable: bool
    default: int
    low: int = 0
    high: int = 0
    signed: bool = False

    @property
    def eeprom(self) -> bool:
        """EEPROM area (addresses below 64): writable only with the torque off."""
        return self.address < 64


TORQUE_ENABLE, STATUS_RETURN_LEVEL, REGISTERED_INSTRUCTION, HARDWARE_ERROR_STATUS = 64, 68, 69, 70
GOAL_POSITION, PRESENT_POSITION = 116, 132


def control_table(model: Model) -> list[Item]:
    """The X-series / MX(2.0) control table (Protocol 2.0) up to Present Temperature(146)."""
    big = 1_044_479
    items = [
        Item(0, 2, "Model Number", False, model.model_number),
        Item(2, 4, "Model Information", False, 0),
        Item(6, 1, "Firmware Version", False, model.firmware),
        Item(7, 1, "ID", True, 1, 0, MAX_ID),
        Item(8, 1, "Baud Rate", True, 1, 0, 7),
        Item(9, 1, "Return Delay Time", True, 250, 0, 254),
        Item(10, 1, "Drive Mode", True, 0, 0, 5),
        Item(11, 1, "Operating Mode", True, 3, 0, 16),
        Item(12, 1, "Secondary(Shadow) ID", True, 255, 0, 255),
        Item(13, 1, "Protocol Type", True, 2, 1, 2),
        Item(20, 4, "Homing Offset", True, 0, -big, big, True),
        Item(24, 4, "Moving Threshold", True, 10, 0, 1023),
        Item(31, 1, "Temperature Limit", True, 80, 0, 100),
        Item(32, 2, "Max Voltage Limit", True, 160, 95, 160),
        Item(34, 2, "Min Voltage Limit", True, 95, 95, 160),
        Item(36, 2, "PWM Limit", True, 885, 0, 885),
        Item(38, 2, "Current Limit", True, model.current_limit, 0, model.current_limit),
        Item(44, 4, "Velocity Limit", True, model.velocity_limit, 0, 1023),
        Item(48, 4, "Max Position Limit", True, 4095, 0, 4095),
        Item(52, 4, "Min Position Limit", True, 0, 0, 4095),
        Item(63, 1, "Shutdown", True, 52, 0, 0x3D),
        Item(64, 1, "Torque Enable", True, 0, 0, 1),
        Item(65, 1, "LED", True, 0, 0, 1),
        Item(68, 1, "Status Return Level", True, 2, 0, 2),
        Item(69, 1, "Registered Instruction", False, 0),
        Item(70, 1, "Hardware Error Status", False, 0),
        Item(76, 2, "Velocity I Gain", True, 1920, 0, 16383),
        Item(78, 2, "Velocity P Gain", True, 100, 0, 16383),
        Item(80, 2, "Position D Gain", True, 0, 0, 16383),
        Item(82, 2, "Position I Gain", True, 0, 0, 16383),
        Item(84, 2, "Position P Gain", True, 850 if model.acceleration_limit else 800, 0, 16383),
        Item(88, 2, "Feedforward 2nd Gain", True, 0, 0, 16383),
        Item(90, 2, "Feedforward 1st Gain", True, 0, 0, 16383),
        Item(98, 1, "Bus Watchdog", True, 0, 0, 127),
        Item(100, 2, "Goal PWM", True, 0, -885, 885, True),
        Item(102, 2, "Goal Current", True, 0, -model.current_limit, model.current_limit, True),
        Item(104, 4, "Goal Velocity", True, 0, -1023, 1023, True),
        Item(108, 4, "Profile Acceleration", True, 0, 0, 32767),
        Item(112, 4, "Profile Velocity", True, 0, 0, 32767),
        Item(116, 4, "Goal Position", True, 0, -1_048_575, 1_048_575, True),
        Item(120, 2, "Realtime Tick", False, 0),
        Item(122, 1, "Moving", False, 0),
        Item(123, 1, "Moving Status", False, 0),
        Item(124, 2, "Present PWM", False, 0, signed=True),
        Item(126, 2, "Present Current", False, 0, signed=True),
        Item(128, 4, "Present Velocity", False, 0, signed=True),
        Item(132, 4, "Present Position", False, 0, signed=True),
        Item(136, 4, "Velocity Trajectory", False, 0, signed=True),
        Item(140, 4, "Position Trajectory", False, 0, signed=True),
        Item(144, 2, "Present Input Voltage", False, 120),
        Item(146, 1, "Present Temperature", False, 30),
    ]
    if model.acceleration_limit:
        items.append(Item(40, 4, "Acceleration Limit", True, 32767, 0, 32767))
    if model.startup_configuration:
        items += [Item(60, 1, "Startup Configuration", True, 0, 0, 3), Item(147, 1, "Backup Ready", False, 0)]
    return sorted(items, key=lambda item: item.address)


# -- one servo -------------------------------------------------------------------------------------------------

@dataclass
class Faults:
    """Fault injection for one servo; the test thread may change it at any time.

    Attributes:
        no_reply: executes instructions but never answers (a broken data line towards the host).
        corrupt_crc: answers with both CRC bytes inverted.
        vanish_after_packets: it takes part in this many instruction packets, then neither acts nor answers
            any more (power lost); ``None``: never.
        hardware_error_at_packet: at this many instruction packets seen, ``hardware_error_bits`` are set in
            Hardware Error Status (as by the servo's own protection); ``None``: never.
        hardware_error_bits: the bits set then (default overload).
    """

    no_reply: bool = False
    corrupt_crc: bool = False
    vanish_after_packets: int | None = None
    hardware_error_at_packet: int | None = None
    hardware_error_bits: int = OVERLOAD_ERROR


@dataclass
class ServoConfig:
    """A servo at power-up.

    Attributes:
        model: key of :data:`MODELS`.
        position: Present Position at power-up [ticks].
        table: control-table values at power-up by address (e.g. ``{9: 0}`` for Return Delay Time 0), as if
            written earlier and kept in EEPROM.
    """

    model: str = "MX-106"
    position: int = 2048
    table: dict[int, int] = field(default_factory=dict)


@dataclass(frozen=True)
class Rejected:
    """A write a servo refused (these have no status packet when they came by SYNC/BULK WRITE or broadcast).

    Attributes:
        t: monotonic time [s].
        instruction: the instruction.
        address: first address written.
        data: the bytes.
        error: the error number.
    """

    t: float
    instruction: int
    address: int
    data: bytes
    error: int


class Servo:
    """One emulated servo: its control table, its motion, its faults.

    Args:
        model: the model.
        servo_id: ID(7) at power-up.
        config: power-up state.
        baud_code: Baud Rate(8) at power-up.
        now: monotonic time of power-up [s].
        time_constant_s: first-order time constant of the position response [s].
        undefined_reads: ``"error"`` or ``"zero"``, see :class:`EManualBus`.
    """

    def __init__(self, model: Model, servo_id: int, config: ServoConfig, baud_code: int, now: float,
                 time_constant_s: float, undefined_reads: str = "error") -> None:
        self.model = model
        self.items = {item.address: item for item in control_table(model)}
        self.owner: dict[int, Item] = {item.address + k: item for item in self.items.values() for k in
                                       range(item.size)}
        self.table_size = max(self.owner) + 1
        self.table = bytearray(self.table_size)
        """The raw control table; read it through :meth:`get` (little-endian, signed items)."""
        self.time_constant_s = time_constant_s
        self.undefined_reads = undefined_reads
        self.faults = Faults()
        self.packets_seen = 0
        """Instruction packets this servo took part in (unicast to it, broadcast, or listing it)."""
        self.rejected: list[Rejected] = []
        """Every write it refused (those by SYNC/BULK WRITE or broadcast have no status packet to tell)."""
        self.vanished = False
        self.registered: tuple[int, bytes] | None = None
        """(address, data) of a REG WRITE waiting for ACTION."""
        self.pending_reset: int | None = None
        """REBOOT, or a FACTORY RESET option, to run once the status packet is out."""
        self.key = servo_id
        """ID at power-up (the bus's key for it)."""
        self.position = float(config.position)
        """Present position [ticks], continuous."""
        self.trace: list[tuple[float, int, float, bool]] = []
        """(time [s], Goal Position [ticks], present position [ticks], torque on) at every instruction packet it
        took part in."""
        self.velocity = 0.0
        """Present velocity [ticks/s]."""
        for item in self.items.values():
            self.set(item.address, item.default)
        self.set(7, servo_id)
        self.set(8, baud_code)
        for address, value in config.table.items():
            self.set(address, value)
        self.set(GOAL_POSITION, config.position)
        self.boot_t = self.last_t = now
        self.advance(now)

    # -- the table ---------------------------------------------------------------------------------------------

    def get(self, address: int) -> int:
        """The value of the item at ``address``."""
        item = self.items[address]
        return int.from_bytes(self.table[address:address + item.size], "little", signed=item.signed)

    def set(self, address: int, value: int) -> None:
        """Stores ``value`` in the item at ``address`` (no checks)."""
        item = self.items[address]
        bits = 8 * item.size
        self.table[address:address + item.size] = (value % (1 << bits)).to_bytes(item.size, "little")

    @property
    def id(self) -> int:
        """ID(7) now."""
        return self.table[7]

    @property
    def torque_on(self) -> bool:
        """Torque Enable(64) is 1."""
        return self.table[TORQUE_ENABLE] == 1

    @property
    def return_delay_s(self) -> float:
        """Return Delay Time [s]."""
        return self.table[9] * RETURN_DELAY_UNIT_S

    @property
    def alert(self) -> int:
        """The Alert bit for the status error byte."""
        return ALERT if self.table[HARDWARE_ERROR_STATUS] else 0

    def answers(self, instruction: int) -> bool:
        """Status Return Level(68): 0 only PING; 1 PING and reads; 2 everything."""
        level = self.table[STATUS_RETURN_LEVEL]
        if instruction == PING:
            return True
        if instruction in (READ, SYNC_READ, BULK_READ):
            return level >= 1
        return level >= 2

    def read(self, address: int, length: int) -> tuple[int, bytes]:
        """(error, data) of a read of ``length`` bytes from ``address``."""
        if length == 0:
            return DATA_LENGTH_ERROR, b""
        end = address + length
        if self.undefined_reads == "zero":  # gaps inside the table read as 0; outside it: Access Error
            if address not in self.owner or end > self.table_size:
                return ACCESS_ERROR, b""
        elif any(a not in self.owner for a in range(address, end)):  # e-Manual: undefined address → Access
            return ACCESS_ERROR, b""
        return 0, bytes(self.table[address:address + length])

    def check_write(self, address: int, data: bytes) -> int:
        """The error number a write of ``data`` at ``address`` gets (0: it may be applied)."""
        end = address + len(data)
        if not data:
            return DATA_LENGTH_ERROR
        if any(a not in self.owner for a in range(address, end)):
            return ACCESS_ERROR
        if self.owner[address].address != address or (self.owner[end - 1].address + self.owner[end - 1].size
                                                       != end):
            return DATA_LENGTH_ERROR  # choice: part of an item
        a = address
        while a < end:
            item = self.owner[a]
            if not item.writable or (item.eeprom and self.torque_on):
                return ACCESS_ERROR
            value = int.from_bytes(data[a - address:a - address + item.size], "little", signed=item.signed)
            error = self._check_value(item, value)
            if error:
                return error
            a += item.size
        return 0

    def _check_value(self, item: Item, value: int) -> int:
        if not item.low <= value <= item.high:
            return DATA_RANGE_ERROR
        a = item.address
        if a == 11 and value not in (0, 1, 3, 4, 5, 16):
            return DATA_RANGE_ERROR
        if a == GOAL_POSITION and self.get(11) == 3 and not self.get(52) <= value <= self.get(48):
            return DATA_LIMIT_ERROR
        if a == GOAL_POSITION and self.get(11) in (4, 5) and abs(value) > 1_048_575:
            return DATA_RANGE_ERROR
        if a == 112 and self.model.profile_velocity_limited and value > self.get(44):
            return DATA_LIMIT_ERROR
        if a == 104 and abs(value) > self.get(44):
            return DATA_LIMIT_ERROR
        if a == 102 and abs(value) > self.get(38):
            return DATA_LIMIT_ERROR
        if a == 100 and abs(value) > self.get(36):
            return DATA_LIMIT_ERROR
        if a == TORQUE_ENABLE and value == 1 and self.table[HARDWARE_ERROR_STATUS] & self.table[63]:
            return RESULT_FAIL  # choice: only REBOOT re-enables the torque after a shutdown
        return 0

    def write(self, address: int, data: bytes, now: float, instruction: int) -> int:
        """Checks and applies a write; returns the error number (recorded in :attr:`rejected` if non-zero)."""
        error = self.check_write(address, data)
        if error:
            self.rejected.append(Rejected(now, instruction, address, bytes(data), error))
            return error
        self.table[address:address + len(data)] = data
        return 0

    # -- device operations -------------------------------------------------------------------------------------

    def hardware_error(self, bits: int) -> None:
        """Sets Hardware Error Status bits; a bit enabled in Shutdown(63) turns the torque off."""
        self.table[HARDWARE_ERROR_STATUS] |= bits
        if bits & self.table[63]:
            self.table[TORQUE_ENABLE] = 0

    def reboot(self, now: float) -> None:
        """REBOOT: the RAM area to its initial values (torque off, errors cleared), EEPROM kept, the goal at the
        present position."""
        for item in self.items.values():
            if (not item.eeprom and item.writable) or item.address in (REGISTERED_INSTRUCTION,
                                                                       HARDWARE_ERROR_STATUS):
                self.set(item.address, item.default)
        self.set(GOAL_POSITION, round(self.position))
        self.registered = None
        self.boot_t = now
        self.velocity = 0.0

    def factory_reset(self, option: int, now: float) -> None:
        """FACTORY RESET: 0xFF everything, 0x01 all but ID, 0x02 all but ID and Baud Rate."""
        keep = {0x01: (7,), 0x02: (7, 8)}.get(option, ())
        saved = {a: self.table[a] for a in keep}
        for item in self.items.values():
            if item.eeprom:
                self.set(item.address, item.default)
        for address, value in saved.items():
            self.table[address] = value
        self.reboot(now)

    def advance(self, now: float) -> None:
        """Moves the emulated motor to time ``now`` [s] and refreshes the present values."""
        dt = now - self.last_t
        if dt < 0:
            return
        self.last_t = now
        mode = self.get(11)
        goal = float(self.get(GOAL_POSITION))
        ticks_per_s_per_unit = VELOCITY_UNIT_RPM / 60.0 * TICKS_PER_REV
        cap = self.model.no_load_rpm / 60.0 * TICKS_PER_REV  # [ticks/s]
        profile = min(self.get(112), self.get(44))
        if profile:
            cap = min(cap, profile * ticks_per_s_per_unit)
        if self.torque_on and mode in (3, 4, 5) and dt > 0:
            error = goal - self.position
            step = error * (1.0 - math.exp(-dt / self.time_constant_s))
            step = max(-cap * dt, min(cap * dt, step))
            self.position += step
            self.velocity = step / dt
        elif self.torque_on and mode == 1 and dt > 0:
            self.velocity = max(-cap, min(cap, self.get(104) * ticks_per_s_per_unit))
            self.position += self.velocity * dt
        elif dt > 0:
            self.velocity = 0.0
        if not self.torque_on:
            goal = self.position
        error = goal - self.position if mode in (3, 4, 5) else 0.0
        velocity_units = round(self.velocity / ticks_per_s_per_unit)
        current_ma = (3.0 * error + 0.05 * self.velocity) if self.torque_on else 0.0  # [mA]: a plausible stiffness
        limit = self.get(38)
        current = max(-limit, min(limit, round(current_ma / self.model.current_unit_ma)))
        pwm_limit = self.get(36)
        pwm = max(-pwm_limit, min(pwm_limit, round(velocity_units * 885 / max(self.model.velocity_limit, 1))))
        moving = abs(velocity_units) > self.get(24)
        self.set(120, int((now - self.boot_t) * 1000) % 32768)
        self.table[122] = int(moving)
        self.table[123] = (1 if abs(error) < 1.0 else 0) | (2 if moving else 0)
        self.set(124, pwm if self.torque_on else 0)
        self.set(126, current)
        self.set(128, velocity_units)
        self.set(132, round(self.position))
        self.set(136, velocity_units)
        self.set(140, round(goal))


# -- the bus ---------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class FaultEvent:
    """A fault that fired.

    Attributes:
        t: monotonic time [s].
        packet_index: index in :attr:`EManualBus.packets` of the instruction packet during which it fired.
        servo_id: the servo (its ID at power-up).
        description: what happened.
    """

    t: float
    packet_index: int
    servo_id: int
    description: str


class EManualBus:
    """Dynamixel Protocol 2.0 servos on a pty, served by a daemon thread.

    Args:
        servos: ID → model name or :class:`ServoConfig`.
        baud: the bus's bit rate [bit/s]; a servo whose Baud Rate(8) does not match it hears nothing.
        wire_time: if true, status packets also take their transmission time at ``baud`` (10 bits per byte),
            and instruction packets are taken to end that long after they were read.
        motion_time_constant_s: time constant of the emulated position response [s].
        inter_byte_timeout_s: longest silence inside an instruction packet before it is dropped [s].
        undefined_reads: ``"error"`` (Access Error for a read touching an undefined address, the e-Manual) or
            ``"zero"`` (gaps inside the table read as 0).

    Use as a context manager; ``port`` is the device path to give the host.
    """

    def __init__(self, servos: Mapping[int, str | ServoConfig], *, baud: int = 1_000_000, wire_time: bool = False,
                 motion_time_constant_s: float = 0.02, inter_byte_timeout_s: float = 0.1,
                 undefined_reads: str = "error") -> None:
        codes = {rate: code for code, rate in BAUD_RATES.items()}
        if baud not in codes:
            raise ValueError(f"{baud} bit/s is not a Dynamixel baud rate")
        self.baud, self.wire_time = baud, wire_time
        self._baud_code = codes[baud]
        now = time.monotonic()
        self.servos: dict[int, Servo] = {}
        """By ID at power-up (stable even if the host changes an ID)."""
        for servo_id, spec in servos.items():
            config = ServoConfig(spec) if isinstance(spec, str) else spec
            self.servos[servo_id] = Servo(MODELS[config.model], servo_id, config, codes[baud], now,
                                          motion_time_constant_s, undefined_reads)
        self.packets: list[Packet] = []
        """Every instruction packet received with a good CRC, in order."""
        self.protocol_violations: list[Violation] = []
        """Everything malformed received from the host."""
        self.fault_events: list[FaultEvent] = []
        self.replies: list[tuple[float, bytes]] = []
        """(monotonic time it was written [s], bytes) of every status packet sent, in order."""
        self.lock = threading.RLock()
        self._parser = Parser(inter_byte_timeout_s)
        self._master, self._slave = os.openpty()
        tty.setraw(self._master)
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.port = os.ttyname(self._slave)
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = False
        self._thread = threading.Thread(target=self._serve, name="emanual-bus", daemon=True)
        self.error: BaseException | None = None
        """An exception that stopped the serving thread."""

    # -- life cycle --------------------------------------------------------------------------------------------

    def start(self) -> EManualBus:
        """Starts serving. The process's objects so far are frozen out of the garbage collector until :meth:`stop`:
        a full collection of a test process pauses every thread for tens of ms, longer than a host's status
        timeout (a real servo has no such pauses)."""
        gc.freeze()
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stops the thread and closes the pty and the wake-up pipe."""
        if self._stopping:
            return
        self._stopping = True
        if self._thread.is_alive():
            os.write(self._wake_w, b"x")
            self._thread.join(timeout=5.0)
        for fd in (self._master, self._slave, self._wake_r, self._wake_w):
            with contextlib.suppress(OSError):
                os.close(fd)
        gc.unfreeze()

    def __enter__(self) -> EManualBus:
        return self.start()

    def __exit__(self, kind: type[BaseException] | None, value: BaseException | None,
                 traceback: TracebackType | None) -> None:
        self.stop()

    # -- inspection --------------------------------------------------------------------------------------------

    def position(self, servo_id: int) -> int:
        """Present Position [ticks] of the servo with power-up ID ``servo_id``, now."""
        with self.lock:
            servo = self.servos[servo_id]
            servo.advance(time.monotonic())
            return servo.get(PRESENT_POSITION)

    def goal(self, servo_id: int) -> int:
        """Goal Position [ticks]."""
        with self.lock:
            return self.servos[servo_id].get(GOAL_POSITION)

    def faults(self, servo_id: int) -> Faults:
        """The fault injection of a servo (by power-up ID)."""
        return self.servos[servo_id].faults

    def hardware_error(self, servo_id: int, bits: int) -> None:
        """Sets Hardware Error Status bits on a servo now (a Shutdown bit turns its torque off)."""
        with self.lock:
            self.servos[servo_id].hardware_error(bits)
            self.fault_events.append(FaultEvent(time.monotonic(), len(self.packets), servo_id,
                                                f"hardware error {bits:#04x}"))

    def instructions(self, instruction: int) -> Iterator[tuple[int, Packet]]:
        """(index, packet) of every received instruction packet with that instruction."""
        with self.lock:
            packets = list(self.packets)
        return ((i, p) for i, p in enumerate(packets) if p.instruction == instruction)

    # -- serving -----------------------------------------------------------------------------------------------

    def _serve(self) -> None:
        serve_promptly()
        try:
            while not self._stopping:
                timeout = self._parser.inter_byte_timeout_s if self._parser.busy else 0.5
                ready, _, _ = select.select([self._master, self._wake_r], [], [], timeout)
                if self._wake_r in ready or self._stopping:
                    return
                now = time.monotonic()
                data = b""
                if self._master in ready:
                    try:
                        data = os.read(self._master, 4096)
                    except BlockingIOError:
                        data = b""
                    except OSError:  # nobody has the slave open (cannot happen: we hold it) or it closed
                        time.sleep(0.01)
                        continue
                for item in self._parser.feed(data, now):
                    if isinstance(item, Violation):
                        self._violation(item)
                    else:
                        self._handle(item)
                expired = self._parser.expire(time.monotonic())
                if expired:
                    self._violation(expired)
        except BaseException as error:  # kept for the test to see; the thread must not die silently
            self.error = error
            raise

    def _violation(self, violation: Violation) -> None:
        with self.lock:
            self.protocol_violations.append(violation)
        if violation.description.startswith("CRC") and len(violation.raw) >= 10:
            packet_id, instruction = violation.raw[4], violation.raw[7]
            servo = self._by_id(packet_id)
            if servo is not None and servo.answers(instruction) and not servo.vanished:
                self._transmit([(servo, CRC_ERROR, b"")], violation.t)

    def _by_id(self, packet_id: int) -> Servo | None:
        """The listening servo with that ID now (ID 0–252)."""
        return next((servo for servo in self._listening() if servo.id == packet_id), None)

    def _listening(self) -> list[Servo]:
        """Servos that hear the bus (Baud Rate matches, not vanished), in ID order."""
        return sorted((s for s in self.servos.values() if s.table[8] == self._baud_code and not s.vanished),
                      key=lambda s: s.id)

    def _handle(self, received: Packet) -> None:
        replies: list[tuple[Servo, int, bytes]] = []
        with self.lock:
            index = len(self.packets)
            self.packets.append(received)
            now = received.t
            for servo in self.servos.values():
                servo.advance(now)
            if received.unstuffed_at:
                self.protocol_violations.append(Violation(
                    now, f"FF FF FD without byte stuffing at offset(s) {list(received.unstuffed_at)} of the "
                         f"{INSTRUCTION_NAMES.get(received.instruction, hex(received.instruction))} payload",
                    received.raw))
            involved = self._involved(received)
            for servo in involved:
                self._count(servo, index, now)
            involved = [s for s in involved if not s.vanished]
            for servo in involved:
                servo.trace.append((now, servo.get(GOAL_POSITION), servo.position, servo.torque_on))
            replies = self._execute(received, involved, now)
        self._transmit(replies, received.t + (self._wire(len(received.raw)) if self.wire_time else 0.0))
        with self.lock:
            for servo in involved:  # REBOOT / FACTORY RESET run after their status packet
                if servo.pending_reset is not None:
                    option, servo.pending_reset = servo.pending_reset, None
                    if option == REBOOT:
                        servo.reboot(time.monotonic())
                    else:
                        servo.factory_reset(option, time.monotonic())

    def _involved(self, received: Packet) -> list[Servo]:
        """The listening servos an instruction packet concerns."""
        listening = self._listening()
        if received.packet_id != BROADCAST_ID:
            return [s for s in listening if s.id == received.packet_id]
        params, instruction = received.params, received.instruction
        if instruction == SYNC_READ:
            ids = set(params[4:])
        elif instruction == SYNC_WRITE and len(params) >= 4:
            size = 1 + (params[2] | params[3] << 8)
            ids = set(params[4::size])
        elif instruction in (BULK_READ, BULK_WRITE):
            ids = {entry[0] for entry in self._bulk_entries(received) or []}
        else:
            return listening
        return [s for s in listening if s.id in ids]

    def _count(self, servo: Servo, index: int, now: float) -> None:
        servo.packets_seen += 1
        faults = servo.faults
        key = servo.key
        if faults.hardware_error_at_packet is not None and servo.packets_seen == faults.hardware_error_at_packet:
            servo.hardware_error(faults.hardware_error_bits)
            self.fault_events.append(FaultEvent(now, index, key, f"hardware error {faults.hardware_error_bits:#04x}"))
        if faults.vanish_after_packets is not None and servo.packets_seen > faults.vanish_after_packets:
            if not servo.vanished:
                self.fault_events.append(FaultEvent(now, index, key, "vanished"))
            servo.vanished = True

    def _malformed(self, received: Packet, what: str) -> None:
        self.protocol_violations.append(Violation(
            received.t, f"{INSTRUCTION_NAMES.get(received.instruction, hex(received.instruction))}: {what}",
            received.raw))

    def _execute(self, received: Packet, involved: list[Servo], now: float) -> list[tuple[Servo, int, bytes]]:
        """Runs the instruction on the servos it concerns; returns the status packets to send, in order."""
        instruction, params = received.instruction, received.params
        unicast = received.packet_id != BROADCAST_ID
        replies: list[tuple[Servo, int, bytes]] = []

        def reply(servo: Servo, error: int, data: bytes = b"") -> None:
            if unicast and servo.answers(instruction):
                replies.append((servo, error, data))

        if instruction == PING:
            for servo in involved:  # broadcast: every servo, in ID order
                if params:
                    self._malformed(received, f"{len(params)} parameter(s), none expected")
                model = servo.get(0)
                replies.append((servo, 0, bytes([model & 0xFF, model >> 8, servo.table[6]])))
        elif instruction == READ:
            if not unicast:
                return replies  # no status to a broadcast READ (e-Manual note)
            for servo in involved:
                if len(params) != 4:
                    self._malformed(received, f"{len(params)} parameters, 4 expected")
                    reply(servo, DATA_LENGTH_ERROR)
                    continue
                error, data = servo.read(params[0] | params[1] << 8, params[2] | params[3] << 8)
                reply(servo, error, data)
        elif instruction in (WRITE, REG_WRITE):
            if len(params) < 3:
                self._malformed(received, f"{len(params)} parameters, at least 3 expected")
                for servo in involved:
                    reply(servo, DATA_LENGTH_ERROR)
                return replies
            address, data = params[0] | params[1] << 8, params[2:]
            for servo in involved:
                if instruction == WRITE:
                    reply(servo, servo.write(address, data, now, instruction))
                    continue
                error = servo.check_write(address, data)
                if error:
                    servo.rejected.append(Rejected(now, instruction, address, bytes(data), error))
                else:
                    servo.registered = (address, bytes(data))
                    servo.table[REGISTERED_INSTRUCTION] = 1
                reply(servo, error)
        elif instruction == ACTION:
            for servo in involved:
                if servo.registered is None:
                    reply(servo, INSTRUCTION_ERROR)  # Action without Reg Write
                    continue
                address, data = servo.registered
                servo.registered = None
                servo.table[REGISTERED_INSTRUCTION] = 0
                reply(servo, servo.write(address, data, now, instruction))
        elif instruction == REBOOT:
            for servo in involved:
                reply(servo, 0)
                servo.pending_reset = REBOOT
        elif instruction == FACTORY_RESET:
            option = params[0] if len(params) == 1 else -1
            for servo in involved:
                if option not in (0xFF, 0x01, 0x02):
                    if len(params) != 1:
                        self._malformed(received, f"{len(params)} parameters, 1 expected")
                    reply(servo, DATA_RANGE_ERROR if len(params) == 1 else DATA_LENGTH_ERROR)
                elif not unicast and option == 0xFF:
                    continue  # not activated for the broadcast ID with Reset All (firmware 42+)
                elif servo.torque_on:
                    reply(servo, ACCESS_ERROR)  # choice: it writes the EEPROM area, locked by the torque
                else:
                    reply(servo, 0)
                    servo.pending_reset = option
        elif instruction == CLEAR:
            for servo in involved:
                if len(params) != 5:
                    self._malformed(received, f"{len(params)} parameters, 5 expected")
                    reply(servo, DATA_LENGTH_ERROR)
                elif params != bytes([0x01, 0x44, 0x58, 0x4C, 0x22]):
                    reply(servo, DATA_RANGE_ERROR)
                elif servo.table[122]:
                    reply(servo, RESULT_FAIL)  # only while stopped
                else:
                    turns = math.floor(servo.position / TICKS_PER_REV)
                    servo.position -= turns * TICKS_PER_REV
                    servo.set(GOAL_POSITION, servo.get(GOAL_POSITION) - turns * TICKS_PER_REV)
                    servo.advance(now)
                    reply(servo, 0)
        elif instruction == SYNC_READ:
            if unicast or len(params) < 5:
                self._malformed(received, "needs the broadcast ID, an address, a length and at least one ID")
                return replies
            address, length = params[0] | params[1] << 8, params[2] | params[3] << 8
            by_id = {s.id: s for s in involved}
            for servo_id in params[4:]:  # in the order of the instruction
                target = by_id.get(servo_id)
                if target is not None and target.answers(SYNC_READ):
                    error, data = target.read(address, length)
                    replies.append((target, error, data))
        elif instruction == SYNC_WRITE:
            size = 1 + (params[2] | params[3] << 8) if len(params) >= 4 else 0
            if unicast or size < 2 or (len(params) - 4) % size or len(params) == 4:
                self._malformed(received, f"{len(params)} parameters do not make address, length and "
                                          f"ID + {max(size - 1, 0)} bytes per servo (broadcast ID required)")
                return replies
            address = params[0] | params[1] << 8
            by_id = {s.id: s for s in involved}
            for start in range(4, len(params), size):
                target = by_id.get(params[start])
                if target is not None:
                    target.write(address, params[start + 1:start + size], now, instruction)
        elif instruction in (BULK_READ, BULK_WRITE):
            entries = self._bulk_entries(received)
            if unicast or not entries:
                self._malformed(received, "malformed parameters (or not the broadcast ID)")
                return replies
            ids = [entry[0] for entry in entries]
            if len(set(ids)) != len(ids):
                self._malformed(received, f"an ID appears more than once: {ids}")
            by_id = {s.id: s for s in involved}
            seen: set[int] = set()
            for servo_id, address, length, data in entries:
                target = by_id.get(servo_id)
                if target is None or servo_id in seen:
                    continue
                seen.add(servo_id)
                if instruction == BULK_WRITE:
                    target.write(address, data, now, instruction)
                elif target.answers(BULK_READ):
                    error, values = target.read(address, length)
                    replies.append((target, error, values))
        else:
            for servo in involved:
                reply(servo, INSTRUCTION_ERROR)
        return replies

    @staticmethod
    def _bulk_entries(received: Packet) -> list[tuple[int, int, int, bytes]] | None:
        """(id, address, length, data) of a BULK READ / BULK WRITE, or None if the parameters do not parse."""
        params, entries, index = received.params, [], 0
        write = received.instruction == BULK_WRITE
        while index < len(params):
            if index + 5 > len(params):
                return None
            servo_id, address, length = params[index], params[index + 1] | params[index + 2] << 8, (
                params[index + 3] | params[index + 4] << 8)
            data = params[index + 5:index + 5 + length] if write else b""
            if write and len(data) != length:
                return None
            entries.append((servo_id, address, length, bytes(data)))
            index += 5 + (length if write else 0)
        return entries or None

    def _wire(self, count: int) -> float:
        """Time ``count`` bytes take on the bus [s] (10 bits per byte)."""
        return count * 10.0 / self.baud

    def _transmit(self, replies: list[tuple[Servo, int, bytes]], bus_free: float) -> None:
        """Sends status packets in order, each the servo's Return Delay Time after the bus fell silent (the end of
        the instruction packet or of the previous status packet), on the bus's own time line: a reply this thread
        wrote late does not delay the next one beyond where a real bus would have it."""
        for servo, error, data in replies:
            if servo.faults.no_reply:
                continue
            with self.lock:
                out = bytearray(status_packet(servo.id, error | servo.alert, data))
                if servo.faults.corrupt_crc:
                    out[-2] ^= 0xFF
                    out[-1] ^= 0xFF
            due = bus_free + servo.return_delay_s + (self._wire(len(out)) if self.wire_time else 0.0)
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            self._write(bytes(out))
            bus_free = due
            with self.lock:
                self.replies.append((time.monotonic(), bytes(out)))

    def _write(self, data: bytes) -> None:
        view = memoryview(data)
        deadline = time.monotonic() + 0.5
        while view:
            try:
                count = os.write(self._master, view)
            except BlockingIOError:  # the host is not reading: wait a little, then drop
                if time.monotonic() > deadline:
                    return
                time.sleep(0.001)
                continue
            except OSError:
                return
            view = view[count:]
