"""Dynamixel Protocol 1.0 packets (ROBOTIS e-Manual), which Feetech STS/SCS servos share.

Instruction packet: ``FF FF | ID | LENGTH | INSTRUCTION | PARAMS… | CHECKSUM``; a status packet has the error byte
where the instruction is. ``LENGTH`` = number of parameters + 2; ``CHECKSUM = ~(ID + LENGTH + INSTRUCTION + PARAMS…)
& 0xFF`` (only the lowest byte of the sum). No byte stuffing. Broadcast ID ``FE`` (no status packet answers it).

Instructions (e-Manual Protocol 1.0): PING 01, READ 02 (address, length), WRITE 03 (address, data…), REG WRITE 04,
ACTION 05, FACTORY RESET 06, REBOOT 08, SYNC WRITE 83 (address, length, then ID + data per servo), BULK READ 92
(00, then length, ID, address per servo; MX series). Feetech adds SYNC READ 82 (address, length, IDs…).
"""

from __future__ import annotations

from dataclasses import dataclass

HEADER = b"\xff\xff"
BROADCAST = 0xFE
PING, READ, WRITE, REG_WRITE, ACTION, FACTORY_RESET, REBOOT = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08
SYNC_READ, SYNC_WRITE, BULK_READ = 0x82, 0x83, 0x92
# Protocol 1.0 status error bits (e-Manual).
ERROR_VOLTAGE, ERROR_ANGLE, ERROR_OVERHEATING, ERROR_RANGE, ERROR_CHECKSUM, ERROR_OVERLOAD, ERROR_INSTRUCTION = (
    1, 2, 4, 8, 16, 32, 64)


def checksum(body: bytes) -> int:
    """``~(sum of ID, LENGTH, INSTRUCTION/ERROR and the parameters) & 0xFF``."""
    return ~sum(body) & 0xFF


def packet(servo: int, instruction: int, params: bytes = b"") -> bytes:
    """A complete instruction packet (a status packet when ``instruction`` is the error byte)."""
    body = bytes([servo, len(params) + 2, instruction]) + bytes(params)
    return HEADER + body + bytes([checksum(body)])


def status(servo: int, error: int = 0, params: bytes = b"") -> bytes:
    return packet(servo, error, params)


@dataclass(frozen=True)
class Packet:
    """A parsed packet: ``instruction`` is the error byte for a status packet."""

    servo: int
    instruction: int
    params: bytes


class PacketError(ValueError):
    """A packet whose checksum or length is wrong."""


def parse(buffer: bytearray) -> Packet | None:
    """Take one packet from the front of ``buffer`` (dropping noise before a header); ``None`` when incomplete.

    Raises :class:`PacketError` (after dropping the bad packet's first byte, so a wrong length cannot swallow the
    next packet) if its checksum does not match or its length is below 2."""
    start = buffer.find(HEADER)
    while start >= 0 and len(buffer) > start + 2 and buffer[start + 2] == 0xFF:  # FF FF FF: the header is later
        start += 1
    if start < 0:
        del buffer[:max(0, len(buffer) - 1)]
        return None
    del buffer[:start]
    if len(buffer) < 4:
        return None
    length = buffer[3]
    if length < 2:
        del buffer[:1]
        raise PacketError(f"length {length} below 2")
    total = 4 + length
    if len(buffer) < total:
        return None
    raw = bytes(buffer[:total])
    if checksum(raw[2:-1]) != raw[-1]:
        del buffer[:1]
        raise PacketError(f"checksum {raw[-1]:#04x} received, {checksum(raw[2:-1]):#04x} computed")
    del buffer[:total]
    return Packet(raw[2], raw[4], raw[5:-1])
