"""Whole MCAP chunks at once for rosbags' MCAP storage: the records of many cycles built with numpy.

rosbags writes an MCAP message record per call (≈ 40 µs each, 150,000 of them for an 80 s run). Here every
cycle's messages have a fixed size per topic, so a chunk of cycles is one numpy array of identical rows — opcode,
record length, channel id, sequence 0, log and publish time, then the serialised message — and its message
indexes are arrays too. The chunk, message-index and chunk-index records are exactly those of
``rosbags.rosbag2.storage_mcap.McapWriter.close_chunk`` (MCAP spec: chunk 0x06, message index 0x07), written into
the same storage object so rosbags still writes the summary, statistics and ``metadata.yaml``.
"""

from __future__ import annotations

from io import BytesIO
from typing import Any

import numpy as np

MESSAGE_HEADER = 1 + 8 + 2 + 4 + 8 + 8
"""opcode, record length, channel id, sequence, log time, publish time [bytes]."""
CHUNK_BYTES = 2**20
"""Uncompressed chunk size rosbags uses."""


def supports(writer: Any) -> bool:
    """Whether ``writer`` (a rosbags rosbag2 Writer) stores MCAP through the storage this module knows."""
    storage = getattr(writer, "storage", None)
    return all(hasattr(storage, name) for name in ("bio", "chunks", "compressor", "compression", "channel_stats",
                                                   "message_start_time", "message_end_time")) and \
        hasattr(writer, "counts")


def _u64(value: int) -> bytes:
    return int(value).to_bytes(8, "little")


def _string(text: str) -> bytes:
    data = text.encode()
    return len(data).to_bytes(4, "little") + data


def write_streams(writer: Any, streams: list[tuple[Any, np.ndarray]], stamps: np.ndarray) -> None:
    """Write ``streams`` — (connection, messages ``(N, size)`` uint8) — at ``stamps`` ``(N,)`` [ns], cycle by cycle
    in time order, as whole chunks."""
    storage = writer.storage
    count = len(stamps)
    sizes = [data.shape[1] for _, data in streams]
    starts = np.cumsum([0] + [MESSAGE_HEADER + size for size in sizes])
    row = int(starts[-1])
    template = np.zeros(row, dtype=np.uint8)
    for (connection, _), size, at in zip(streams, sizes, starts[:-1].tolist(), strict=True):
        template[at] = 0x05
        template[at + 1:at + 9] = np.frombuffer(_u64(MESSAGE_HEADER - 9 + size), dtype=np.uint8)
        template[at + 9:at + 11] = np.frombuffer(int(connection.id).to_bytes(2, "little"), dtype=np.uint8)
    per_chunk = max(1, CHUNK_BYTES // row)
    stamps = np.asarray(stamps, dtype=np.int64)
    for first in range(0, count, per_chunk):
        last = min(count, first + per_chunk)
        rows = last - first
        block = np.tile(template, (rows, 1))
        times = stamps[first:last].astype("<u8").view(np.uint8).reshape(rows, 8)
        for (_, data), size, at in zip(streams, sizes, starts[:-1].tolist(), strict=True):
            block[:, at + 15:at + 23] = times
            block[:, at + 23:at + 31] = times
            block[:, at + MESSAGE_HEADER:at + MESSAGE_HEADER + size] = data[first:last]
        _write_chunk(storage, block.tobytes(), streams, starts[:-1], row, stamps[first:last])
        writer_counts = writer.counts
        for connection, _ in streams:
            storage.channel_stats[connection.id] += rows
            writer_counts[connection.id] += rows
    if count:
        storage.message_start_time = min(storage.message_start_time, int(stamps.min()))
        storage.message_end_time = max(storage.message_end_time, int(stamps.max()))


def _write_chunk(storage: Any, content: bytes, streams: list[tuple[Any, np.ndarray]], starts: np.ndarray,
                 row: int, stamps: np.ndarray) -> None:
    """One chunk record, its message indexes and its chunk index (``McapWriter.close_chunk``)."""
    start_time, end_time = int(stamps.min()), int(stamps.max())
    compressed = storage.compressor(content)
    record = _u64(start_time) + _u64(end_time) + _u64(len(content)) + (0).to_bytes(4, "little") \
        + _string(storage.compression) + _u64(len(compressed)) + bytes(compressed)
    bio = storage.bio
    chunk_start = bio.tell()
    bio.write(b"\x06" + _u64(len(record)) + record)
    chunk_end = bio.tell()
    offsets: list[tuple[int, int]] = []
    rows = len(stamps)
    for (connection, _), at in zip(streams, starts.tolist(), strict=True):
        offsets.append((int(connection.id), bio.tell()))
        entries = np.empty((rows, 2), dtype="<u8")
        entries[:, 0] = stamps
        entries[:, 1] = at + row * np.arange(rows, dtype=np.uint64)
        index = int(connection.id).to_bytes(2, "little") + (rows * 16).to_bytes(4, "little") + entries.tobytes()
        bio.write(b"\x07" + _u64(len(index)) + index)
    chunk_index = BytesIO()
    chunk_index.write(_u64(start_time) + _u64(end_time) + _u64(chunk_start) + _u64(chunk_end - chunk_start))
    chunk_index.write((len(offsets) * 10).to_bytes(4, "little"))
    for channel, offset in offsets:
        chunk_index.write(channel.to_bytes(2, "little") + _u64(offset))
    chunk_index.write(_u64(bio.tell() - chunk_end) + _string(storage.compression) + _u64(len(compressed))
                      + _u64(len(content)))
    storage.chunks.append(chunk_index)
