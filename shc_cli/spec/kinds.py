"""Which kind of shc file a file is (the checks of each kind: :mod:`shc_cli.domain.file_checks`).

``shc validate`` takes any shc file: a robot, a gait, an auto-pose set, a sweep, a study, a plan script or a path
(TOML), or a command timeline or a path (CSV, told apart by the header). The kind follows from the top-level keys
only each kind has (:func:`file_kind`), so that a sweep is checked as a sweep instead of as a robot file with an
unknown key ``grid``.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Literal

from shc_cli.spec.loading import bundled
from shc_cli.spec.robot import Robot

DEFAULT_ROBOT = "bullet"
"""The robot of a point whose file names none (``shc simulate``'s default)."""

Kind = Literal["robot", "gait", "pose set", "sweep", "study", "plan script", "timeline", "path"]

MARKERS: tuple[tuple[Kind, tuple[str, ...]], ...] = (
    ("gait", ("stance_phase", "swing_phase", "offset_multiplier")),
    ("sweep", ("grid",)),
    ("study", ("space", "objectives")),
    ("plan script", ("step",)),
    ("path", ("waypoint",)),
    ("pose set", ("poser", "pose_phase_length", "negation")),
)
"""Top-level keys only one kind of file has, in the order they are tried."""


def file_kind(name: str) -> Kind:
    """The kind of the file at ``name`` (by its extension and top-level keys) or of a bundled name (robot, else
    gait, else pose set); ``robot`` when nothing else fits (the robot loader then reports what is wrong)."""
    path = Path(name)
    if path.is_file():
        if path.suffix.lower() == ".csv":
            from shc_cli.spec.path import is_path_csv

            return "path" if is_path_csv(path) else "timeline"
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except (tomllib.TOMLDecodeError, UnicodeDecodeError, OSError):
            return "robot"  # the robot loader reports the syntax error with its line
        for kind, keys in MARKERS:
            if any(key in data for key in keys):
                return kind
        return "robot"
    if name in bundled("robots"):
        return "robot"
    if name in bundled("gaits"):
        return "gait"
    if name in bundled("poses"):
        return "pose set"
    return "robot"


def field_at(robot: Robot, dotted: str) -> object:
    """The robot's value at a dotted robot-file path (tables and leg/joint maps alike), or ``None``."""
    node: object = robot
    for part in dotted.split("."):
        node = node.get(part) if isinstance(node, dict) else getattr(node, part, None)
        if node is None:
            return None
    return node
