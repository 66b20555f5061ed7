"""Protocol 2.0 packets against the e-Manual's examples, and the servo emulator driven by dynamixel-sdk."""

from __future__ import annotations

import time

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shc_cli.hardware import protocol2 as p2
from shc_cli.hardware.emulator import STUFFING_POSITION, BusEmulator


def test_packets_match_the_e_manual_examples() -> None:
    """ROBOTIS e-Manual, Protocol 2.0: ping ID 1, its status (model 1030, firmware 38), read 4 bytes at 132."""
    assert p2.packet(1, p2.PING) == bytes.fromhex("FF FF FD 00 01 03 00 01 19 4E")
    assert p2.status(1, 0, bytes([0x06, 0x04, 0x26])) == bytes.fromhex("FF FF FD 00 01 07 00 55 00 06 04 26 65 5D")
    assert p2.packet(1, p2.READ, bytes([0x84, 0x00, 0x04, 0x00])) == bytes.fromhex(
        "FF FF FD 00 01 07 00 02 84 00 04 00 1D 15")


@given(st.integers(0, 252), st.sampled_from([p2.READ, p2.WRITE, p2.SYNC_WRITE]), st.binary(max_size=40))
def test_stuffed_packets_parse_back(servo: int, instruction: int, params: bytes) -> None:
    data = p2.packet(servo, instruction, params)
    assert p2.HEADER not in data[4:] or b"\xff\xff\xfd\xfd" in data  # no unstuffed header after the first
    buffer = bytearray(b"\x00\x17" + data)  # noise before the header is skipped
    parsed = p2.parse(buffer)
    assert parsed == p2.Packet(servo, instruction, params) and not buffer


def test_a_corrupt_packet_is_refused() -> None:
    data = bytearray(p2.packet(3, p2.PING))
    data[-1] ^= 1
    with pytest.raises(p2.PacketError):
        p2.parse(bytearray(data))


def test_dynamixel_sdk_drives_the_emulated_bus() -> None:
    from dynamixel_sdk import (
        COMM_RX_CORRUPT,
        COMM_RX_TIMEOUT,
        COMM_SUCCESS,
        GroupSyncRead,
        GroupSyncWrite,
        PacketHandler,
        PortHandler,
    )

    with BusEmulator({1: "MX-106", 2: "MX-106", 3: "XM430-W350"}) as bus:
        port = PortHandler(bus.port)
        assert port.openPort() and port.setBaudRate(1_000_000)
        handler = PacketHandler(2.0)
        try:
            assert handler.ping(port, 3) == (1020, COMM_SUCCESS, 0)
            assert handler.broadcastPing(port) == ({1: [321, 45], 2: [321, 45], 3: [1020, 45]}, COMM_SUCCESS)
            assert handler.ping(port, 9)[1] == COMM_RX_TIMEOUT
            assert handler.write1ByteTxRx(port, 1, 64, 1) == (COMM_SUCCESS, 0)  # torque on
            assert handler.write4ByteTxRx(port, 1, 116, 3000) == (COMM_SUCCESS, 0)
            time.sleep(0.25)  # ≈ 8 time constants
            position, result, error = handler.read4ByteTxRx(port, 1, 132)
            assert (result, error) == (COMM_SUCCESS, 0) and abs(position - 3000) <= 2
            writer = GroupSyncWrite(port, handler, 116, 4)
            for servo in (1, 2):
                writer.addParam(servo, (1000 + servo).to_bytes(4, "little"))
            assert writer.txPacket() == COMM_SUCCESS  # no reply: wait for the emulator to take it
            deadline = time.monotonic() + 1.0
            while (bus.goal(1), bus.goal(2)) != (1001, 1002) and time.monotonic() < deadline:
                time.sleep(0.005)
            assert (bus.goal(1), bus.goal(2)) == (1001, 1002)
            reader = GroupSyncRead(port, handler, 126, 10)
            for servo in (1, 2, 3):
                reader.addParam(servo)
            assert reader.txRxPacket() == COMM_SUCCESS
            assert reader.getData(3, 132, 4) == 2048  # torque off: stays
            bus.faults(2).corrupt_crc = True
            assert handler.read4ByteTxRx(port, 2, 132)[1] == COMM_RX_CORRUPT
            bus.faults(2).corrupt_crc = False
            bus.faults(2).stuffing_position = True
            bus.servos[2].set_position(0)
            assert handler.read4ByteTxRx(port, 2, 132) == (STUFFING_POSITION, COMM_SUCCESS, 0)  # stuffed reply
            bus.faults(3).hardware_error = 32
            assert handler.read4ByteTxRx(port, 3, 70) == (32, COMM_SUCCESS, p2.ERROR_ALERT)
            bus.faults(1).vanish_after_packets = bus.servos[1].packets_seen
            assert handler.ping(port, 1)[1] == COMM_RX_TIMEOUT
        finally:
            port.closePort()


def test_the_emulated_servo_moves_on_its_injected_clock() -> None:
    """The motion model reads the clock it is given: one time constant after a goal step the servo has covered
    1 − 1/e of it, without the test waiting."""
    import math

    from shc_cli.hardware.emulator import EmulatedServo
    from shc_cli.hardware.models import MODELS

    now = [10.0]
    servo = EmulatedServo(1, MODELS["MX-106"], clock=lambda: now[0])
    servo.write(servo.model.torque_enable, bytes([1]))
    servo.write(servo.model.goal_position, (3048).to_bytes(4, "little", signed=True))
    now[0] += servo.time_constant
    position = int.from_bytes(servo.read(servo.model.present_position, 4), "little", signed=True)
    assert position == round(2048 + 1000 * (1 - math.exp(-1)))


def _stalling(base: type) -> type:
    """``base`` whose first read finds nothing and then is not scheduled for 80 ms (a loaded machine, a VM pause):
    the reply arrives meanwhile, unread."""

    class Stalling(base):  # type: ignore[misc]
        stalled = False

        def readPort(self, length: int) -> list[int]:
            if not self.stalled:
                self.stalled = True
                time.sleep(0.08)
                return []
            return list(super().readPort(length))

    return Stalling


def test_a_reply_that_arrived_while_the_process_stalled_is_read_not_a_timeout() -> None:
    """The SDK's receive loop reads, then checks its clock: a stall between the two made run-hw report "no reply"
    with the reply in the input buffer (seen on this machine). The bus's port reads it; a servo that is not there
    still times out."""
    from dynamixel_sdk import COMM_RX_TIMEOUT, COMM_SUCCESS, PacketHandler, PortHandler

    from shc_cli.hardware.bus import patient_port

    handler = PacketHandler(2.0)
    with BusEmulator({1: "XM430-W350"}) as bus:
        results = {}
        for name, base in (("sdk", PortHandler), ("patient", patient_port(PortHandler))):
            port = _stalling(base)(bus.port)
            assert port.openPort() and port.setBaudRate(1_000_000)
            model, result, _ = handler.ping(port, 1)
            results[name] = (result, model)
            port.clearPort()
            if name == "patient":
                started = time.monotonic()
                _, missing, _ = handler.ping(port, 9)
                assert missing == COMM_RX_TIMEOUT and time.monotonic() - started < 0.2
            port.closePort()
    assert results["sdk"][0] == COMM_RX_TIMEOUT  # the SDK's own port: the stall reads as no reply
    assert results["patient"] == (COMM_SUCCESS, 1020)  # XM430-W350's model number (e-Manual)
