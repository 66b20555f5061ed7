"""Path files (``--path FILE``): waypoints the robot walks to in turn, with optional headings.

Coordinates are in the **odometry frame**: the robot's start pose is the origin, x ahead, y to its left, yaw
anticlockwise from x; metres and radians. The robot walks from its start (0, 0) to the first waypoint, then to each
next one, turns to a waypoint's heading when it has one, and stops at the last.

CSV (a header ``x,y`` or ``x,y,yaw``; an empty yaw cell: no heading at that waypoint; ``#`` starts a comment)::

    x,y,yaw
    2.0,0.0,1.5708
    2.0,2.0,3.1416
    0.0,2.0,-1.5708
    0.0,0.0,0.0

TOML (``[[waypoint]]`` tables in order; ``yaw`` optional; an optional top-level ``tolerance`` [m] overrides the
follower's default)::

    tolerance = 0.05
    [[waypoint]]
    x = 2.0
    y = 0.0
    yaw = 1.5708
"""

from __future__ import annotations

import csv
import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from pydantic import Field, ValidationError

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.robot import Strict

MAX_DISTANCE_M = 1000.0
"""Largest coordinate a path may hold [m] (a larger one is a unit slip: millimetres for metres)."""
PATH_HEADERS = (["x", "y"], ["x", "y", "yaw"])
"""The header lines a CSV path file may have."""


@dataclass(frozen=True)
class Waypoint:
    """One place to walk to, in the odometry frame.

    Attributes:
        x: ahead of the start pose [m].
        y: left of the start pose [m].
        yaw: heading to turn to there [rad], anticlockwise from the start heading; ``None``: any heading.
    """

    x: float
    y: float
    yaw: float | None = None


@dataclass(frozen=True)
class Path2D:
    """The waypoints of a path file, in order.

    Attributes:
        waypoints: at least one.
        source: the file they were read from (``None``: made in code).
        tolerance_m: the file's own reach tolerance [m] (``None``: the follower's default).
        turn_while_walking: the headings are headings of arrival, turned to along each segment (the file's
            ``turn = "while-walking"``); else turned to on the spot at the waypoint.
    """

    waypoints: tuple[Waypoint, ...]
    source: Path | None = None
    tolerance_m: float | None = None
    turn_while_walking: bool = False

    @property
    def length_m(self) -> float:
        """Length of the polyline from the start (0, 0) through every waypoint [m]."""
        points = [(0.0, 0.0), *((w.x, w.y) for w in self.waypoints)]
        return sum(math.dist(a, b) for a, b in itertools.pairwise(points))


class _TomlWaypoint(Strict):
    x: float = Field(description="ahead of the start pose [m]")
    y: float = Field(description="left of the start pose [m]")
    yaw: float | None = Field(None, description="heading to turn to at the waypoint [rad] (absent: any heading)")


class PathFile(Strict):
    """A TOML path file: ``[[waypoint]]`` tables in order."""

    tolerance: float | None = Field(None, gt=0, le=1.0, description="distance within which a waypoint counts as "
                                                                    "reached [m] (default: the follower's, 0.05)")
    turn: Literal["at-waypoints", "while-walking"] = Field(
        "at-waypoints", description="where the headings are turned to: on the spot at each waypoint, or along each "
        "segment (the heading of arrival, as an RViz goal sequence)")
    waypoint: list[_TomlWaypoint] = Field(description="the waypoints, in the order they are walked to")


def is_path_csv(path: Path) -> bool:
    """Whether a CSV file is a path rather than a command timeline: its header's first column is ``x`` (a path's
    header is ``x,y`` or ``x,y,yaw``; a timeline's starts with ``cycle``)."""
    try:
        with path.open(encoding="utf-8") as handle:
            for line in handle:
                text = line.strip()
                if text and not text.startswith("#"):
                    return text.split(",")[0].strip() == "x"
    except (OSError, UnicodeDecodeError):
        return False
    return False


def load_path(path: Path) -> Path2D:
    """Read a path file (``.toml`` by extension, else CSV); one-line :class:`SpecError` on bad input."""
    path = Path(path)
    if not path.is_file():
        raise SpecError([Issue(path, None, "--path", "no such file", "give a path file (CSV x,y[,yaw] or TOML "
                               "[[waypoint]] tables), e.g. paths/square_2m.csv")])
    if path.suffix.lower() == ".toml":
        return _load_toml(path)
    return _load_csv(path)


def _text(path: Path) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except OSError as error:
        raise SpecError([Issue(path, None, "", f"cannot read the path: {error.strerror}", "check the path")]) from None
    except UnicodeDecodeError as error:
        line = path.read_bytes()[:error.start].count(b"\n") + 1
        raise SpecError([Issue(path, line, "", f"not UTF-8 text (byte {error.object[error.start]:#04x})",
                               "save the file as UTF-8 text")]) from None


def _check(path: Path, line: int | None, field: str, value: float, name: str) -> None:
    if not math.isfinite(value):
        raise SpecError([Issue(path, line, field, f"{name} is {value}", "use a finite number")])
    if name == "yaw" and abs(value) > math.tau:
        raise SpecError([Issue(path, line, field, f"yaw {value:g} is outside −2π…2π",
                               f"write radians, not degrees: {value:g}° is {math.radians(value):.4f}")])
    if name != "yaw" and abs(value) > MAX_DISTANCE_M:
        raise SpecError([Issue(path, line, field, f"{name} {value:g} is beyond {MAX_DISTANCE_M:g} m",
                               "write metres, not millimetres")])


def _load_csv(path: Path) -> Path2D:
    lines = [(number, line) for number, line in enumerate(_text(path).splitlines(), start=1)
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise SpecError([Issue(path, None, "", "empty path file", "write the header x,y,yaw and one waypoint a line")])
    header_line, header = lines[0]
    columns = [c.strip() for c in header.split(",")]
    if columns not in PATH_HEADERS:
        raise SpecError([Issue(path, header_line, "header", f"expected the header 'x,y' or 'x,y,yaw', got '{header}'",
                               "start the file with the line x,y,yaw (metres, radians)")])
    waypoints: list[Waypoint] = []
    for number, row in ((n, next(csv.reader([text]))) for n, text in lines[1:]):
        if len(row) != len(columns):
            raise SpecError([Issue(path, number, "", f"expected {len(columns)} values, got {len(row)}",
                                   f"write {','.join(columns)} (an empty yaw: any heading)")])
        values: list[float | None] = []
        for name, cell in zip(columns, row, strict=True):
            cell = cell.strip()
            if name == "yaw" and not cell:
                values.append(None)
                continue
            try:
                value = float(cell)
            except ValueError:
                raise SpecError([Issue(path, number, name, f"'{cell}' is not a number",
                                       "write metres for x and y, radians for yaw, e.g. 1.5708")]) from None
            _check(path, number, name, value, name)
            values.append(value)
        x, y = values[0], values[1]
        assert x is not None and y is not None
        waypoints.append(Waypoint(x, y, values[2] if len(values) == 3 else None))
    if not waypoints:
        raise SpecError([Issue(path, header_line + 1, "", "no waypoints after the header",
                               "add at least one line x,y[,yaw]")])
    return Path2D(tuple(waypoints), path)


def _load_toml(path: Path) -> Path2D:
    from shc_cli.spec.loading import Located, _describe
    from shc_cli.spec.source import Document, origins, unwrap

    document = Document(path)
    data = document.sourced()
    located = Located(path=path, origin_map=origins(data), documents={path: document})
    try:
        loaded = PathFile.model_validate(unwrap(data))
    except ValidationError as error:
        item = error.errors()[0]
        problem, fix = _describe(item, PathFile)
        raise SpecError([located.issue(tuple(item["loc"]), problem, fix)]) from None
    if not loaded.waypoint:
        raise SpecError([Issue(path, None, "waypoint", "no waypoints", "add [[waypoint]] tables with x = …, y = …")])
    for index, entry in enumerate(loaded.waypoint):
        for name in ("x", "y", "yaw"):
            value = getattr(entry, name)
            if value is not None:
                _, line = located.where(("waypoint", index, name))
                _check(path, line, f"waypoint[{index}].{name}", value, name)
    return Path2D(tuple(Waypoint(w.x, w.y, w.yaw) for w in loaded.waypoint), path, loaded.tolerance,
                  loaded.turn == "while-walking")
