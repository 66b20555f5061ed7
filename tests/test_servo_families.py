"""Protocol 1.0 and Feetech packets against the vendors' documented examples, the Protocol 1.0 / Feetech emulator
driven through the vendors' SDKs (dynamixel-sdk's Protocol 1.0 handler, feetech-servo-sdk), and the servo models'
units and datasheet figures.

Packets in the example tests are copied from the ROBOTIS e-Manual, "DYNAMIXEL Protocol 1.0", Instruction Details
(PING of ID 1, READ of Present Temperature, the SYNC WRITE of four servos' goal positions and speeds, the BULK READ
of two servos).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shc_cli.hardware import protocol1 as p1
from shc_cli.hardware.emulator_protocol1 import Protocol1Emulator


def h(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


def test_packets_match_the_e_manual_examples() -> None:
    assert p1.packet(1, p1.PING) == h("FF FF 01 02 01 FB")
    assert p1.status(1) == h("FF FF 01 02 00 FC")
    assert p1.packet(1, p1.READ, bytes([0x2B, 0x01])) == h("FF FF 01 04 02 2B 01 CC")
    assert p1.status(1, 0, bytes([0x20])) == h("FF FF 01 03 00 20 DB")
    sync = h("1E 04 00 10 00 50 01 01 20 02 60 03 02 30 00 70 01 03 20 02 80 03")
    assert p1.packet(p1.BROADCAST, p1.SYNC_WRITE, sync) == h("FF FF FE 18 83") + sync + h("12")
    bulk = h("00 02 01 1E 02 02 24")
    assert p1.packet(p1.BROADCAST, p1.BULK_READ, bulk) == h("FF FF FE 09 92") + bulk + h("1D")


@given(st.integers(0, 253), st.integers(0, 0x7F), st.binary(max_size=40))
def test_packets_parse_back_after_noise(servo: int, instruction: int, params: bytes) -> None:
    data = p1.packet(servo, instruction, params)
    buffer = bytearray(b"\x00\x17" + data)
    assert p1.parse(buffer) == p1.Packet(servo, instruction, params) and not buffer


def test_a_wrong_checksum_is_refused_and_the_next_packet_still_found() -> None:
    bad = bytearray(p1.packet(3, p1.PING))
    bad[-1] ^= 1
    buffer = bytearray(bad + p1.packet(4, p1.PING))
    with pytest.raises(p1.PacketError):
        p1.parse(buffer)
    found = None
    while found is None:
        try:
            found = p1.parse(buffer)
        except p1.PacketError:
            continue
    assert found == p1.Packet(4, p1.PING, b"")


def _answered(call: Any, *args: Any) -> Any:
    """An SDK call, asked again (up to 3 times) when it timed out: the emulator is a thread of this process on a
    shared, loaded machine, and a pause past the SDK's 34 ms packet timeout is the machine's, not the protocol's."""
    for _ in range(3):
        out = call(*args)
        result = out[1] if isinstance(out, tuple) and len(out) == 3 else out[0] if isinstance(out, tuple) else out
        if result != -6:  # COMM_RX_TIMEOUT in both SDKs
            return out
    return out


def _handled(bus: Protocol1Emulator, count: int) -> None:
    """Wait until the emulator has handled its ``count``-th packet (an instruction without a status packet, e.g. a
    SYNC WRITE, is taken a moment after the host wrote it): then the test may move the servos' clock."""
    deadline = time.monotonic() + 2.0
    while len(bus.packets) < count and time.monotonic() < deadline:
        time.sleep(0.0005)
    with bus.lock:  # held while a packet is handled
        assert len(bus.packets) >= count


class _Clock:
    """The servos' clock [s]: the test moves it (``clock.now += s``) instead of waiting."""

    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


@contextmanager
def _port(bus: Protocol1Emulator, sdk: Any) -> Iterator[Any]:
    port = sdk.PortHandler(bus.port)
    assert port.openPort() and port.setBaudRate(1_000_000)
    port.ser.timeout = 0.001  # block in the read (as the bus does) instead of the SDK's polling, which holds the GIL
    try:
        yield port
    finally:
        port.closePort()


def test_dynamixel_sdk_protocol1_drives_ax_servos() -> None:
    import dynamixel_sdk as sdk

    clock = _Clock()
    with Protocol1Emulator({1: "AX-12A", 2: "AX-12A", 3: "AX-18A"}, clock=clock) as bus, _port(bus, sdk) as port:
        handler = sdk.PacketHandler(1.0)
        assert handler.ping(port, 1) == (12, sdk.COMM_SUCCESS, 0)  # AX-12A: model number 12
        assert handler.ping(port, 3)[0] == 18
        assert handler.ping(port, 9)[1] == sdk.COMM_RX_TIMEOUT
        assert handler.read2ByteTxRx(port, 2, 36) == (512, sdk.COMM_SUCCESS, 0)  # the middle of 0–1023
        assert handler.read1ByteTxRx(port, 1, 5) == (250, sdk.COMM_SUCCESS, 0)  # factory return delay 500 µs
        assert handler.write2ByteTxRx(port, 1, 30, 1024) == (sdk.COMM_SUCCESS, 8)  # Range Error: not applied
        assert bus.goal(1) == 512
        sent = len(bus.packets)  # every packet so far had a status packet: all taken
        writer = sdk.GroupSyncWrite(port, handler, 24, 1)  # torque on, one SYNC WRITE
        for servo in (1, 2, 3):
            writer.addParam(servo, [1])
        assert writer.txPacket() == sdk.COMM_SUCCESS
        writer = sdk.GroupSyncWrite(port, handler, 30, 2)
        writer.addParam(1, [0x00, 0x02])  # 512
        writer.addParam(2, [0x90, 0x01])  # 400: moves clockwise
        assert writer.txPacket() == sdk.COMM_SUCCESS
        _handled(bus, sent + 2)  # both SYNC WRITEs
        clock.now += 0.02
        speed, result, _ = handler.read2ByteTxRx(port, 2, 38)
        assert result == sdk.COMM_SUCCESS and speed & 0x400 and speed & 0x3FF > 0  # bit 10: clockwise
        clock.now += 0.3
        assert abs(handler.read2ByteTxRx(port, 2, 36)[0] - 400) <= 1
        bus.protect(3)  # overload: the error byte of every status, and Shutdown turns the torque off
        assert handler.read1ByteTxRx(port, 3, 24) == (0, sdk.COMM_SUCCESS, 32)
        assert handler.bulkReadTx(port, [2, 1, 36], 3) == sdk.COMM_SUCCESS  # AX: no BULK READ, no reply
        assert handler.readRx(port, 1, 2)[1] == sdk.COMM_RX_TIMEOUT


def test_mx_bulk_read_through_dynamixel_sdk_without_group_bulk_read() -> None:
    """GroupBulkRead of dynamixel-sdk 4.1.0 cannot send a Protocol 1.0 BULK READ (it passes bulkReadTx a fourth
    argument); the handler's own bulkReadTx and readRx can, which is what the bus does."""
    import dynamixel_sdk as sdk

    with Protocol1Emulator({1: "MX-64(1.0)", 2: "MX-106(1.0)"}) as bus, _port(bus, sdk) as port:
        handler = sdk.PacketHandler(1.0)
        group = sdk.GroupBulkRead(port, handler)
        group.addParam(1, 36, 2)
        with pytest.raises(TypeError):
            group.txPacket()
        assert handler.bulkReadTx(port, [2, 1, 30, 2, 2, 36], 6) == sdk.COMM_SUCCESS  # the e-Manual's layout
        assert handler.readRx(port, 1, 2) == ([0x00, 0x08], sdk.COMM_SUCCESS, 0)  # goal 2048
        assert handler.readRx(port, 2, 2) == ([0x00, 0x08], sdk.COMM_SUCCESS, 0)  # present 2048
        assert _answered(handler.ping, port, 2)[0] == 320


def test_feetech_sdk_drives_sts_servos() -> None:
    import scservo_sdk as sdk

    clock = _Clock()
    with Protocol1Emulator({1: "STS3215", 2: "STS3215", 3: "STS3215"}, clock=clock) as bus, _port(bus, sdk) as port:
        handler = sdk.PacketHandler(0)  # STS (0: little-endian words; 1 would be SCS)
        assert handler.ping(port, 2) == (777, sdk.COMM_SUCCESS, 0)  # model number: the word at address 3
        assert handler.read1ByteTxRx(port, 3, 5) == (3, sdk.COMM_SUCCESS, 0)  # ID at address 5
        assert handler.write1ByteTxRx(port, 1, 40, 1) == (sdk.COMM_SUCCESS, 0)  # torque on
        writer = sdk.GroupSyncWrite(port, handler, 42, 2)
        writer.addParam(1, [0x00, 0x07])  # 1792: backwards
        sent = len(bus.packets)
        assert writer.txPacket() == sdk.COMM_SUCCESS
        _handled(bus, sent + 1)
        clock.now += 0.02
        reader = sdk.GroupSyncRead(port, handler, 56, 4)
        for servo in (1, 2, 3):
            reader.addParam(servo)
        assert reader.txRxPacket() == sdk.COMM_SUCCESS
        speed = reader.getData(1, 58, 2)
        assert speed & 0x8000 and speed & 0x7FFF > 0  # bit 15: the negative direction
        assert reader.getData(2, 56, 2) == 2048 and reader.getData(3, 56, 2) == 2048
        clock.now += 0.3
        assert abs(handler.read2ByteTxRx(port, 1, 56)[0] - 1792) <= 1
        bus.protect(2)  # overload: in the status packets, and Unloading Condition turns the torque off
        assert handler.read1ByteTxRx(port, 2, 40) == (0, sdk.COMM_SUCCESS, 32)


def test_feetech_sdk_takes_a_late_reply_for_the_next_read_and_the_bus_port_does_not() -> None:
    """feetech-servo-sdk 1.0's clearPort flushes the output only: a status packet that came after its read timed
    out stays in the input and answers the next read. The bus's port clears the input first."""
    import scservo_sdk as sdk

    from shc_cli.hardware.bus_protocol1 import _FeetechPort

    for make, expected_wrong in ((sdk.PortHandler, True), (_FeetechPort, False)):
        # a bus each: the SDK's case leaves the real model reply in the pty, which would answer the next case's read
        with Protocol1Emulator({1: "STS3215"}) as bus:
            port = make(bus.port)
            assert port.openPort() and port.setBaudRate(1_000_000)
            port.ser.timeout = 0.001
            handler = sdk.PacketHandler(0)
            bus.faults(1).late_reply_s = 0.06
            assert handler.read2ByteTxRx(port, 1, 56)[1] == sdk.COMM_RX_TIMEOUT  # 34 ms timeout
            # the whole late reply arrives (60 ms; later on a loaded machine, and maybe in pieces: wait for its 8 bytes
            # — FF FF id length error 2 data checksum — or the bus's port clears a head and reads the tail later)
            arrives = time.monotonic() + 2.0
            while port.ser.in_waiting < 8 and time.monotonic() < arrives:
                time.sleep(0.005)
            assert port.ser.in_waiting == 8, f"the late reply: {port.ser.in_waiting} of its 8 bytes"
            bus.faults(1).late_reply_s = 0.0
            number, result, _ = _answered(handler.read2ByteTxRx, port, 1, 3)  # the model number
            assert result == sdk.COMM_SUCCESS and (number != 777) is expected_wrong
            port.closePort()


def test_model_units() -> None:
    from shc_cli.hardware.models import MODELS

    assert MODELS["AX-12A"].ticks_per_radian == pytest.approx(1024 / math.radians(300))
    assert MODELS["AX-12A"].centre == 512 and MODELS["STS3215"].centre == 2048
    assert MODELS["STS3215"].ticks_per_radian == pytest.approx(4096 / (2 * math.pi))
    assert MODELS["MX-64(1.0)"].family == "protocol1" and MODELS["MX-64(1.0)"].bulk_read
    assert not MODELS["AX-18A"].bulk_read and MODELS["STS3215"].family == "feetech"


@pytest.mark.parametrize(("name", "stall", "rpm", "gears", "p_gain"), [
    ("AX-12A", 1.5, 59.0, 254.0, 1062.0),  # e-Manual AX-12A; compliance slope 32 → 1/32 per 0.29° tick
    ("AX-18A", 1.8, 97.0, 254.0, 1062.0),
    ("XL430-W250", 1.5, 61.0, 258.5, 640.0),
    ("XM430-W350", 4.1, 46.0, 353.5, 800.0),
    ("MX-64", 6.0, 63.0, 200.0, 850.0),
    ("MX-106", 8.4, 45.0, 225.0, 850.0),
    ("STS3215", 1.91, 52.0, 345.0, 453.0),
])
def test_datasheets_fill_a_robot_files_servo_table(name: str, stall: float, rpm: float, gears: float,
                                                   p_gain: float) -> None:
    from shc_cli.spec.robot import Servo
    from shc_cli.spec.servo_models import DATASHEETS

    sheet = DATASHEETS[name]
    assert (sheet.stall_torque, sheet.no_load_speed_rpm, sheet.gear_ratio) == (stall, rpm, gears)
    servo = Servo.model_validate({"model": name, "idle_power": 0.5})
    assert servo.stall_torque == stall and servo.no_load_speed == pytest.approx(rpm * math.pi / 30, abs=1e-4)
    assert servo.torque_constant == pytest.approx(stall / sheet.stall_current, abs=1e-4)
    assert servo.position_p_gain == pytest.approx(p_gain, abs=1.0) and servo.idle_power == 0.5
    assert Servo.model_validate({"model": name, "stall_torque": 2.0}).stall_torque == 2.0  # the file wins
