"""The e-Manual emulator (tests/emanual_emulator.py) against the e-Manual's worked examples, and ``shc run-hw`` end to
end against it.

Packets in the example tests are copied from the ROBOTIS e-Manual, "DYNAMIXEL Protocol 2.0", Instruction Details.
"""

from __future__ import annotations

import csv
import json
import math
import os
import select
import subprocess
import sys
import time
import tomllib
import tty
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from tests.emanual_emulator import (
    ACCESS_ERROR,
    ACTION,
    ALERT,
    BULK_READ,
    BULK_WRITE,
    CLEAR,
    CRC_ERROR,
    DATA_LENGTH_ERROR,
    DATA_LIMIT_ERROR,
    DATA_RANGE_ERROR,
    FACTORY_RESET,
    GOAL_POSITION,
    INSTRUCTION_ERROR,
    OVERLOAD_ERROR,
    PING,
    READ,
    REBOOT,
    REG_WRITE,
    RESULT_FAIL,
    SYNC_READ,
    SYNC_WRITE,
    WRITE,
    EManualBus,
    ServoConfig,
    crc16,
    packet,
    parse_packets,
    status_packet,
)

ROOT = Path(__file__).resolve().parent.parent
BULLET = tomllib.loads((ROOT / "robots" / "bullet.toml").read_text(encoding="utf-8"))
SERVOS = {spec["id"]: name for name, spec in BULLET["hardware"]["servos"].items()}
"""bullet's servo ID → joint (30 MX-106, IDs 11–15 … 61–65, 1 Mbaud)."""
TICKS_PER_RAD = 4096 / (2 * math.pi)
ACK = bytes.fromhex("FFFFFD0001040055 00A10C".replace(" ", ""))
"""The e-Manual's status packet of ID 1 with no error and no parameters."""


def h(text: str) -> bytes:
    """Bytes from the e-Manual's hex notation (spaces ignored)."""
    return bytes.fromhex(text.replace(" ", ""))


def u32(value: int) -> bytes:
    return (value % (1 << 32)).to_bytes(4, "little")


def u16(value: int) -> bytes:
    return (value % (1 << 16)).to_bytes(2, "little")


class Host:
    """The host end: the pty slave opened raw, like a USB2Dynamixel."""

    def __init__(self, port: str) -> None:
        self.fd = os.open(port, os.O_RDWR | os.O_NOCTTY)
        tty.setraw(self.fd)

    def send(self, data: bytes) -> None:
        os.write(self.fd, data)

    def receive(self, count: int = 1 << 16, timeout_s: float = 0.3) -> bytes:
        """Up to ``count`` bytes, waiting at most ``timeout_s`` [s] for them."""
        out = b""
        deadline = time.monotonic() + timeout_s
        while len(out) < count:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self.fd], [], [], left)[0]:
                break
            out += os.read(self.fd, count - len(out))
        return out

    def transact(self, data: bytes, count: int = 1 << 16, timeout_s: float = 0.3) -> bytes:
        self.send(data)
        return self.receive(count, timeout_s)

    def status(self, data: bytes, timeout_s: float = 0.5) -> tuple[int, bytes]:
        """Sends an instruction packet; (error, parameters) of the status packet that answers it (returns as soon as
        it is complete)."""
        self.send(data)
        raw = b""
        deadline = time.monotonic() + timeout_s
        while not parse_packets(raw) and time.monotonic() < deadline:
            raw += self.receive(timeout_s=0.01)
        replies = parse_packets(raw)
        assert len(replies) == 1, raw.hex()
        return replies[0].error, replies[0].data


@contextmanager
def emanual_bus(servos: dict[int, ServoConfig], **options: object) -> Iterator[tuple[EManualBus, Host]]:
    """An emulated bus and a host on it."""
    with EManualBus(servos, **options) as bus:  # type: ignore[arg-type]
        host = Host(bus.port)
        try:
            yield bus, host
        finally:
            os.close(host.fd)


def xm430(position: int = 2048, table: dict[int, int] | None = None) -> ServoConfig:
    """An XM430-W210 as in the e-Manual's examples (model number 1030, firmware 38); ``table``: address → value."""
    return ServoConfig("XM430-W210", position, table or {})


# -- the emulator against the e-Manual ---------------------------------------------------------------------------

def test_packets_and_crc_are_the_emanual_examples() -> None:
    examples = [  # (id, instruction, parameters, the e-Manual's packet)
        (1, PING, "", "FF FF FD 00 01 03 00 01 19 4E"),
        (0xFE, PING, "", "FF FF FD 00 FE 03 00 01 31 42"),
        (1, READ, "84 00 04 00", "FF FF FD 00 01 07 00 02 84 00 04 00 1D 15"),
        (1, WRITE, "74 00 00 02 00 00", "FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89"),
        (1, REG_WRITE, "68 00 C8 00 00 00", "FF FF FD 00 01 09 00 04 68 00 C8 00 00 00 AE 8E"),
        (1, ACTION, "", "FF FF FD 00 01 03 00 05 02 CE"),
        (1, FACTORY_RESET, "01", "FF FF FD 00 01 04 00 06 01 A1 E6"),
        (1, REBOOT, "", "FF FF FD 00 01 03 00 08 2F 4E"),
        (1, CLEAR, "01 44 58 4C 22", "FF FF FD 00 01 08 00 10 01 44 58 4C 22 B1 DC"),
        (0xFE, SYNC_READ, "84 00 04 00 01 02", "FF FF FD 00 FE 09 00 82 84 00 04 00 01 02 CE FA"),
        (0xFE, SYNC_WRITE, "74 00 04 00 01 96 00 00 00 02 AA 00 00 00",
         "FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87"),
        (0xFE, BULK_READ, "01 90 00 02 00 02 92 00 01 00",
         "FF FF FD 00 FE 0D 00 92 01 90 00 02 00 02 92 00 01 00 1A 05"),
        (0xFE, BULK_WRITE, "01 20 00 02 00 A0 00 02 1F 00 01 00 50",
         "FF FF FD 00 FE 10 00 93 01 20 00 02 00 A0 00 02 1F 00 01 00 50 B7 68"),
    ]
    for packet_id, instruction, params, expected in examples:
        assert packet(packet_id, instruction, h(params)) == h(expected)
    statuses = [  # (id, error, parameters, the e-Manual's status packet)
        (1, 0, "06 04 26", "FF FF FD 00 01 07 00 55 00 06 04 26 65 5D"),
        (2, 0, "06 04 26", "FF FF FD 00 02 07 00 55 00 06 04 26 6F 6D"),
        (1, 0, "A6 00 00 00", "FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0"),
        (2, 0, "1F 08 00 00", "FF FF FD 00 02 08 00 55 00 1F 08 00 00 BA BE"),
        (1, 0, "", "FF FF FD 00 01 04 00 55 00 A1 0C"),
        (1, 0, "77 00", "FF FF FD 00 01 06 00 55 00 77 00 C3 69"),
        (2, 0, "24", "FF FF FD 00 02 05 00 55 00 24 8B A9"),
    ]
    for packet_id, error, params, expected in statuses:
        assert status_packet(packet_id, error, h(params)) == h(expected)
    assert crc16(h("FF FF FD 00 01 03 00 01")) == 0x4E19


def test_single_servo_instructions_answer_as_in_the_emanual() -> None:
    with emanual_bus({1: xm430(166), 2: xm430()}, baud=57_600) as (bus, host):  # Baud Rate(8) 1, the default
        assert host.transact(h("FF FF FD 00 01 03 00 01 19 4E"), 14) == h("FF FF FD 00 01 07 00 55 00 06 04 26 65 5D")
        assert host.transact(h("FF FF FD 00 FE 03 00 01 31 42"), 28) == (
            h("FF FF FD 00 01 07 00 55 00 06 04 26 65 5D") + h("FF FF FD 00 02 07 00 55 00 06 04 26 6F 6D"))
        assert host.transact(h("FF FF FD 00 01 07 00 02 84 00 04 00 1D 15"), 15) == (
            h("FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0"))
        assert host.transact(h("FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89"), 11) == ACK
        assert bus.goal(1) == 512
        assert host.transact(h("FF FF FD 00 01 09 00 04 68 00 C8 00 00 00 AE 8E"), 11) == ACK
        servo = bus.servos[1]
        assert servo.get(69) == 1 and servo.get(104) == 0  # registered, not yet executed
        assert host.transact(h("FF FF FD 00 01 03 00 05 02 CE"), 11) == ACK
        assert servo.get(69) == 0 and servo.get(104) == 200
        assert host.transact(h("FF FF FD 00 01 08 00 10 01 44 58 4C 22 B1 DC"), 11) == ACK  # CLEAR
        host.send(packet(1, WRITE, h("0900") + bytes([7])))  # Return Delay Time 14 µs: EEPROM, torque off
        assert host.receive(11) == ACK and servo.get(9) == 7
        assert host.transact(h("FF FF FD 00 01 04 00 06 01 A1 E6"), 11) == ACK  # FACTORY RESET all but ID
        assert host.status(packet(1, READ, h("0700 0300"))) == (0, bytes([1, 1, 250]))  # ID, Baud Rate, delay
        host.send(packet(1, WRITE, h("4000 01")))  # torque on
        assert host.receive(11) == ACK and servo.torque_on
        assert host.transact(h("FF FF FD 00 01 03 00 08 2F 4E"), 11) == ACK  # REBOOT: torque off again
        assert host.status(packet(1, READ, h("4000 0100"))) == (0, b"\x00")
        assert bus.goal(1) == bus.position(1) == 166
        assert bus.protocol_violations == []
        assert [p.instruction for p in bus.packets] == [PING, PING, READ, WRITE, REG_WRITE, ACTION, CLEAR, WRITE,
                                                         FACTORY_RESET, READ, WRITE, REBOOT, READ]


def test_sync_and_bulk_instructions_as_in_the_emanual() -> None:
    servos = {1: xm430(166, {144: 119}), 2: xm430(2079, {146: 36})}
    with emanual_bus(servos) as (bus, host):
        assert host.transact(h("FF FF FD 00 FE 09 00 82 84 00 04 00 01 02 CE FA"), 30) == (
            h("FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0") + h("FF FF FD 00 02 08 00 55 00 1F 08 00 00 BA BE"))
        # the replies come in the order of the IDs in the instruction
        replies = parse_packets(host.transact(packet(0xFE, SYNC_READ, h("84 00 04 00 02 01")), 30))
        assert [r.packet_id for r in replies] == [2, 1]
        host.send(h("FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87"))
        assert host.receive(timeout_s=0.05) == b""  # SYNC WRITE: no status
        host.status(packet(1, PING))  # packets are executed in order: the SYNC WRITE is done
        assert (bus.goal(1), bus.goal(2)) == (150, 170)
        assert host.transact(h("FF FF FD 00 FE 0D 00 92 01 90 00 02 00 02 92 00 01 00 1A 05"), 25) == (
            h("FF FF FD 00 01 06 00 55 00 77 00 C3 69") + h("FF FF FD 00 02 05 00 55 00 24 8B A9"))
        host.send(h("FF FF FD 00 FE 10 00 93 01 20 00 02 00 A0 00 02 1F 00 01 00 50 B7 68"))
        assert host.receive(timeout_s=0.05) == b""  # BULK WRITE: no status
        host.status(packet(1, PING))
        assert bus.servos[1].get(32) == 160 and bus.servos[2].get(31) == 80
        assert bus.protocol_violations == []


def test_byte_stuffing_both_ways() -> None:
    """Goal Position −131,073 (extended position mode) is FF FF FD FF on the wire: stuffed to FF FF FD FD FF."""
    with emanual_bus({1: xm430(table={11: 4})}) as (bus, host):
        value = u32(-131_073)
        assert value == h("FF FF FD FF")
        request = packet(1, WRITE, h("7400") + value)
        assert h("FF FF FD FD FF") in request and request[5] == 10  # length counts the stuffing byte
        assert host.status(request) == (0, b"")
        assert bus.goal(1) == -131_073
        raw = host.transact(packet(1, READ, h("7400 0400")), 16)  # the status packet is stuffed too
        assert raw[5:7] == h("09 00") and raw[9:14] == h("FF FF FD FD FF")
        assert crc16(raw[:-2]) == raw[-2] | raw[-1] << 8
        assert parse_packets(raw)[0].data == value
        assert bus.protocol_violations == []

        from dynamixel_sdk import COMM_SUCCESS, PacketHandler, PortHandler  # the SDK un-stuffs a status packet

        port = PortHandler(bus.port)
        assert port.openPort()
        read, result, error = PacketHandler(2.0).read4ByteTxRx(port, 1, GOAL_POSITION)
        port.closePort()
        assert (read, result, error) == (0xFFFDFFFF, COMM_SUCCESS, 0)

        unstuffed = h("FF FF FD 00 01 09 00 03 74 00") + value  # as a sender that does not stuff
        assert host.status(unstuffed + u16(crc16(unstuffed))) == (0, b"")
        [violation] = bus.protocol_violations
        assert "without byte stuffing" in violation.description and violation.raw.startswith(unstuffed)


def test_a_packet_split_across_writes_after_garbage() -> None:
    with emanual_bus({1: xm430()}) as (bus, host):
        ping = h("FF FF FD 00 01 03 00 01 19 4E")
        host.send(h("00 13 FF FE FF FD") + ping[:5])
        time.sleep(0.02)
        host.send(ping[5:8])
        time.sleep(0.02)
        assert host.transact(ping[8:], 14) == h("FF FF FD 00 01 07 00 55 00 06 04 26 65 5D")
        assert [p.instruction for p in bus.packets] == [PING]
        assert [v.raw for v in bus.protocol_violations] == [h("00 13 FF FE FF FD")]
        # a packet with a wrong length swallows the next one; the CRC check finds it again
        bus.protocol_violations.clear()
        wrong_length = bytearray(h("FF FF FD 00 01 05 00 01"))
        wrong_length += u16(crc16(bytes(wrong_length)))
        replies = parse_packets(host.transact(bytes(wrong_length) + ping, 25))
        assert [(r.packet_id, r.error) for r in replies] == [(1, CRC_ERROR), (1, 0)]
        assert "CRC" in bus.protocol_violations[0].description


def test_errors_as_the_emanual_defines_them() -> None:
    with emanual_bus({1: xm430(table={48: 3000})}) as (bus, host):
        servo = bus.servos[1]
        assert host.status(packet(1, 0x07)) == (INSTRUCTION_ERROR, b"")  # undefined instruction
        assert host.status(packet(1, ACTION)) == (INSTRUCTION_ERROR, b"")  # ACTION without REG WRITE
        assert host.status(packet(1, WRITE, h("0000") + u16(1))) == (ACCESS_ERROR, b"")  # Model Number: read only
        assert host.status(packet(1, READ, h("0E00 0100"))) == (ACCESS_ERROR, b"")  # address 14 is not defined
        assert host.status(packet(1, WRITE, h("7400") + u16(100))) == (DATA_LENGTH_ERROR, b"")  # 2 of 4 bytes
        assert host.status(packet(1, WRITE, h("4000 02"))) == (DATA_RANGE_ERROR, b"")  # Torque Enable 0 ~ 1
        assert host.status(packet(1, WRITE, h("7400") + u32(3001))) == (DATA_LIMIT_ERROR, b"")  # > Max Position
        assert bus.goal(1) == 2048  # not applied
        assert host.status(packet(1, WRITE, h("7400") + u32(3000))) == (0, b"")
        assert host.status(packet(1, WRITE, h("4000 01"))) == (0, b"")
        assert host.status(packet(1, WRITE, h("0900 00"))) == (ACCESS_ERROR, b"")  # EEPROM locked by the torque
        assert servo.get(9) == 250
        assert [r.error for r in servo.rejected] == [ACCESS_ERROR, DATA_LENGTH_ERROR, DATA_RANGE_ERROR,
                                                     DATA_LIMIT_ERROR, ACCESS_ERROR]
        corrupt = bytearray(packet(1, PING))
        corrupt[-1] ^= 0x01
        assert host.status(bytes(corrupt)) == (CRC_ERROR, b"")
        assert [v.description.split()[0] for v in bus.protocol_violations] == ["CRC"]
        # a SYNC WRITE out of limits gets no status, but is not applied either
        host.send(packet(0xFE, SYNC_WRITE, h("7400 0400 01") + u32(4000)))
        assert host.receive(timeout_s=0.05) == b""
        host.status(packet(1, PING))
        assert bus.goal(1) == 3000
        assert servo.rejected[-1].error == DATA_LIMIT_ERROR
    with emanual_bus({1: xm430()}, undefined_reads="zero") as (bus, host):  # the lenient reading of gaps
        assert host.status(packet(1, READ, h("0B00 2D00")))[0] == 0  # Operating Mode(11) .. Min Position Limit
        assert host.status(packet(1, READ, h("0E00 0100"))) == (ACCESS_ERROR, b"")  # not starting on an item


def test_hardware_error_sets_the_alert_bit_and_shuts_down() -> None:
    with emanual_bus({1: xm430()}) as (bus, host):
        assert host.status(packet(1, WRITE, h("4000 01"))) == (0, b"")
        bus.hardware_error(1, OVERLOAD_ERROR)
        assert not bus.servos[1].torque_on  # Overload is in Shutdown(63) by default
        assert host.status(packet(1, PING)) == (ALERT, h("06 04 26"))
        assert host.status(packet(1, READ, h("4600 0100"))) == (ALERT, bytes([OVERLOAD_ERROR]))
        assert host.status(packet(1, WRITE, h("4000 01"))) == (ALERT | RESULT_FAIL, b"")  # only REBOOT helps
        assert host.status(packet(1, REBOOT)) == (ALERT, b"")
        assert host.status(packet(1, WRITE, h("4000 01"))) == (0, b"")
        assert bus.servos[1].torque_on


def test_status_return_level_and_return_delay_time() -> None:
    with emanual_bus({1: xm430(table={68: 0}), 2: xm430(table={68: 1}), 3: xm430(table={9: 0})}) as (bus, host):
        for servo_id, answers in ((1, (True, False, False)), (2, (True, True, False)), (3, (True, True, True))):
            got = tuple(bool(host.transact(data, timeout_s=0.05)) for data in (
                packet(servo_id, PING), packet(servo_id, READ, h("8400 0400")), packet(servo_id, WRITE, h("4100 01"))))
            assert got == answers, servo_id
            assert bus.servos[servo_id].get(65) == 1  # the write was executed either way
        host.send(packet(0xFE, WRITE, h("4100 00")))  # broadcast: executed by all, answered by none
        assert host.receive(timeout_s=0.05) == b""
        host.status(packet(3, PING))
        assert all(servo.get(65) == 0 for servo in bus.servos.values())
        replies = parse_packets(host.transact(packet(0xFE, SYNC_READ, h("8400 0400 01 02 03")), 45))
        assert [r.packet_id for r in replies] == [2, 3]  # level 0 does not answer a SYNC READ

        def latency(servo_id: int) -> float:
            started = time.monotonic()
            assert host.transact(packet(servo_id, PING), 14)
            return time.monotonic() - started

        assert min(latency(2) for _ in range(5)) >= 500e-6  # Return Delay Time 250 × 2 µs
        host.send(packet(3, WRITE, h("0900") + bytes([200])))  # 400 µs
        assert host.receive(11) and min(latency(3) for _ in range(5)) >= 400e-6


def test_motion_follows_the_goal_within_the_profile_velocity() -> None:
    with emanual_bus({1: xm430(table={112: 50})}) as (bus, host):  # 50 × 0.229 rpm = 781 ticks/s
        assert host.status(packet(1, WRITE, h("4000 01"))) == (0, b"")
        started = time.monotonic()
        assert host.status(packet(1, WRITE, h("7400") + u32(3048))) == (0, b"")
        time.sleep(0.3)
        error, data = host.status(packet(1, READ, h("7E00 0A00")))  # current, velocity, position
        elapsed = time.monotonic() - started
        current, velocity, position = (int.from_bytes(data[a:b], "little", signed=True) for a, b in
                                       ((0, 2), (2, 6), (6, 10)))
        assert error == 0 and velocity == 50 and current > 0  # [0.229 rpm], [2.69 mA]
        assert 0.29 * 781 < position - 2048 < elapsed * 781 + 2  # [ticks]
        assert host.status(packet(1, WRITE, h("7000") + u32(0))) == (0, b"")  # no profile: the no-load speed
        time.sleep(1.0)
        assert bus.position(1) == 3048


def test_faults_no_reply_corrupt_crc_and_vanishing() -> None:
    with emanual_bus({1: xm430(), 2: xm430(), 3: xm430()}) as (bus, host):
        bus.faults(1).no_reply = True
        bus.faults(2).corrupt_crc = True
        bus.faults(3).vanish_after_packets = 1
        assert host.transact(packet(1, PING), timeout_s=0.05) == b""
        raw = host.transact(packet(2, PING), 14)
        assert len(raw) == 14 and parse_packets(raw) == []
        assert parse_packets(host.transact(packet(3, PING), 14))[0].packet_id == 3
        assert host.transact(packet(3, PING), timeout_s=0.05) == b""
        assert [(e.servo_id, e.description) for e in bus.fault_events] == [(3, "vanished")]
        host.send(packet(1, WRITE, h("4100 01")))
        assert len(host.transact(packet(2, PING), 14)) == 14  # packets are executed in order
        assert bus.servos[1].get(65) == 1  # the silent servo still executes


# -- shc run-hw against it ---------------------------------------------------------------------------------------

def bullet_bus(return_delay: int | None = None) -> EManualBus:
    """bullet's 30 MX-106(2.0) at power-up (Return Delay Time 250 = 500 µs unless given), strict: a read across
    the control table's undefined addresses is answered with Access Error."""
    table = {} if return_delay is None else {9: return_delay}
    return EManualBus({i: ServoConfig("MX-106", 2048, dict(table)) for i in SERVOS})


def run_hw(bus: EManualBus, out: Path, *options: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "shc_cli.cli", "run-hw", "bullet", "--port", bus.port, "--out",
                           str(out), *options], capture_output=True, text=True, timeout=120)


def read_log(run: Path) -> list[dict[str, str]]:
    with (run / "log.csv").open(encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def goal_writes(bus: EManualBus, start: int = 0) -> int:
    """SYNC WRITEs of Goal Position (116, or Profile Velocity + Goal Position from 112) from packet ``start``."""
    return sum(1 for index, p in bus.instructions(SYNC_WRITE)
               if index >= start and (p.params[0] | p.params[1] << 8) in (112, 116))


@pytest.mark.slow  # real-time runs of shc run-hw
def test_run_hw_walks_on_the_emanual_bus_with_the_default_return_delay(tmp_path: Path) -> None:
    out = tmp_path / "run"
    with bullet_bus() as bus:
        assert all(servo.return_delay_s == 500e-6 for servo in bus.servos.values())
        result = run_hw(bus, out, "--velocity", "1,0,0", "--duration", "2")
        assert result.returncode == 0, result.stderr
        assert bus.error is None and bus.protocol_violations == []
        assert {servo.key: servo.rejected for servo in bus.servos.values() if servo.rejected} == {}
        assert "return delay time 0 µs written to 30 servos" in result.stderr  # hardware.return_delay_us = 0
        assert all(servo.table[9] == 0 for servo in bus.servos.values())
        assert all(not servo.torque_on for servo in bus.servos.values())  # torque off at the end
        assert all(servo.table[70] == 0 for servo in bus.servos.values())
        for servo in bus.servos.values():  # the emulated positions followed the goals
            powered = [(goal, position) for _, goal, position, on in servo.trace if on]
            assert len(powered) > 1000
            assert max(abs(goal - position) for goal, position in powered) < 150, servo.key  # [ticks]
            assert abs(servo.get(132) - servo.get(GOAL_POSITION)) <= 1
        moved = [max(g for _, g, _, on in s.trace if on) - min(g for _, g, _, on in s.trace if on)
                 for s in bus.servos.values()]
        assert all(m > 40 for m in moved)  # every joint moved [ticks] (bullet's verified speed limits: slower)
        pings = [p for _, p in bus.instructions(PING)]
        assert pings and pings[0].packet_id == 0xFE
        final_goals = {servo.key: servo.get(GOAL_POSITION) for servo in bus.servos.values()}
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert summary["fault"] is None and summary["stopped_by_request"] is True
    assert summary["robot"] == "bullet" and summary["baud"] == 1_000_000 and summary["read_retries"] == 0
    rows = read_log(out)
    assert len(rows) == summary["cycles"] > 500 + 200  # start-up, 2 s of walking, the stop
    assert {"RUNNING"} <= {r["robot_state"] for r in rows} and "MOVING" in {r["walk_state"] for r in rows}
    last = rows[-1]
    for servo_id, joint in SERVOS.items():  # what the log says was commanded is what the servo got
        commanded, measured = float(last[f"{joint}_cmd"]), float(last[joint])
        assert abs(2048 + commanded * TICKS_PER_RAD - final_goals[servo_id]) <= 1, joint
        assert abs(commanded - measured) < 0.01, joint  # [rad]


@pytest.mark.slow  # real-time runs of shc run-hw
def test_run_hw_stops_commanding_within_two_cycles_of_an_overload(tmp_path: Path) -> None:
    out = tmp_path / "run"
    with bullet_bus(return_delay=0) as bus:
        faulty = 42  # CL_coxat; 2 packets a cycle: the fault comes near cycle 850, walking (MOVING from ~735)
        bus.faults(faulty).hardware_error_at_packet = 2 * 850
        result = run_hw(bus, out, "--velocity", "1,0,0", "--duration", "5")
        assert result.returncode == 3, result.stderr  # a fault has its own exit code (docs/commands.md)
        assert "fault:" in result.stderr and "CL_coxat" in result.stderr
        [event] = bus.fault_events
        assert event.servo_id == faulty
        assert goal_writes(bus, event.packet_index) <= 2
        assert goal_writes(bus) > 600
        assert bus.servos[faulty].table[70] == OVERLOAD_ERROR
        assert all(not servo.torque_on for servo in bus.servos.values())  # --on-fault torque-off (the default)
        assert bus.protocol_violations == []
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert "CL_coxat" in summary["fault"] and "overload" in summary["fault"]
    assert summary["stopped_by_request"] is False
    rows = read_log(out)
    assert len(rows) == summary["cycles"] and rows[-1]["walk_state"] == "MOVING"  # it happened while walking
