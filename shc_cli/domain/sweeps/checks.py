"""Checks before any run of a sweep or a study: robot-file paths that exist, robots and gaits that load, an
executor that exists — one line with the file's line (exit 2) instead of a table of failed runs."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.domain.sweeps.options import check_sweep, option
from shc_cli.errors import Issue, ShcError, SpecError, check_choice
from shc_cli.spec.sweep import Point, Sweep

if TYPE_CHECKING:
    from shc_cli.spec.robot import Robot

EXECUTORS = ("local", "dask")
"""Where runs execute: this machine's worker processes, or a Dask cluster."""


def field(robot: Robot | None, dotted: str) -> object:
    """The robot's value at a dotted robot-file path (tables and leg/joint maps alike), or ``None``."""
    node: object = robot
    for part in dotted.split("."):
        node = node.get(part) if isinstance(node, dict) else getattr(node, part, None)
        if node is None:
            return None
    return node


def is_adjustable(robot: Robot | None, dotted: str) -> bool:
    """Whether the robot-file path ``dotted`` is an adjustable parameter (``{ default, min, max, step }``)."""
    from shc_cli.spec.robot import Adjustable

    return isinstance(field(robot, dotted), Adjustable)


def check_points(sweep: Sweep) -> None:
    """Fail early, with the sweep file's line, on simulation options ``shc simulate`` does not take, robot-file
    paths that do not exist and robots/gaits that do not load — before any simulation starts."""
    check_sweep(sweep)
    check_runs(sweep.path, sweep.points, key_lines(sweep))


def check_runs(path: Path, points: list[Point], document_lines: dict[str, int | None]) -> None:
    """Fail early with the line of the file at ``path`` (``document_lines``: line of each key) on robot-file paths
    the robot lacks and robots/gaits that do not load; used by sweeps and studies."""
    from shc_cli.spec.loading import load_robot, resolve
    from shc_cli.validation import load_checked

    robots = {str(option(p, "robot")) for p in points}
    for name in sorted(robots):
        try:
            robot = load_robot(resolve("robots", name)).robot
        except ShcError as error:
            raise SpecError([Issue(path, document_lines.get("robot"), "robot", str(error).splitlines()[0],
                                   "name a bundled robot or a robot file")]) from None
        for dotted in {k for p in points for k in p.overrides}:
            if field(robot, dotted) is None:
                raise SpecError([Issue(path, document_lines.get(dotted), dotted,
                                       f"robot '{name}' has no field '{dotted}'",
                                       "use a dotted path of `shc validate --show ROBOT`")])
    seen: set[tuple[str, str]] = set()
    for point in points:
        key = (str(option(point, "robot")), str(option(point, "gait") or ""))
        if key in seen:
            continue
        seen.add(key)
        try:
            load_checked(key[0], key[1] or None)
        except SpecError as error:
            issue = error.issues[0]
            raise SpecError([Issue(path, document_lines.get("gait"), "gait",
                                   f"{key[0]} / {key[1] or 'own gait'}: {issue.problem}", issue.fix)]) from None
        except ShcError as error:  # a gait that does not exist
            raise SpecError([Issue(path, document_lines.get("gait"), "gait", str(error).splitlines()[0],
                                   "name a bundled gait or a gait file")]) from None


def key_lines(sweep: Sweep) -> dict[str, int | None]:
    """The sweep file's line of each grid and fixed key."""
    from shc_cli.spec.source import Document

    document = Document(sweep.path)
    out: dict[str, int | None] = {}
    for key in [*sweep.grid, *sweep.fixed]:
        out[key] = document.line(("grid", key)) or document.line(("fixed", key))
    return out


def check_executor(executor: str, scheduler: str | None) -> None:
    """One line for an unknown executor or a scheduler without Dask."""
    check_choice("--executor", executor, EXECUTORS, "an executor")
    if scheduler is not None and executor != "dask":
        raise SpecError([Issue(None, None, "--scheduler", "only the dask executor has a scheduler",
                               "add --executor dask")])
