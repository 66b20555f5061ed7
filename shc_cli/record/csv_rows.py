"""Rows of a CSV table gathered in a block and written by the compiled formatter (:mod:`shc_cli.record.csv_kernels`).

:class:`RowBlock` keeps up to ``capacity`` rows of ``cycle, t, values…, names…`` in arrays; :meth:`RowBlock.drain`
formats them in one kernel call and writes the text, with Python's ``%`` for the rare row the kernel leaves to it,
so the file is byte for byte what ``row % (cycle, t, *values, *names)`` row by row would write.
"""

from __future__ import annotations

from enum import Enum
from typing import IO, Any

import numpy as np


class RowBlock:
    """A block of CSV rows waiting to be written.

    Args:
        columns: float columns per row (after ``cycle`` and ``t``; formatted ``%.6g``).
        names: name columns per row (after the floats): enum members, written as their names.
        row_format: the ``%`` format of one whole row (``%d,%.4f,%.6g,…,%s,%s\\n``), for the rows Python writes.
        capacity: rows kept before :meth:`add` writes them itself.
    """

    def __init__(self, columns: int, names: int, row_format: str, capacity: int = 256) -> None:
        from shc_cli.record import csv_kernels

        self._kernels: Any = csv_kernels
        self.row_format = row_format
        self.capacity = capacity
        self.values = np.zeros((capacity, columns))
        """The rows' float values; :meth:`next_row` gives the row to fill."""
        self.cycles = np.zeros(capacity, dtype=np.int64)
        self.times = np.zeros(capacity)
        self.states = np.zeros((capacity, names), dtype=np.int64)
        self.rows = 0
        self._codes: list[dict[Enum, int]] = [{} for _ in range(names)]
        self._texts: list[str] = []
        self._names = np.zeros(0, dtype=np.uint8)
        self._starts = np.zeros(1, dtype=np.int64)
        self._ends = np.zeros(capacity, dtype=np.int64)
        self._hard = np.zeros(capacity, dtype=np.uint8)
        self._out = np.zeros(1, dtype=np.uint8)
        self._per_row = csv_kernels.VALUE_WIDTH * columns + csv_kernels.ROW_EXTRA
        # numba loads (or compiles) the kernel at its first call: here, not in the middle of a (real-time) run
        csv_kernels.format_rows(self.cycles, self.times, self.values, self.states, self._names, self._starts, 0,
                                self._out, self._ends, self._hard)

    def code(self, column: int, value: Enum) -> int:
        """The index of name column ``column``'s ``value``, written as its name (members of different enums may
        compare equal — IntEnums — so each column has its own codes)."""
        codes = self._codes[column]
        code = codes.get(value)
        if code is None:
            code = codes[value] = len(self._texts)
            self._texts.append(value.name)
            encoded = [t.encode() for t in self._texts]
            self._names = np.frombuffer(b"".join(encoded), dtype=np.uint8).copy()
            self._starts = np.cumsum([0, *map(len, encoded)], dtype=np.int64)
        return code

    def add(self, handle: IO[str], cycle: int, time: float, codes: tuple[int, ...]) -> np.ndarray:
        """Start a row: its cycle, time and name codes; returns the row of :attr:`values` to fill (the block is
        written to ``handle`` first when full)."""
        if self.rows == self.capacity:
            self.drain(handle)
        row = self.rows
        self.rows = row + 1
        self.cycles[row] = cycle
        self.times[row] = time
        self.states[row] = codes
        values: np.ndarray = self.values[row]
        return values

    def drain(self, handle: IO[str]) -> None:
        """Write the block's rows to ``handle`` (not flushed) and empty it."""
        rows = self.rows
        if rows == 0:
            return
        self.rows = 0
        longest = max((len(t) for t in self._texts), default=0) + 1
        size = rows * (self._per_row + self.states.shape[1] * longest)
        if self._out.size < size:
            self._out = np.zeros(size, dtype=np.uint8)
        out, ends, hard = self._out, self._ends, self._hard
        written = self._kernels.format_rows(self.cycles, self.times, self.values, self.states, self._names,
                                            self._starts, rows, out, ends, hard)
        if not hard[:rows].any():
            handle.write(out[:written].tobytes().decode("utf-8"))
            return
        start = 0
        for row in range(rows):  # a row the kernel left to Python: '%' as ever
            if hard[row]:
                handle.write(self.row_format % (int(self.cycles[row]), float(self.times[row]),
                                                *self.values[row].tolist(),
                                                *(self._texts[c] for c in self.states[row].tolist())))
            else:
                handle.write(out[start:ends[row]].tobytes().decode("utf-8"))
            start = int(ends[row])
