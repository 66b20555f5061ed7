"""Dynamixel Protocol 2.0 packets, as the ROBOTIS e-Manual defines them.

Instruction packet: ``FF FF FD 00 | ID | LEN_L LEN_H | INST | PARAMS… | CRC_L CRC_H``; a status packet has
instruction ``0x55`` followed by an error byte. ``LEN`` counts the bytes after it (instruction, error, parameters
after stuffing, CRC). Byte stuffing: wherever ``FF FF FD`` appears from the instruction to the end of the
parameters, an ``FD`` is inserted after it; the CRC (CRC-16, polynomial 0x8005, initial value 0, no reflection)
covers the stuffed packet from the header on.
"""

from __future__ import annotations

from dataclasses import dataclass

HEADER = b"\xff\xff\xfd\x00"
BROADCAST = 0xFE
PING, READ, WRITE, REG_WRITE, ACTION, FACTORY_RESET, REBOOT, CLEAR = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x10
STATUS = 0x55
SYNC_READ, SYNC_WRITE, BULK_READ, BULK_WRITE = 0x82, 0x83, 0x92, 0x93
# Status error byte (lower 7 bits: the result; bit 7: a hardware error is set in Hardware Error Status).
ERROR_RESULT_FAIL, ERROR_INSTRUCTION, ERROR_CRC, ERROR_DATA_RANGE, ERROR_DATA_LENGTH, ERROR_DATA_LIMIT, \
    ERROR_ACCESS = 1, 2, 3, 4, 5, 6, 7
ERROR_ALERT = 0x80
ERROR_NAMES = {ERROR_RESULT_FAIL: "Result Fail", ERROR_INSTRUCTION: "Instruction Error", ERROR_CRC: "CRC Error",
               ERROR_DATA_RANGE: "Data Range Error", ERROR_DATA_LENGTH: "Data Length Error",
               ERROR_DATA_LIMIT: "Data Limit Error", ERROR_ACCESS: "Access Error"}


def error_name(error: int) -> str:
    """A status packet's error byte in words (the e-Manual's names)."""
    name = ERROR_NAMES.get(error & 0x7F, f"error {error & 0x7F}")
    return name + (" (with the hardware alert)" if error & ERROR_ALERT else "")


def _crc_table() -> list[int]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else (crc << 1)
        table.append(crc & 0xFFFF)
    return table


_TABLE = _crc_table()


def crc16(data: bytes) -> int:
    """The Protocol 2.0 CRC of ``data``."""
    crc = 0
    for byte in data:
        crc = ((crc << 8) ^ _TABLE[((crc >> 8) ^ byte) & 0xFF]) & 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    """Insert ``FD`` after every ``FF FF FD``."""
    return body.replace(b"\xff\xff\xfd", b"\xff\xff\xfd\xfd")


def unstuff(body: bytes) -> bytes:
    """Remove the stuffing ``FD`` after every ``FF FF FD``."""
    return body.replace(b"\xff\xff\xfd\xfd", b"\xff\xff\xfd")


def needs_stuffing(payload: bytes) -> bool:
    """Whether a payload contains the header pattern (dynamixel-sdk 4.1.0 sends such payloads unstuffed)."""
    return b"\xff\xff\xfd" in payload


def packet(servo: int, instruction: int, params: bytes = b"") -> bytes:
    """A complete, stuffed packet (instruction, or status when ``instruction`` is :data:`STATUS` and the error byte
    leads ``params``)."""
    body = stuff(bytes([instruction]) + params)
    length = len(body) + 2
    head = HEADER + bytes([servo, length & 0xFF, length >> 8]) + body
    crc = crc16(head)
    return head + bytes([crc & 0xFF, crc >> 8])


def status(servo: int, error: int = 0, params: bytes = b"") -> bytes:
    return packet(servo, STATUS, bytes([error]) + params)


@dataclass(frozen=True)
class Packet:
    """A parsed packet: ``instruction`` and unstuffed ``params`` (for a status packet ``params[0]`` is the error)."""

    servo: int
    instruction: int
    params: bytes


class PacketError(ValueError):
    """A packet whose CRC or length is wrong."""


def parse(buffer: bytearray) -> Packet | None:
    """Take one packet from the front of ``buffer`` (dropping noise before a header); ``None`` when incomplete.

    Raises :class:`PacketError` (after dropping the packet) if its CRC does not match.
    """
    start = buffer.find(HEADER)
    if start < 0:
        del buffer[:max(0, len(buffer) - 3)]
        return None
    del buffer[:start]
    if len(buffer) < 7:
        return None
    length = buffer[5] | (buffer[6] << 8)
    total = 7 + length
    if len(buffer) < total:
        return None
    raw = bytes(buffer[:total])
    del buffer[:total]
    if length < 3:
        raise PacketError("length below 3")
    if crc16(raw[:-2]) != (raw[-2] | (raw[-1] << 8)):
        raise PacketError("CRC mismatch")
    body = unstuff(raw[7:-2])
    return Packet(raw[4], body[0], body[1:])
