"""ROS 1's TCPROS wire format: connection headers and length-prefixed messages (wiki.ros.org/ROS/TCPROS).

A connection starts with each side sending a header — a 4-byte little-endian length, then ``key=value`` fields,
each with its own 4-byte length — and goes on with messages, each a 4-byte length and the ROS 1 serialisation of
the message. Nothing here knows about topics or the master: :mod:`shc_cli.ros.node` uses it for both directions.
"""

from __future__ import annotations

import socket
import struct

from shc_cli.errors import ShcError

_LENGTH = struct.Struct("<I")
MAX_FRAME = 64 * 1024 * 1024
"""Largest header or message accepted [bytes]: a corrupt length fails fast instead of allocating gigabytes."""


class TcprosError(ShcError):
    """A peer broke the TCPROS protocol (bad header, closed connection, wrong type or md5sum)."""


def encode_header(fields: dict[str, str]) -> bytes:
    """A connection header: the length-prefixed ``key=value`` fields, the whole prefixed by its length."""
    body = b"".join(_LENGTH.pack(len(item)) + item for item in (f"{k}={v}".encode() for k, v in fields.items()))
    return _LENGTH.pack(len(body)) + body


def decode_header(body: bytes) -> dict[str, str]:
    """The fields of a header body (without its leading total length)."""
    fields: dict[str, str] = {}
    offset = 0
    while offset < len(body):
        if offset + 4 > len(body):
            raise TcprosError("TCPROS header: truncated field length")
        (size,) = _LENGTH.unpack_from(body, offset)
        offset += 4
        item = body[offset:offset + size].decode("utf-8", "replace")
        if len(item) != size or "=" not in item:
            raise TcprosError(f"TCPROS header: malformed field {item[:40]!r}")
        key, _, value = item.partition("=")
        fields[key] = value
        offset += size
    return fields


def frame(payload: bytes) -> bytes:
    """A message as sent on a connection: its length, then its bytes."""
    return _LENGTH.pack(len(payload)) + payload


def read_exactly(sock: socket.socket, size: int) -> bytes:
    """``size`` bytes from the socket; :class:`TcprosError` if the peer closes first."""
    chunks = bytearray()
    while len(chunks) < size:
        chunk = sock.recv(min(size - len(chunks), 1 << 20))
        if not chunk:
            raise TcprosError("TCPROS: connection closed by the peer")
        chunks += chunk
    return bytes(chunks)


def read_frame(sock: socket.socket) -> bytes:
    """One length-prefixed frame (a header body or a message)."""
    (size,) = _LENGTH.unpack(read_exactly(sock, 4))
    if size > MAX_FRAME:
        raise TcprosError(f"TCPROS: frame of {size} bytes is larger than {MAX_FRAME}")
    return read_exactly(sock, size)


def read_header(sock: socket.socket) -> dict[str, str]:
    """One connection header; a header with an ``error`` field raises it as :class:`TcprosError`."""
    fields = decode_header(read_frame(sock))
    if "error" in fields:
        raise TcprosError(f"TCPROS peer refused the connection: {fields['error']}")
    return fields
