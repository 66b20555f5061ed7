"""Command timelines for ``shc plan``: a CSV of velocities or a TOML plan script.

Both count time from the first RUNNING cycle (after the robot's start-up), and every entry holds until
the next one changes it.

CSV (``cycle,vx,vy,wz``; inputs in the robot's velocity input mode)::

    cycle,vx,vy,wz
    0,0.5,0,0
    1000,1.0,0,0
    2000,0,0,0.5

TOML plan script (``[[step]]`` tables in time order; ``at`` [s] or ``cycle``)::

    [[step]]
    at = 0.0
    velocity = [1.0, 0.0, 0.0]        # x, y, yaw input
    [[step]]
    at = 4.0
    pose_velocity = [0, 0, 0.5, 0, 0, 0]   # manual body posing input x, y, z, roll, pitch, yaw (−1..1)
    [[step]]
    at = 6.0
    pose_velocity = [0, 0, 0, 0, 0, 0]
    pose_reset = "all"                # no_reset, z_and_yaw, x_and_y, pitch_and_roll, all, immediate_all
    [[step]]
    at = 10.0
    gait = "wave"                     # stop, switch gait, walk on (a bundled name or a gait file)
    parameters = { step_frequency = 1.5, swing_height = 0.06 }
    cruise = true                     # hold the robot's cruise velocity

    [[step]]
    at = 20.0
    velocity = [0, 0, 0]
    leg_toggle = "AR"                 # stop, lift AR for manipulation (toggle again to put it back)
    [[step]]
    at = 23.0
    tip_velocity = { AR = [0, 0, 0.5] }   # manual leg: tip velocity input (x, y, z), −1..1
    [[step]]
    at = 30.0
    state = "ready"                   # shut down (sequence mode) — the robot state to reach

``velocity``, ``pose_velocity``, ``pose_reset``, ``state``, ``tip_velocity`` and ``tip_position`` hold until
changed; ``gait``, ``parameters``, ``cruise`` and ``leg_toggle`` are requests made once, at their step.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Literal

from pydantic import Field, ValidationError, model_validator

from shc_cli.errors import Issue, NotFoundError, SpecError
from shc_cli.spec.gait import Gait
from shc_cli.spec.loading import Located, _describe, load_gait
from shc_cli.spec.robot import ADJUSTABLE, Strict
from shc_cli.spec.source import Document, origins, unwrap

Vector3 = Annotated[tuple[float, float, float], Field(strict=False)]
"""Three numbers, written as a TOML array."""

ResetName = Literal["no_reset", "z_and_yaw", "x_and_y", "pitch_and_roll", "all", "immediate_all"]
"""Manual pose reset modes: the controller's ``PoseReset`` members, in lower case."""
StateName = Literal["packed", "ready", "running"]
"""Robot states a script can request: the controller's ``RobotState`` members, in lower case."""


class Step(Strict):
    """One change of the command inputs."""

    at: float | None = Field(None, ge=0, description="time after the robot starts running [s]")
    cycle: int | None = Field(None, ge=0, description="control cycle after the robot starts running")
    velocity: tuple[float, float, float] | None = Field(None, strict=False, description="x, y, yaw input")
    pose_velocity: tuple[float, float, float, float, float, float] | None = Field(
        None, strict=False, description="manual posing input x, y, z, roll, pitch, yaw (−1..1)")
    pose_reset: ResetName | None = Field(None, description="manual pose reset mode")
    gait: str | None = Field(None, description="switch to this gait (bundled name or file); the robot stops first")
    parameters: dict[str, float] = Field(default_factory=dict,
                                         description="run-time parameter changes, e.g. { step_frequency = 1.5 }")
    cruise: bool | None = Field(None, description="cruise control on or off")
    state: StateName | None = Field(
        None, description="requested robot state (reached one state at a time; sequences run as configured)")
    leg_toggle: str | None = Field(None, description="leg id to switch between walking and manual manipulation")
    tip_velocity: dict[str, Vector3] = Field(
        default_factory=dict, description="manual legs' tip velocity inputs (x, y, z), −1..1")
    tip_position: dict[str, Vector3] = Field(
        default_factory=dict, description="manual legs' absolute tip positions in base_link [m]")

    @model_validator(mode="after")
    def _one_time(self) -> Step:
        if (self.at is None) == (self.cycle is None):
            raise ValueError("give exactly one of 'at' (seconds) or 'cycle'; e.g. at = 2.0")
        return self


class PlanScript(Strict):
    """A TOML plan script: ``[[step]]`` entries."""

    step: list[Step] = Field(description="command changes in time order")


EVENTS = ("gait", "parameters", "cruise", "leg_toggle")
"""Timeline keys that are one-off requests; every other key holds until changed."""


@dataclass
class Timeline:
    """Command changes by RUNNING-relative cycle; :func:`shc_cli.loop.input_sources.timeline_commands` gives the
    command of every cycle.

    A change maps the controller's ``Command`` fields to values: ``velocity``, ``pose_velocity`` (tuples),
    ``pose_reset`` (a :data:`ResetName`), ``state_request`` (a :data:`StateName`), ``gait`` (a :class:`Gait`),
    ``parameters``, ``cruise``, ``leg_toggle``, ``tip_velocity``, ``tip_position``. Enum-valued fields hold the
    member's name in lower case (the loop's commands hold the enums).
    """

    changes: list[tuple[int, dict[str, object]]]

    @property
    def last_cycle(self) -> int:
        return self.changes[-1][0] if self.changes else 0


def constant(velocity: tuple[float, float, float]) -> Timeline:
    """One velocity for the whole run."""
    return Timeline([(0, {"velocity": velocity})])


def load_timeline(path: Path, time_delta: float) -> Timeline:
    """Read a CSV timeline or a TOML plan script (by extension)."""
    if path.suffix == ".toml":
        return _load_script(path, time_delta)
    return _load_csv(path)


def _load_csv(path: Path) -> Timeline:
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise SpecError([Issue(path, None, "", f"cannot read commands: {error.strerror}", "check the path")]) from None
    except UnicodeDecodeError as error:
        line = path.read_bytes()[:error.start].count(b"\n") + 1
        raise SpecError([Issue(path, line, "", f"not UTF-8 text (byte {error.object[error.start]:#04x})",
                               "save the file as UTF-8 text")]) from None
    rows = list(csv.reader(text.splitlines()))
    if not rows or [c.strip() for c in rows[0]] != ["cycle", "vx", "vy", "wz"]:
        raise SpecError([Issue(path, 1, "header", "expected the header 'cycle,vx,vy,wz'",
                               "start the file with that line")])
    changes: list[tuple[int, dict[str, object]]] = []
    previous = -1
    for number, row in enumerate(rows[1:], start=2):
        if not row or not "".join(row).strip():
            continue
        if len(row) != 4:
            raise SpecError([Issue(path, number, "", f"expected 4 values, got {len(row)}", "write cycle,vx,vy,wz")])
        try:
            cycle = int(row[0])
            values = tuple(float(v) for v in row[1:])
        except ValueError:
            raise SpecError([Issue(path, number, "", f"not numbers: {','.join(row)}",
                                   "cycle is a whole number, vx, vy, wz are numbers")]) from None
        if cycle <= previous:
            raise SpecError([Issue(path, number, "cycle", f"cycle {cycle} is not after the previous row's {previous}",
                                   "sort the rows by cycle")])
        if any(v != v or v in (float("inf"), float("-inf")) for v in values):
            raise SpecError([Issue(path, number, "", "nan or inf in the velocities", "use finite numbers")])
        previous = cycle
        changes.append((cycle, {"velocity": values}))
    if not changes:
        raise SpecError([Issue(path, None, "", "no command rows", "add at least one row after the header")])
    return Timeline(changes)


def _gait(name: str, path: Path, located: Located, index: int) -> Gait:
    """A gait named in a plan script (relative paths from the script's folder)."""
    try:
        loaded = load_gait(name, relative_to=path.parent)
    except NotFoundError as error:
        raise SpecError([located.issue(("step", index, "gait"), str(error),
                                       "name a bundled gait or a gait file")]) from None
    return loaded.gait


def _load_script(path: Path, time_delta: float) -> Timeline:
    document = Document(path)
    data = document.sourced()
    located = Located(path=path, origin_map=origins(data), documents={path: document})
    try:
        script = PlanScript.model_validate(unwrap(data))
    except ValidationError as error:
        issues = []
        for item in error.errors():
            problem, fix = _describe(item, PlanScript)
            issues.append(located.issue(tuple(item["loc"]), problem, fix))
        raise SpecError(issues[:1]) from None
    changes: list[tuple[int, dict[str, object]]] = []
    for index, step in enumerate(script.step):
        cycle = step.cycle if step.cycle is not None else round((step.at or 0.0) / time_delta)
        change: dict[str, object] = {}
        if step.velocity is not None:
            change["velocity"] = step.velocity
        if step.pose_velocity is not None:
            change["pose_velocity"] = step.pose_velocity
        if step.pose_reset is not None:
            change["pose_reset"] = step.pose_reset
        if step.gait is not None:
            change["gait"] = _gait(step.gait, path, located, index)
        if step.parameters:
            unknown = [name for name in step.parameters if name not in ADJUSTABLE]
            if unknown:
                raise SpecError([located.issue(("step", index, "parameters", unknown[0]),
                                               f"'{unknown[0]}' is not a run-time parameter",
                                               f"use one of: {', '.join(ADJUSTABLE)}")])
            change["parameters"] = dict(step.parameters)
        if step.cruise is not None:
            change["cruise"] = step.cruise
        if step.state is not None:
            change["state_request"] = step.state
        if step.leg_toggle is not None:
            change["leg_toggle"] = step.leg_toggle
        if step.tip_velocity:
            change["tip_velocity"] = dict(step.tip_velocity)
        if step.tip_position:
            change["tip_position"] = dict(step.tip_position)
        changes.append((cycle, change))
    return Timeline(changes)
