"""The robot's servos on one or more Dynamixel Protocol 2.0 buses, through the official dynamixel-sdk; and the
base of the other families' buses (:mod:`shc_cli.hardware.bus_protocol1`: Dynamixel Protocol 1.0 and Feetech).
:func:`shc_cli.hardware.buses.servo_bus` picks the class from the servo models.

Joint angles ↔ ticks: ``ticks = zero_ticks + direction · (q + offset) · ticks_per_revolution / 2π`` (``offset`` is
the joint's servo offset, as OpenSHC adds it to hardware commands; ``ticks_per_revolution`` the model's: 4096, or
1228.8 for the AX series' 1024 ticks per 300°; ``zero_ticks`` by default the middle of the model's range).
Per cycle and bus: one sync read (present current, velocity and position: addresses 126–135, 10 bytes per servo)
and one sync write (goal position, or profile velocity + goal position: 112–119). With several buses the sync
reads go out on every bus before the replies are received, so the buses answer in parallel.

dynamixel-sdk's GroupSyncRead drops each servo's status error byte, so the sync read is sent with it and the replies
are received one by one with ``PacketHandler.readRx``, which keeps the error byte: its alert bit flags a hardware
error in the same cycle, and only then is Hardware Error Status (address 70) read to name it. The SDK does not
byte-stuff what it sends, so every write payload is checked for ``FF FF FD``.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from shc_cli.errors import ShcError
from shc_cli.hardware import protocol2 as p2
from shc_cli.hardware.models import MODELS, OPERATING_MODES, POSITION_MODES, ServoModel, hardware_error_names
from shc_cli.model.chains import JointSlots
from shc_cli.spec.robot import Robot

STATE_ADDRESS, STATE_LENGTH = 126, 10
"""Present current (2), velocity (4), position (4), contiguous in the X/MX 2.0 control table."""
SETTINGS_ADDRESS, SETTINGS_LENGTH = 11, 45
"""Operating Mode (11) to Min Position Limit (52–55): read once at start to check the servos' configuration."""
PROFILE_ADDRESS = 112
"""Profile Velocity (112–115) followed by Goal Position (116–119)."""


class HardwareError(ShcError):
    """The bus or a servo is missing, wrong or failing (one line, exit 2)."""


STALL_GRACE_MS = 250.0
"""How long past an SDK packet timeout a reply already waiting in the input buffer is still read [ms]."""


@functools.cache
def patient_port(base: type) -> type:
    """An SDK ``PortHandler`` class (dynamixel-sdk's or feetech-servo-sdk's) whose packet timeout does not fire while
    a reply is waiting unread in the input buffer.

    The SDKs' receive loop reads the port and then checks the clock: when this process is not scheduled between the
    two (a loaded computer; a virtual machine's pause of 40–70 ms was measured here) the whole reply arrives in the
    meantime and the SDK reports "no reply" without reading it. Here the timeout is declared only when the input is
    empty too, up to :data:`STALL_GRACE_MS` past it (a babbling bus still times out). A servo that does not answer
    costs the same timeout as before.
    """

    class PatientPort(base):  # type: ignore[misc]
        def isPacketTimeout(self) -> bool:
            elapsed, timeout = float(self.getTimeSinceStart()), float(getattr(self, "packet_timeout", 0.0))
            if elapsed <= timeout:
                return False
            if elapsed <= timeout + STALL_GRACE_MS and self.ser is not None and self.ser.in_waiting:
                return False  # the reply came while this process was not running: read it
            self.packet_timeout = 0
            return True

    PatientPort.__name__ = PatientPort.__qualname__ = f"Patient{base.__name__}"
    return PatientPort


def open_port(port: Any, name: str, baud: int, close: Callable[[], None]) -> Any:
    """Open an SDK port handler (dynamixel-sdk's or feetech-servo-sdk's ``PortHandler``) at ``baud``; on failure
    ``close()`` (the bus's other ports) and a one-line :class:`HardwareError` naming the port and the fix."""
    try:
        opened = port.openPort()
    except Exception as error:  # pyserial raises several types; all mean "cannot open"
        reason = "no such device" if not os.path.exists(name) else str(error) or type(error).__name__
        close()
        raise HardwareError(f"{name}: cannot open the serial port: {reason} "
                            "(give the servo bus adapter with --port, e.g. /dev/ttyUSB0)") from None
    if not opened or not port.setBaudRate(baud):
        close()
        raise HardwareError(f"{name}: cannot open the serial port at {baud} baud "
                            "(check --port and --baud or hardware.baud)")
    return port

@dataclass(frozen=True)
class Slot:
    """One joint's servo: where it is in the controller's ``(L, n)`` arrays and on the bus."""

    key: str
    leg: int
    joint: int
    servo_id: int
    bus: int
    model: ServoModel
    direction: int
    zero: int
    offset: float
    limits: tuple[float, float]
    """The joint's position limits [rad]."""


@dataclass
class BusState:
    """One sync read: per joint (controller order) position [rad], velocity [rad/s], current [mA]; per servo (slot
    order) whether it answered and whether its status carried the hardware-error alert bit; and why servos did not
    answer (slot → "no reply" or "corrupt reply"). ``bridged`` (slot order) marks the servos whose values are their
    last reading standing in for a missed one (:class:`shc_cli.backends.dynamixel.MissedReads`); None: none."""

    positions: np.ndarray
    velocities: np.ndarray
    currents: np.ndarray
    answered: np.ndarray
    alerts: np.ndarray
    failures: dict[int, str] = field(default_factory=dict)
    bridged: np.ndarray | None = None


@dataclass
class _Line:
    """One bus: its port and the slots on it."""

    name: str
    slots: list[int]
    port: Any = None
    state_reader: Any = None
    ids: list[int] = field(default_factory=list)


class ServoBus:
    """Every joint's servo, on one bus per port.

    Args:
        robot: the robot (its ``[hardware]`` table; a servo's ``bus`` indexes ``ports``).
        ports: serial devices, bus 0 first (USB2Dynamixel/U2D2 adapters, or emulators' ptys).
        baud: baud rate of every bus; default ``hardware.baud``.
        profile_velocity: also write Profile Velocity each cycle (the speed that reaches the goal in one period),
            so the servos interpolate between goals.
    """

    skipped: frozenset[int] = frozenset()
    """Slots no goal is written to any more (a failed leg's servos, ``run-hw --on-fault adapt``)."""

    def __init__(self, robot: Robot, ports: list[str] | str, baud: int | None = None,
                 profile_velocity: bool = False) -> None:
        hardware = robot.hardware
        if not hardware.servos:
            raise HardwareError(f"{robot.name}: no [hardware.servos] table (map every joint to a servo id)")
        ports = [ports] if isinstance(ports, str) else list(ports)
        self.robot, self.port_names, self.baud = robot, ports, baud or hardware.baud
        self.port_name = ", ".join(ports)
        self.profile_velocity = profile_velocity
        self.slots = []
        for i, (leg, spec) in enumerate(robot.legs.items()):
            for k, (joint, joint_spec) in enumerate(spec.joints.items()):
                servo = hardware.servos[f"{leg}_{joint}"]
                model = MODELS[servo.model or hardware.model]
                zero = model.centre if servo.zero_ticks is None else servo.zero_ticks
                self.slots.append(Slot(f"{leg}_{joint}", i, k, servo.id, servo.bus, model, servo.direction,
                                       zero, joint_spec.offset, (joint_spec.min, joint_spec.max)))
        used = sorted({slot.bus for slot in self.slots})
        if used[-1] >= len(ports):
            raise HardwareError(f"{robot.name}: servos are on buses {', '.join(map(str, used))}, but "
                                f"{len(ports)} port{'s' if len(ports) > 1 else ''} given "
                                f"(give --port once per bus, bus 0 first)")
        self.lines = [_Line(name, [i for i, s in enumerate(self.slots) if s.bus == b]) for b, name in enumerate(ports)]
        self.layout = JointSlots.of(robot)  # the slots are in servo order: legs in id order, joints body to tip
        self.shape = (self.layout.legs, self.layout.width)
        self._direction = np.array([s.direction for s in self.slots], dtype=float)
        self._zero = np.array([s.zero for s in self.slots], dtype=float)
        self._offset = np.array([s.offset for s in self.slots])
        self._ticks_per_rad = np.array([hardware.ticks_per_revolution / (2.0 * math.pi) if s.model.name == "generic"
                                        else s.model.ticks_per_radian for s in self.slots])
        """Each servo's ticks per radian (its model's units)."""
        self._current_unit = np.array([s.model.current_unit_ma for s in self.slots])
        self._velocity_unit = np.array([s.model.velocity_unit_rpm for s in self.slots])
        self._handler: Any = None
        self.return_delays = [0.0] * len(self.slots)
        """Each servo's Return Delay Time [s], as read at the start check (or written by :meth:`configure`)."""
        self._last_ticks: np.ndarray | None = None
        self.retries = 0
        """Sync reads repeated because a reply was missing or corrupt."""

    # -- opening, checking, configuring ----------------------------------------------------------------------

    def open(self) -> None:
        from dynamixel_sdk import GroupSyncRead, PacketHandler, PortHandler

        self._handler = PacketHandler(2.0)
        for line in self.lines:
            port = open_port(patient_port(PortHandler)(line.name), line.name, self.baud, self.close)
            line.port = port
            line.ids = [self.slots[i].servo_id for i in line.slots]
            line.state_reader = GroupSyncRead(port, self._handler, STATE_ADDRESS, STATE_LENGTH)
            for servo_id in line.ids:
                line.state_reader.addParam(servo_id)

    def close(self) -> None:
        """Close every port (again: nothing)."""
        for line in self.lines:
            if line.port is not None:
                line.port.closePort()
                line.port = None

    def __enter__(self) -> ServoBus:
        """``with ServoBus(...) as bus:`` opens the ports and closes them at the end."""
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def check(self) -> list[str]:
        """Every problem that must stop a start (one text each): missing servos (a broadcast ping, then a unicast
        ping for each servo it did not find), wrong models, hardware errors, servos not in a position-control
        operating mode, joint limits outside the servo's position limits."""
        from dynamixel_sdk import COMM_SUCCESS

        problems = []
        for line in self.lines:
            if not line.slots:
                continue
            found, result = self._handler.broadcastPing(line.port)
            found = dict(found) if result == COMM_SUCCESS or found else {}
            for index in line.slots:
                slot = self.slots[index]
                if slot.servo_id not in found:
                    number, result, _ = self._handler.ping(line.port, slot.servo_id)
                    if result == COMM_SUCCESS:
                        found[slot.servo_id] = [number, 0]
                if slot.servo_id not in found:
                    problems.append(f"{slot.key}: servo {slot.servo_id} does not answer on {line.name} "
                                    f"at {self.baud} baud")
                elif slot.model.model_number and found[slot.servo_id][0] != slot.model.model_number:
                    problems.append(f"{slot.key}: servo {slot.servo_id} is model number {found[slot.servo_id][0]}, "
                                    f"not a {slot.model.name} ({slot.model.model_number})")
        if problems:
            return problems
        problems += [f"{key}: hardware error ({', '.join(names)})" for key, names in self.hardware_errors().items()]
        return problems + self._check_settings()

    def _check_settings(self) -> list[str]:
        """Operating mode and position limits of every servo, and their Return Delay Time (kept for
        :meth:`wire_time`); reads of defined items only (a read across the control table's gaps may be refused)."""
        problems: list[str] = []
        model = self.slots[0].model
        modes = self.read_items(model.operating_mode, 1, "Operating Mode", problems)
        limits = self.read_items(model.max_position_limit, 8, "Max/Min Position Limit", problems)
        delays = self.read_items(model.return_delay_time, 1, "Return Delay Time", problems)
        for index, data in delays.items():
            self.return_delays[index] = 2e-6 * data[0]
        for index, slot in enumerate(self.slots):
            if index not in modes or index not in limits:
                continue
            mode = modes[index][0]
            if mode not in POSITION_MODES:
                problems.append(f"{slot.key}: servo {slot.servo_id} is in {OPERATING_MODES.get(mode, str(mode))} "
                                f"operating mode; set Operating Mode (address {slot.model.operating_mode}) to 3 "
                                "(position control)")
                continue
            if mode == 4:
                continue  # extended position mode has no position limits
            high = int.from_bytes(limits[index][0:4], "little", signed=True)
            low = int.from_bytes(limits[index][4:8], "little", signed=True)
            ends = sorted(self._to_ticks(index, np.array(slot.limits)))
            if ends[0] < low or ends[1] > high:
                problems.append(f"{slot.key}: the joint limits {slot.limits[0]:.3f}..{slot.limits[1]:.3f} rad are "
                                f"ticks {ends[0]}..{ends[1]}, outside servo {slot.servo_id}'s position limits "
                                f"{low}..{high}; widen the servo's Min/Max Position Limit or fix zero_ticks, "
                                "direction or the joint limits")
        return problems

    def read_items(self, address: int, length: int, name: str, problems: list[str]) -> dict[int, bytes]:
        """One sync read per bus of ``length`` bytes at ``address``: the data by slot; a servo that did not answer
        properly (no reply, a corrupt one, an error status such as Access Error) adds a problem naming it."""
        from dynamixel_sdk import GroupSyncRead

        out: dict[int, bytes] = {}
        for line in self.lines:
            if not line.slots:
                continue
            reader = GroupSyncRead(line.port, self._handler, address, length)
            for servo_id in line.ids:
                reader.addParam(servo_id)
            replies, failures = self._sync_read(line, reader, length)
            out.update((index, data) for index, (data, _) in replies.items())
            problems += [f"{self.slots[i].key}: servo {self.slots[i].servo_id}, {name} read (address {address}): "
                         f"{reason}" for i, reason in failures.items()]
        return out

    def _sync_read(self, line: _Line, reader: Any, length: int, sent: bool = False
                   ) -> tuple[dict[int, tuple[bytes, int]], dict[int, str]]:
        """Send ``reader``'s sync read (unless ``sent``) and receive each servo's status in order with ``readRx``,
        which keeps the error byte (GroupSyncRead drops it). Returns ``{slot: (data, error byte)}`` and
        ``{slot: why it failed}``: an error status or a short reply fails that servo; a missing or corrupt one
        also leaves the rest of the bus unread. On a failure the port is cleared and the read repeated once."""
        from dynamixel_sdk import COMM_RX_CORRUPT, COMM_SUCCESS

        retried = False
        while True:
            if retried or not sent:
                reader.txPacket()
            replies: dict[int, tuple[bytes, int]] = {}
            failures: dict[int, str] = {}
            for index in line.slots:
                data, result, error = self._handler.readRx(line.port, self.slots[index].servo_id, length)
                if result != COMM_SUCCESS:
                    failures[index] = "corrupt reply (CRC or length)" if result == COMM_RX_CORRUPT else "no reply"
                    break
                if error & 0x7F or len(data) != length:  # an error status carries no data
                    failures[index] = f"{p2.error_name(error)} reply" if error & 0x7F else "short reply"
                    continue
                replies[index] = (bytes(data), error)
            if not failures or retried:
                return replies, failures
            line.port.clearPort()
            self.retries += 1
            retried = True

    def configure(self) -> list[str]:
        """Write the robot file's Return Delay Time and current limit (EEPROM, torque off) where a servo differs;
        returns what it did."""
        from dynamixel_sdk import COMM_SUCCESS

        hardware, done = self.robot.hardware, []
        if hardware.return_delay_us is not None:
            value = hardware.return_delay_us // 2
            changed = [i for i, delay in enumerate(self.return_delays) if round(delay / 2e-6) != value]
            for index in changed:
                self._write(index, self.slots[index].model.return_delay_time, bytes([value]), "Return Delay Time")
                self.return_delays[index] = 2e-6 * value
            if changed:
                done.append(f"return delay time {2 * value} µs written to {len(changed)} servos")
        if hardware.current_limit_ma is not None:
            changed = []
            for index, slot in enumerate(self.slots):
                value = round(hardware.current_limit_ma / slot.model.current_unit_ma)
                present, result, error = self._handler.read2ByteTxRx(self._port_of(index), slot.servo_id,
                                                                     slot.model.current_limit)
                if result == COMM_SUCCESS and not error & 0x7F and present == value:
                    continue
                self._write(index, slot.model.current_limit, value.to_bytes(2, "little"), "Current Limit")
                changed.append(index)
            if changed:
                done.append(f"current limit {hardware.current_limit_ma:g} mA written to {len(changed)} servos")
        return done

    def _port_of(self, index: int) -> Any:
        return self.lines[self.slots[index].bus].port

    def _write(self, index: int, address: int, data: bytes, name: str) -> None:
        """One WRITE with its status checked (and the payload checked for what the SDK would not stuff); a status
        that did not come is asked for by writing once more (the start's settings: the same bytes again)."""
        from dynamixel_sdk import COMM_SUCCESS

        slot = self.slots[index]
        if p2.needs_stuffing(address.to_bytes(2, "little") + data):
            raise HardwareError(f"{slot.key}: the {name} write contains FF FF FD, which dynamixel-sdk sends unstuffed")
        for attempt in range(2):
            result, error = self._handler.writeTxRx(self._port_of(index), slot.servo_id, address, len(data),
                                                    list(data))
            if result == COMM_SUCCESS or attempt:
                break
            self._port_of(index).clearPort()
            self.retries += 1
        if result != COMM_SUCCESS or error & 0x7F:
            reason = self._handler.getTxRxResult(result) if result != COMM_SUCCESS else p2.error_name(error)
            raise HardwareError(f"{slot.key}: servo {slot.servo_id} refused {name} (address {address}): {reason}")

    # -- the cycle -------------------------------------------------------------------------------------------

    def read_state(self) -> BusState:
        """One sync read per bus of current, velocity and position of every servo, keeping each status packet's
        error byte (its alert bit says a Hardware Error Status bit is set). A bus that misses a reply is read again
        once at once, after clearing its port, before the servos from that one on count as missing."""
        count = len(self.slots)
        raw = np.zeros((count, STATE_LENGTH), dtype=np.uint8)
        answered = np.zeros(count, dtype=bool)
        alerts = np.zeros(count, dtype=bool)
        failures: dict[int, str] = {}
        for line in self.lines:  # every bus starts answering at once
            if line.slots:
                line.state_reader.txPacket()
        for line in self.lines:
            if not line.slots:
                continue
            replies, missed = self._sync_read(line, line.state_reader, STATE_LENGTH, sent=True)
            failures.update(missed)
            for index, (data, error) in replies.items():
                raw[index] = np.frombuffer(data, dtype=np.uint8)
                answered[index] = True
                alerts[index] = bool(error & p2.ERROR_ALERT)
        current = raw[:, 0:2].copy().view("<i2")[:, 0].astype(float)
        velocity = raw[:, 2:6].copy().view("<i4")[:, 0].astype(float)
        ticks = raw[:, 6:10].copy().view("<i4")[:, 0].astype(float)
        positions = self._direction * (ticks - self._zero) / self._ticks_per_rad - self._offset
        velocities = self._direction * velocity * self._velocity_unit * (2.0 * math.pi / 60.0)
        padded = self.layout.padded
        return BusState(padded(positions), padded(velocities), padded(current * self._current_unit),
                        answered, alerts, failures)

    def hardware_errors(self) -> dict[str, list[str]]:
        """Servos whose Hardware Error Status is set (or that did not answer its read properly), by joint."""
        problems: list[str] = []
        bits = self.read_items(self.slots[0].model.hardware_error_status, 1, "Hardware Error Status", problems)
        out: dict[str, list[str]] = {}
        for index, slot in enumerate(self.slots):
            if index not in bits:
                out[slot.key] = ["no proper reply to its read"]
            elif bits[index][0]:
                out[slot.key] = hardware_error_names(bits[index][0]) or [f"bits {bits[index][0]:#04x}"]
        return out

    def write_goals(self, joints: np.ndarray, period: float) -> None:
        """One sync write per bus of every goal position ``(L, n)`` [rad]; with ``profile_velocity`` also the speed
        that reaches it in ``period`` [s] (at least one unit: 0 would mean unlimited)."""
        from dynamixel_sdk import GroupSyncWrite

        ticks = self._to_ticks(slice(None), joints[self.layout.rows, self.layout.cols])
        if self.profile_velocity:
            previous = ticks if self._last_ticks is None else self._last_ticks
            rpm = np.abs(ticks - previous) / (self._ticks_per_rad * 2.0 * math.pi) / period * 60.0
            speed = np.maximum(1, np.rint(rpm / self._velocity_unit)).astype(np.int64)
        self._last_ticks = ticks
        for line in self.lines:
            if not line.slots:
                continue
            model = self.slots[line.slots[0]].model
            address, length = (PROFILE_ADDRESS, 8) if self.profile_velocity else (model.goal_position, 4)
            writer = GroupSyncWrite(line.port, self._handler, address, length)
            payload = bytearray()
            for index in line.slots:
                if index in self.skipped:
                    continue
                data = int(ticks[index]).to_bytes(4, "little", signed=True)
                if self.profile_velocity:
                    data = int(speed[index]).to_bytes(4, "little") + data
                writer.addParam(self.slots[index].servo_id, data)
                payload += bytes([self.slots[index].servo_id]) + data
            if not payload:
                continue
            if p2.needs_stuffing(bytes(payload)):
                raise HardwareError(f"{line.name}: a goal payload contains FF FF FD, which dynamixel-sdk would send "
                                    "unstuffed")
            writer.txPacket()

    def torque(self, on: bool) -> None:
        """Torque enable (or disable) on every servo, one sync write per bus."""
        from dynamixel_sdk import GroupSyncWrite

        for line in self.lines:
            if not line.slots:
                continue
            writer = GroupSyncWrite(line.port, self._handler, self.slots[line.slots[0]].model.torque_enable, 1)
            for servo_id in line.ids:
                writer.addParam(servo_id, bytes([1 if on else 0]))
            writer.txPacket()

    def _to_ticks(self, index: Any, joints: np.ndarray) -> np.ndarray:
        """Joint angles [rad] of the slots ``index`` → servo ticks."""
        ticks: np.ndarray = np.rint(self._zero[index] + self._direction[index] * (joints + self._offset[index])
                                    * self._ticks_per_rad[index]).astype(np.int64)
        return ticks

    def ticks_per_radian(self, index: int) -> float:
        """Slot ``index``'s servo ticks per radian (its model's units)."""
        return float(self._ticks_per_rad[index])

    def angle_to_ticks(self, index: int, angle: float) -> int:
        """Slot ``index``'s joint angle [rad] → its servo's ticks (zero, direction and the joint's offset)."""
        return int(self._to_ticks(index, np.array(angle)))

    def ticks_to_angle(self, index: int, ticks: float) -> float:
        """Slot ``index``'s servo ticks → its joint angle [rad]."""
        return float(self._direction[index] * (ticks - self._zero[index]) / self._ticks_per_rad[index]
                     - self._offset[index])

    def read_mode(self) -> str:
        """How the state is read (for messages)."""
        return "sync read"

    def measure_cycle(self, reads: int = 20) -> float:
        """Seconds a cycle occupies the bus, measured: the fastest of ``reads`` state reads (the adapter's and the
        host's turnaround included; the fastest, so that a busy computer's pauses do not count) plus the goal
        write's time on the wire. Before the torque is on."""
        import time

        times = []
        for _ in range(reads):
            began = time.perf_counter()
            self.read_state()
            times.append(time.perf_counter() - began)
        per_goal = 1 + (8 if self.profile_velocity else 4)
        write = max((14 + len(line.slots) * per_goal) * 10.0 / self.baud for line in self.lines)
        return min(times) + write

    def rate_problem(self, period: float, reads: int = 20) -> str | None:
        """Why the bus cannot keep ``period`` [s] (a sentence naming the rate it keeps and the fixes), or None."""
        cycle = self.measure_cycle(reads)
        if cycle <= period:
            return None
        longer = math.ceil(cycle * 1.2 * 1000.0) / 1000.0
        return (f"one cycle's reads and goal write take {cycle * 1e3:.1f} ms on the bus (the fastest of {reads} "
                f"reads, {self.read_mode()}, {max(len(line.slots) for line in self.lines)} servos on the busiest bus), "
                f"more than the {period * 1e3:.0f} ms period: it keeps {1.0 / cycle:.0f} Hz; set time_delta = "
                f"{longer:g} or more in the robot file, split the servos over more buses, or lower the USB "
                "adapter's latency timer (/sys/bus/usb-serial/devices/ttyUSB0/latency_timer = 1)")

    def wire_time(self) -> float:
        """Seconds one cycle's sync read (instruction + every status, each after its servo's Return Delay Time) and
        sync write occupy the busiest bus at this baud (buses run in parallel; 10 bits per byte on the wire; the
        USB adapter's latency not counted)."""
        per_goal = 9 if self.profile_velocity else 5
        busiest = 0.0
        for line in self.lines:
            count = len(line.slots)
            read = (14 + count + count * (11 + STATE_LENGTH)) * 10.0 / self.baud
            write = (14 + count * per_goal) * 10.0 / self.baud
            busiest = max(busiest, read + write + sum(self.return_delays[i] for i in line.slots))
        return busiest
