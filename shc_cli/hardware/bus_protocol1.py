"""Servo buses that speak the Protocol 1.0 framing: Dynamixel Protocol 1.0 (AX series, MX series with 1.0 firmware)
through dynamixel-sdk's Protocol 1.0 handler, and Feetech STS through feetech-servo-sdk (``scservo_sdk``).

The same interface as the Protocol 2.0 :class:`~shc_cli.hardware.bus.ServoBus` (``run-hw``'s backend does not know
which it drives). Per cycle and bus, the state read (Present Position, Speed and Load: 6 bytes) is

* Dynamixel Protocol 1.0, every servo an MX: one BULK READ (MX series only). dynamixel-sdk 4.1.0's GroupBulkRead
  cannot send it with Protocol 1.0 (its ``txPacket`` passes ``bulkReadTx`` an extra argument), so the bus sends it
  with ``PacketHandler.bulkReadTx`` itself and receives each status with ``readRx``;
* Dynamixel Protocol 1.0 with an AX on the bus: one READ per servo (the AX series has neither SYNC READ nor BULK
  READ) — interleaved over the buses, so several buses still answer in parallel; see docs/performance.md for the
  rate that keeps;
* Feetech: one SYNC READ, each status received with ``readRx``.

Every status packet's error byte is kept: the servo's protection bits (input voltage, overheating, overload; for
Feetech also angle sensor and overcurrent) are a fault named by servo in the same cycle. Goals go out in one SYNC
WRITE per bus. Present Load (0.1 % of the maximum torque, sign-magnitude) is reported as a current estimate: the
share times the model's stall current.

feetech-servo-sdk 1.0's ``PortHandler.clearPort`` flushes the output only, so a status packet that arrived after
its read timed out would answer the next read: the Feetech bus clears the input before every instruction and,
after a failed read, waits for the line to fall silent before it asks again. Its ``PacketHandler(0)`` (STS,
little-endian words) sets a module-wide byte order: the bus decodes every word itself.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

import numpy as np

from shc_cli.hardware.bus import BusState, HardwareError, ServoBus, _Line, open_port, patient_port
from shc_cli.hardware.models import (
    FAMILY_NAMES,
    PROTOCOL1_HARDWARE,
    TABLES,
    ControlTable,
    Family,
    hardware_error_names,
)
from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

FEETECH_ALERTS = 1 | 2 | 4 | 8 | 32
"""Feetech status bits that are the servo's protection (voltage, angle sensor, overheating, overcurrent, overload)."""
READ_WAIT_S = 0.001
"""How long one serial read blocks for its bytes [s]: the SDKs' receive loops call it with their own deadline, so
this only replaces their busy polling (timeout 0) with waiting (the packet timeouts are unchanged)."""
PROTOCOL1_BAUD = {1_000_000: 1, 500_000: 3, 400_000: 4, 250_000: 7, 200_000: 9, 115_200: 16, 57_600: 34}
"""Protocol 1.0 Baud Rate values (2,000,000 / (value + 1) bit/s)."""


def _magnitude(raw: np.ndarray, bit: int) -> np.ndarray:
    """Sign-magnitude words (``bit`` set: negative) as signed numbers."""
    sign = np.where(raw & (1 << bit), -1.0, 1.0)
    return np.asarray(sign * (raw & ((1 << bit) - 1)), dtype=float)


class Protocol1Bus(ServoBus):
    """Dynamixel Protocol 1.0 servos (AX-12A, AX-18A, MX-28/64/106 with 1.0 firmware) on one bus per port.

    Args: as :class:`~shc_cli.hardware.bus.ServoBus`; ``profile_velocity`` writes Moving Speed with each goal.
    """

    family: Family = "protocol1"
    alert_bits = PROTOCOL1_HARDWARE

    def __init__(self, robot: Robot, ports: list[str] | str, baud: int | None = None,
                 profile_velocity: bool = False) -> None:
        super().__init__(robot, ports, baud, profile_velocity)
        wrong = [s for s in self.slots if s.model.family != self.family]
        if wrong:
            raise HardwareError(f"{robot.name}: {wrong[0].key} is a {wrong[0].model.name} "
                                f"({FAMILY_NAMES[wrong[0].model.family]}), not {FAMILY_NAMES[self.family]}")
        self.table: ControlTable = TABLES[self.family]
        self._stall_ma = np.array([1000.0 * (s.model.datasheet.stall_current if s.model.datasheet else 1.0)
                                   for s in self.slots])
        self._speed_unit = np.array([s.model.velocity_unit_rpm for s in self.slots])
        self._load_unit = np.array([s.model.load_unit for s in self.slots])
        self._last_tick = np.array([s.model.resolution - 1 for s in self.slots])
        """Each servo's last position tick (1023 for the AX series, 4095 for MX and STS)."""
        self._sdk: Any = None
        self.errors: dict[int, int] = {}
        """The last status error byte of each servo (slot) that had one set."""

    # -- the SDK -----------------------------------------------------------------------------------------------

    def _import(self) -> Any:
        import dynamixel_sdk

        return dynamixel_sdk

    def _make_handler(self) -> Any:
        return self._sdk.PacketHandler(1.0)

    def _make_port(self, name: str) -> Any:
        return patient_port(self._sdk.PortHandler)(name)

    def open(self) -> None:
        self._sdk = self._import()
        self._handler = self._make_handler()
        for line in self.lines:
            port = open_port(self._make_port(line.name), line.name, self.baud, self.close)
            port.ser.timeout = READ_WAIT_S  # the SDKs poll with timeout 0: a spinning host starves a busy computer
            line.port = port
            line.ids = [self.slots[i].servo_id for i in line.slots]

    def _clear(self, line: _Line) -> None:
        """Empty the input (dynamixel-sdk's clearPort does; Feetech's does not)."""
        line.port.ser.reset_input_buffer()

    def _settle(self, line: _Line) -> None:
        """After a failed read: wait until the line has been silent for 2 ms (at most 50 ms), emptying the input,
        so a late status packet cannot answer the next instruction."""
        deadline = time.monotonic() + 0.05
        self._clear(line)
        quiet_since = time.monotonic()
        while time.monotonic() < deadline and time.monotonic() - quiet_since < 0.002:
            time.sleep(0.0005)
            if line.port.ser.in_waiting:
                self._clear(line)
                quiet_since = time.monotonic()

    # -- transactions ------------------------------------------------------------------------------------------

    def _read(self, index: int, address: int, length: int, again: bool = True) -> tuple[bytes | None, int, str]:
        """One READ of a servo: (data or None, error byte, why it failed); without a proper reply it is asked once
        more (``again``) after the line fell silent."""
        line = self.lines[self.slots[index].bus]
        self._clear(line)
        data, result, error = self._handler.readTxRx(line.port, self.slots[index].servo_id, address, length)
        got = self._judge(data, result, error, length)
        if got[0] is None and again:
            self.retries += 1
            self._settle(line)
            return self._read(index, address, length, again=False)
        return got

    def _judge(self, data: Any, result: int, error: int, length: int) -> tuple[bytes | None, int, str]:
        if result != self._sdk.COMM_SUCCESS:
            return None, 0, "corrupt reply (checksum or length)" if result == self._sdk.COMM_RX_CORRUPT else "no reply"
        if len(data) != length:
            return None, error, "short reply"
        return bytes(data), error, ""

    def _write(self, index: int, address: int, data: bytes, name: str) -> None:
        """One WRITE with its status checked; without a proper status it is written once more after the line fell
        silent (the start's settings: the same bytes again)."""
        slot = self.slots[index]
        line = self.lines[slot.bus]
        for attempt in range(2):
            self._clear(line)
            result, error = self._handler.writeTxRx(line.port, slot.servo_id, address, len(data), list(data))
            if result == self._sdk.COMM_SUCCESS or attempt:
                break
            self.retries += 1
            self._settle(line)
        if result != self._sdk.COMM_SUCCESS or error & ~self.alert_bits:
            reason = (self._handler.getTxRxResult(result) if result != self._sdk.COMM_SUCCESS
                      else ", ".join(hardware_error_names(error, self.family)))
            raise HardwareError(f"{slot.key}: servo {slot.servo_id} refused {name} (address {address}): {reason}")

    def read_items(self, address: int, length: int, name: str, problems: list[str]) -> dict[int, bytes]:
        """One READ per servo of ``length`` bytes at ``address``: the data by slot; a servo that does not answer
        properly adds a problem naming it."""
        out: dict[int, bytes] = {}
        for index, slot in enumerate(self.slots):
            data, error, failure = self._read(index, address, length)
            if data is None:
                problems.append(f"{slot.key}: servo {slot.servo_id}, {name} read (address {address}): {failure}")
            elif error & ~self.alert_bits:
                problems.append(f"{slot.key}: servo {slot.servo_id}, {name} read (address {address}): "
                                f"{', '.join(hardware_error_names(error, self.family))} error")
            else:
                out[index] = data
        return out

    def _model_number(self, index: int) -> tuple[int | None, int]:
        """(model number or None if the servo did not answer, error byte)."""
        data, error, _ = self._read(index, self.table.model_number, 2)
        return (None, error) if data is None else (int.from_bytes(data, "little"), error)

    # -- checking and configuring ------------------------------------------------------------------------------

    def check(self) -> list[str]:
        """Missing servos, wrong models, protection bits set, servos not in position control, joint limits
        outside the servo's angle limits, a Status Return Level that leaves reads unanswered."""
        problems: list[str] = []
        for index, slot in enumerate(self.slots):
            number, error = self._model_number(index)
            line = self.lines[slot.bus]
            if number is None:
                problems.append(f"{slot.key}: servo {slot.servo_id} does not answer on {line.name} at {self.baud} "
                                "baud")
            elif number != slot.model.model_number:
                problems.append(f"{slot.key}: servo {slot.servo_id} is model number {number}, not a "
                                f"{slot.model.name} ({slot.model.model_number})")
            elif error & self.alert_bits:
                names = hardware_error_names(error & self.alert_bits, self.family)
                problems.append(f"{slot.key}: hardware error ({', '.join(names)})")
        if problems:
            return problems
        return self._check_settings()

    def _check_settings(self) -> list[str]:
        problems: list[str] = []
        table = self.table
        limits = self.read_items(table.min_position_limit, 4, "angle limits", problems)
        delays = self.read_items(table.return_delay_time, 1, "Return Delay Time", problems)
        modes = self.read_items(table.mode, 1, "Operating Mode", problems) if table.mode is not None else {}
        for index, data in delays.items():
            self.return_delays[index] = 2e-6 * data[0]
        for index, slot in enumerate(self.slots):
            if index in modes and modes[index][0] != 0:
                problems.append(f"{slot.key}: servo {slot.servo_id} is in operating mode {modes[index][0]}; set "
                                f"Operating Mode (address {table.mode}) to 0 (position)")
                continue
            if index not in limits:
                continue
            low = int.from_bytes(limits[index][0:2], "little")
            high = int.from_bytes(limits[index][2:4], "little")
            if low == high == 0:
                what = "wheel mode" if self.family == "protocol1" else "multi-turn mode"
                problems.append(f"{slot.key}: servo {slot.servo_id} is in {what} (both angle limits 0); set its "
                                f"angle limits (addresses {table.min_position_limit}, {table.max_position_limit})")
                continue
            ends = sorted(self._to_ticks(index, np.array(slot.limits)))
            # one tick of rounding: a limit at the end of an AX's 300° (±150°: tick 1024) is its last tick, 1023
            if ends[0] < low - 1 or ends[1] > high + 1:
                problems.append(f"{slot.key}: the joint limits {slot.limits[0]:.3f}..{slot.limits[1]:.3f} rad are "
                                f"ticks {ends[0]}..{ends[1]}, outside servo {slot.servo_id}'s angle limits "
                                f"{low}..{high}; widen the servo's angle limits or fix zero_ticks, direction or the "
                                "joint limits")
        return problems

    def configure(self) -> list[str]:
        """Write the robot file's Return Delay Time where a servo differs (Protocol 1.0 and Feetech servos have no
        current limit: ``current_limit_ma`` is not written)."""
        hardware, done = self.robot.hardware, []
        if hardware.return_delay_us is not None:
            value = hardware.return_delay_us // 2
            changed = [i for i, delay in enumerate(self.return_delays) if round(delay / 2e-6) != value]
            for index in changed:
                self._write(index, self.table.return_delay_time, bytes([value]), "Return Delay Time")
                self.return_delays[index] = 2e-6 * value
            if changed:
                done.append(f"return delay time {2 * value} µs written to {len(changed)} servos")
        if hardware.current_limit_ma is not None:
            done.append(f"current limit not written: {FAMILY_NAMES[self.family]} servos have none (set their torque "
                        "limit instead)")
        return done

    # -- the cycle ---------------------------------------------------------------------------------------------

    def _uses_bulk(self, line: _Line) -> bool:
        return bool(line.slots) and all(self.slots[i].model.bulk_read for i in line.slots)

    def _send_state(self, line: _Line) -> None:
        """The BULK READ of every servo's state (MX-only buses)."""
        table = self.table
        param = [v for servo_id in line.ids for v in (table.state_length, servo_id, table.present_position)]
        self._clear(line)
        self._handler.bulkReadTx(line.port, param, len(param))  # not GroupBulkRead: it breaks with Protocol 1.0

    def _receive_chain(self, line: _Line, length: int, replies: dict[int, tuple[bytes, int]],
                       failures: dict[int, str]) -> None:
        """Each listed servo's status in order (readRx keeps the error byte); a missing or corrupt one leaves the
        rest unread."""
        for index in line.slots:
            data, result, error = self._handler.readRx(line.port, self.slots[index].servo_id, length)
            got, error, failure = self._judge(data, result, error, length)
            if got is None:
                failures[index] = failure
                return
            replies[index] = (got, error)

    def _read_line_state(self, line: _Line, sent: bool) -> tuple[dict[int, tuple[bytes, int]], dict[int, str]]:
        """The state of one bus's servos read by a chain (bulk or sync read), repeated once after a failure."""
        for attempt in range(2):
            if attempt or not sent:
                self._send_state(line)
            replies: dict[int, tuple[bytes, int]] = {}
            failures: dict[int, str] = {}
            self._receive_chain(line, self.table.state_length, replies, failures)
            if not failures or attempt:
                return replies, failures
            self.retries += 1
            self._settle(line)
        raise AssertionError("unreachable")

    def read_state(self) -> BusState:
        """Position, speed and load of every servo: a chain read per bus where the models allow it, else one READ
        per servo, interleaved over the buses (the buses answer in parallel); each read that fails is repeated
        once. A servo that fails (and, in a chain, the rest of its bus) counts as unanswered."""
        count, length = len(self.slots), self.table.state_length
        raw = np.zeros((count, length), dtype=np.uint8)
        answered = np.zeros(count, dtype=bool)
        alerts = np.zeros(count, dtype=bool)
        failures: dict[int, str] = {}
        replies: dict[int, tuple[bytes, int]] = {}
        chained = [line for line in self.lines if self._chain(line)]
        for line in chained:
            self._send_state(line)
        single = [line for line in self.lines if line.slots and line not in chained]
        for rank in range(max((len(line.slots) for line in single), default=0)):
            turn = [line for line in single if rank < len(line.slots) and not any(i in failures for i in line.slots)]
            for line in turn:  # every bus gets its instruction before any reply is awaited
                self._clear(line)
                self._handler.readTx(line.port, line.ids[rank], self.table.present_position, length)
            for line in turn:
                index = line.slots[rank]
                data, result, error = self._handler.readRx(line.port, line.ids[rank], length)
                got, error, failure = self._judge(data, result, error, length)
                if got is None:
                    self.retries += 1
                    self._settle(line)
                    got, error, failure = self._read(index, self.table.present_position, length, again=False)
                if got is None:
                    failures[index] = failure
                else:
                    replies[index] = (got, error)
        for line in chained:
            got_replies, missed = self._read_line_state(line, sent=True)
            replies.update(got_replies)
            failures.update(missed)
        for index, (data, error) in replies.items():
            raw[index] = np.frombuffer(data, dtype=np.uint8)
            answered[index] = True
            alerts[index] = bool(error & self.alert_bits)
            if error:
                self.errors[index] = error
        words = raw.astype(np.int64)
        ticks = (words[:, 0] | words[:, 1] << 8).astype(float)
        speed = self._decode_speed(words[:, 2] | words[:, 3] << 8)
        load = _magnitude(words[:, 4] | words[:, 5] << 8, 10) * self._load_unit
        positions = self._direction * (ticks - self._zero) / self._ticks_per_rad - self._offset
        velocities = self._direction * speed
        currents = self._direction * load * self._stall_ma
        padded = self.layout.padded
        return BusState(padded(positions), padded(velocities), padded(currents), answered, alerts,
                        failures)

    def _chain(self, line: _Line) -> bool:
        """Whether the bus reads its servos' state with one instruction (BULK READ: MX-only)."""
        return self._uses_bulk(line)

    def _decode_speed(self, raw: np.ndarray) -> np.ndarray:
        """Present Speed words → [rad/s] (bit 10: clockwise, i.e. decreasing position)."""
        return np.asarray(_magnitude(raw, 10) * self._speed_unit * (2.0 * math.pi / 60.0))

    def hardware_errors(self) -> dict[str, list[str]]:
        """Servos whose status packets carry protection bits (or that no longer answer), by joint."""
        out: dict[str, list[str]] = {}
        for index, slot in enumerate(self.slots):
            _, error = self._model_number(index)
            error |= self.errors.get(index, 0)
            if error & self.alert_bits:
                out[slot.key] = hardware_error_names(error & self.alert_bits, self.family)
        return out

    def _sync_write(self, line: _Line, address: int, length: int, data: dict[int, bytes]) -> None:
        writer = self._sdk.GroupSyncWrite(line.port, self._handler, address, length)
        for servo_id, values in data.items():
            writer.addParam(servo_id, list(values))
        self._clear(line)
        writer.txPacket()

    def write_goals(self, joints: np.ndarray, period: float) -> None:
        """One SYNC WRITE per bus of every goal position ``(L, n)`` [rad]; with ``profile_velocity`` also the speed
        that reaches it in ``period`` [s] (at least one unit: 0 means the servo's maximum)."""
        ticks = self._to_ticks(slice(None), joints[self.layout.rows, self.layout.cols])
        ticks = np.clip(ticks, 0, self._last_tick)  # a joint limit at the range's end rounds one tick past it
        if self.profile_velocity:
            previous = ticks if self._last_ticks is None else self._last_ticks
            rpm = np.abs(ticks - previous) / (self._ticks_per_rad * 2.0 * math.pi) / period * 60.0
            speed = np.clip(np.rint(rpm / self._speed_unit), 1, self._max_speed_word()).astype(np.int64)
        self._last_ticks = ticks
        address, length = self._goal_layout()
        for line in self.lines:
            if not line.slots:
                continue
            data = {}
            for index in (i for i in line.slots if i not in self.skipped):
                payload = int(ticks[index]).to_bytes(2, "little")
                if self.profile_velocity:
                    payload += self._speed_payload(int(speed[index]))
                data[self.slots[index].servo_id] = payload
            if data:
                self._sync_write(line, address, length, data)

    def _goal_layout(self) -> tuple[int, int]:
        """(address, length) of the goal write: Goal Position, + Moving Speed with ``profile_velocity``."""
        return self.table.goal_position, 4 if self.profile_velocity else 2

    def _speed_payload(self, speed: int) -> bytes:
        return speed.to_bytes(2, "little")

    def _max_speed_word(self) -> int:
        return 1023

    def torque(self, on: bool) -> None:
        """Torque Enable on every servo, one SYNC WRITE per bus."""
        for line in self.lines:
            if line.slots:
                self._sync_write(line, self.table.torque_enable, 1, {i: bytes([int(on)]) for i in line.ids})

    def wire_time(self) -> float:
        """Seconds one cycle's reads (every instruction and status, each status after its servo's Return Delay
        Time) and goal write occupy the busiest bus at this baud (10 bits per byte; the USB adapter's latency, which
        per-servo reads pay once per servo, not counted)."""
        length = self.table.state_length
        per_goal = 1 + self._goal_layout()[1]
        busiest = 0.0
        for line in self.lines:
            count = len(line.slots)
            status = (6 + length) * count
            read = 6 + self._chain_request_bytes(count) + status if self._chain(line) else 8 * count + status
            write = 8 + count * per_goal
            busiest = max(busiest, (read + write) * 10.0 / self.baud + sum(self.return_delays[i] for i in line.slots))
        return busiest

    def _chain_request_bytes(self, count: int) -> int:
        return 1 + 3 * count

    def read_mode(self) -> str:
        """How the state is read on the busiest kind of bus (for the summary and messages)."""
        if all(self._chain(line) for line in self.lines if line.slots):
            return "bulk read"
        return "one read per servo"


class _FeetechPort:
    """A feetech-servo-sdk PortHandler whose ``clearPort`` empties the input (the SDK's flushes the output only)."""

    def __new__(cls, name: str) -> Any:
        from scservo_sdk import PortHandler

        class Port(patient_port(PortHandler)):  # type: ignore[misc]
            def clearPort(self) -> None:
                self.ser.reset_input_buffer()

        return Port(name)


class FeetechBus(Protocol1Bus):
    """Feetech STS servos (STS3215 and siblings; SMS/STS memory table) on one bus per port, through
    feetech-servo-sdk: SYNC READ of the state, SYNC WRITE of the goals."""

    family: Family = "feetech"
    alert_bits = FEETECH_ALERTS

    def _import(self) -> Any:
        import scservo_sdk

        return scservo_sdk

    def _make_handler(self) -> Any:
        return self._sdk.PacketHandler(0)  # 0: STS byte order (1 would be SCS)

    def _make_port(self, name: str) -> Any:
        return _FeetechPort(name)

    def _chain(self, line: _Line) -> bool:
        return bool(line.slots)

    def _send_state(self, line: _Line) -> None:
        """The SYNC READ of every servo's state."""
        self._clear(line)
        self._handler.syncReadTx(line.port, self.table.present_position, self.table.state_length, list(line.ids),
                                 len(line.ids))

    def _chain_request_bytes(self, count: int) -> int:
        return 2 + count

    def _decode_speed(self, raw: np.ndarray) -> np.ndarray:
        """Present Speed words (steps/s, bit 15 the sign) → [rad/s]."""
        return np.asarray(_magnitude(raw, 15) / self._ticks_per_rad)

    def _goal_layout(self) -> tuple[int, int]:
        """Goal Position; with ``profile_velocity`` also Goal Time (0) and Goal Speed [steps/s]."""
        return self.table.goal_position, 6 if self.profile_velocity else 2

    def _speed_payload(self, speed: int) -> bytes:
        return bytes(2) + speed.to_bytes(2, "little")

    def _max_speed_word(self) -> int:
        return 0x7FFF

    def read_mode(self) -> str:
        return "sync read"
