"""Serialising many ROS messages of one layout at numpy speed.

A run's messages of one topic differ only in numbers: names, frame ids and array lengths are the same in every
cycle, so their serialised bytes have the same layout. :class:`BatchSerializer` serialises one template message
whose numeric leaves carry unique sentinel values, finds where each sentinel landed, and then writes every
cycle's numbers into copies of the template with numpy — the same bytes the library's serializer would give
(tests compare the two), about a hundred times faster than serialising message by message.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

SEC_SENTINEL = 0x3A5B7C01
NANOSEC_SENTINEL = 0x3A5B7C02


def _sentinels(width: int) -> np.ndarray:
    """Unique float64 values that are exact and unlikely to appear by chance."""
    return 987_654_321.0 + 0.125 * np.arange(width) + 1e-3 / 1024


class BatchSerializer:
    """Serialise ``N`` messages built by ``build(sec, nanosec, values)`` from rows of numbers.

    Args:
        serialize: message → bytes (e.g. ``typestore.serialize_cdr(message, msgtype)``).
        build: ``(sec, nanosec, values)`` → message; ``values`` holds the ``width`` numbers of one cycle, every one
            of them written into a float64 field of the message.
        width: numbers per message.
    """

    def __init__(self, serialize: Callable[[Any], bytes], build: Callable[[int, int, np.ndarray], Any],
                 width: int) -> None:
        sentinels = _sentinels(width)
        template = bytes(serialize(build(SEC_SENTINEL, NANOSEC_SENTINEL, sentinels)))
        self.template = np.frombuffer(template, dtype=np.uint8)
        self.offsets = [self._find(template, np.float64(value).tobytes()) for value in sentinels]
        self.sec_offsets = self._find_all(template, np.int32(SEC_SENTINEL).tobytes())
        self.nanosec_offsets = self._find_all(template, np.uint32(NANOSEC_SENTINEL).tobytes())

    @staticmethod
    def _find(data: bytes, pattern: bytes) -> int:
        at = data.find(pattern)
        if at < 0 or data.find(pattern, at + 1) >= 0:
            raise ValueError("a numeric field is missing from the template or its sentinel is not unique")
        return at

    @staticmethod
    def _find_all(data: bytes, pattern: bytes) -> list[int]:
        """Every place of a stamp field (a message may hold several headers, all with the cycle's stamp)."""
        found, at = [], data.find(pattern)
        while at >= 0:
            found.append(at)
            at = data.find(pattern, at + len(pattern))
        return found

    def serialize(self, stamps_ns: np.ndarray, values: np.ndarray) -> np.ndarray:
        """``(N, size)`` bytes of the messages for stamps ``(N,)`` [ns] and numbers ``(N, width)``."""
        count = len(stamps_ns)
        out = np.tile(self.template, (count, 1))
        stamps = np.asarray(stamps_ns, dtype=np.int64)
        seconds = (stamps // 1_000_000_000).astype("<i4").view(np.uint8).reshape(count, 4)
        nanoseconds = (stamps % 1_000_000_000).astype("<u4").view(np.uint8).reshape(count, 4)
        for offset in self.sec_offsets:
            out[:, offset:offset + 4] = seconds
        for offset in self.nanosec_offsets:
            out[:, offset:offset + 4] = nanoseconds
        numbers = np.ascontiguousarray(values, dtype="<f8")
        for column, offset in enumerate(self.offsets):
            out[:, offset:offset + 8] = numbers[:, column:column + 1].view(np.uint8).reshape(count, 8)
        return out
