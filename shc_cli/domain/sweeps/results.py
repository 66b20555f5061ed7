"""Result tables of sweeps and studies (``results.csv``, ``trials.csv``, ``pareto.csv``): one CSV writer.

A row is a dict of column → value; a cell is the value as text (floats with 6 significant digits, ``None`` and NaN
empty, lists joined by ``;``).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from types import TracebackType
from typing import IO, Any

Row = dict[str, Any]
"""One row of a result table: column → value (grid values, status, summary keys, metrics)."""

METRICS = ("cot", "cot_displacement", "mean_power_w", "mean_speed_mps", "displacement_speed_mps", "path_speed_mps",
           "steady_speed_mps",
           "commanded_speed_mps", "speed_ratio", "distance_m", "duty_factor", "foot_slip_m",
           "stability_margin_median_m", "zmp_margin_median_m", "height_median_m", "height_iqr_m",
           "roll_rate_median_rps", "pitch_rate_median_rps", "step_frequency_hz")
"""Analysis keys copied into the results table."""
RUN_KEYS = ("engine", "fell", "sim_time_s", "wall_time_s", "physics_time_s")
"""Summary keys copied into the results table (the timings differ from run to run; compare the others)."""
WARNINGS = "engine_warnings"
"""Results column with the run's engine warnings (``summary.json`` ``engine_warnings``, joined by "; ")."""


def sweep_columns(grid: list[str]) -> list[str]:
    """The columns of a sweep's ``results.csv`` for its grid keys."""
    return ["index", "slug", *grid, "status", "error", *RUN_KEYS, WARNINGS, *METRICS]


def cell(value: object) -> str:
    """A value as a table cell."""
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    if isinstance(value, list):
        return ";".join(cell(v) for v in value)
    return str(value)


def write_table(path: Path, columns: list[str], rows: list[Row]) -> None:
    """A table with ``columns``, its rows in the given order, written atomically."""
    from shc_cli.outputs import write_text

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([cell(row.get(c)) for c in columns])
    write_text(path, buffer.getvalue())


class PartialTable:
    """A table written a row at a time, each flushed (``results.partial.csv``: kept if the sweep is interrupted).
    Use as a context manager."""

    def __init__(self, path: Path, columns: list[str]) -> None:
        self.path, self.columns = path, columns
        self._handle: IO[str] | None = None

    def __enter__(self) -> PartialTable:
        self._handle = self.path.open("w", encoding="utf-8", newline="")
        self._writer = csv.writer(self._handle, lineterminator="\n")
        self._writer.writerow(self.columns)
        return self

    def append(self, row: Row) -> None:
        """Write ``row`` and flush it to the file."""
        assert self._handle is not None, "PartialTable is used as a context manager"
        self._writer.writerow([cell(row.get(c)) for c in self.columns])
        self._handle.flush()

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None,
                 trace: TracebackType | None) -> None:
        if self._handle is not None:
            self._handle.close()
