"""Checking a sweep, a study, a plan script, a timeline, a path or an auto-pose set as what it is (``shc validate``).

A sweep point or a study trial that sets robot-file values (``"walker.body_clearance" = [0.2, 0.3]``) runs a robot
*variant* — a file that ``extends`` the robot with those values. :func:`check_variants` writes each distinct variant
to a temporary folder and checks it as ``shc validate`` checks a robot (schema, limits, reachability of the stance):
a body clearance no leg reaches is then found before the sweep, not in its results table. Which kind a file is:
:func:`shc_cli.spec.kinds.file_kind`.
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass
from pathlib import Path

from shc_cli.errors import Issue, ShcError, SpecError
from shc_cli.spec.kinds import DEFAULT_ROBOT, Kind, field_at
from shc_cli.spec.loading import load_robot, resolve
from shc_cli.spec.robot import Adjustable
from shc_cli.spec.sweep import Point, variant_text


@dataclass(frozen=True)
class VariantCheck:
    """What :func:`check_variants` found.

    Attributes:
        variants: distinct robot variants checked (a point without robot-file values is its robot, counted once).
        issues: one per variant that fails, naming the point (slug) and the first problem.
    """

    variants: int
    issues: list[Issue]


def check_variants(file: Path, points: list[Point], line: dict[str, int | None]) -> VariantCheck:
    """Load and check the robot of every point (each distinct robot and override set once).

    Args:
        file: the sweep or study file (where the issues point).
        points: the runs to check.
        line: the file's line of each key (the issue of a variant points at its first override's line).
    """
    from shc_cli.validation import check_robot

    seen: dict[tuple[str, str], None] = {}
    issues: list[Issue] = []
    with tempfile.TemporaryDirectory(prefix="shc-variants-") as folder:
        for point in points:
            name = str(point.options.get("robot", DEFAULT_ROBOT))
            key = (name, repr(sorted(point.overrides.items())))
            if key in seen:
                continue
            seen[key] = None
            where = line.get(next(iter(point.overrides), "robot"))
            try:
                base = resolve("robots", name)
                robot_path = base
                if point.overrides:
                    robot = load_robot(base).robot
                    assert robot is not None
                    adjustable = {p for p in point.overrides if isinstance(field_at(robot, p), Adjustable)}
                    robot_path = Path(folder) / f"{len(seen)}.toml"
                    robot_path.write_text(variant_text(base, point.overrides, adjustable), encoding="utf-8")
                found = check_robot(load_robot(robot_path))
            except SpecError as error:
                found = error.issues
            except ShcError as error:
                found = [Issue(None, None, "robot", str(error).splitlines()[0], "name a bundled robot or a file")]
            if found:
                first = found[0]
                values = ", ".join(f"{k} = {v!r}" for k, v in point.overrides.items()) or "as it is"
                issues.append(Issue(file, where, point.slug, f"robot {name} with {values}: {first.problem}",
                                    first.fix))
    return VariantCheck(len(seen), issues)


def _gaits_fit(file: Path, points: list[Point], line: dict[str, int | None]) -> list[Issue]:
    """Each distinct robot and gait of the points loads and fits (the robot's own gait where none is named)."""
    from shc_cli.validation import load_checked

    issues: list[Issue] = []
    for robot, gait in sorted({(str(p.options.get("robot", DEFAULT_ROBOT)), str(p.options.get("gait") or ""))
                               for p in points}):
        try:
            load_checked(robot, gait or None)
        except SpecError as error:
            first = error.issues[0]
            issues.append(Issue(file, line.get("gait"), "gait", f"{robot} / {gait or 'own gait'}: {first.problem}",
                                first.fix))
        except ShcError as error:
            issues.append(Issue(file, line.get("gait"), "gait", str(error).splitlines()[0],
                                "name a bundled gait or a gait file"))
    return issues


def validate_file(name: str, kind: Kind) -> tuple[str, list[Issue]]:
    """Check a sweep, study, plan script, command timeline or auto-pose set as what it is.

    Returns the line ``shc validate`` prints when it is fine, and the problems (sweeps and studies: every point's
    robot variant — a study's at each searched parameter's bounds and choices, the others at their lowest).
    """
    path = Path(name) if Path(name).is_file() else resolve("poses", name)
    if kind == "sweep":
        from shc_cli.spec.source import Document
        from shc_cli.spec.sweep import load_sweep

        sweep = load_sweep(path)
        document = Document(path)
        line = {key: document.line(("grid", key)) or document.line(("fixed", key)) for key in
                {*sweep.grid, *sweep.fixed, "robot", "gait"}}
        found = check_variants(path, sweep.points, line)
        issues = _gaits_fit(path, sweep.points, line) + found.issues
        return (f"{path}: sweep '{sweep.name}' ok ({len(sweep.points)} runs, {found.variants} robot variants "
                "checked)", issues)
    if kind == "study":
        from shc_cli.spec.study import load_study

        study = load_study(path)
        base = {d.key: (d.choices[0] if d.kind == "categorical" else d.low) for d in study.space}
        points = study.points(0, base)[:1]
        for dimension in study.space:
            values = dimension.choices if dimension.kind == "categorical" else (dimension.low, dimension.high)
            points += [study.points(0, {**base, dimension.key: value})[0] for value in values]
        found = check_variants(path, points, study.lines)
        issues = _gaits_fit(path, points, study.lines) + found.issues
        return (f"{path}: study '{study.name}' ok ({len(study.space)} parameters, {found.variants} robot variants "
                "checked at the bounds and choices)", issues)
    if kind == "path":
        from shc_cli.spec.path import load_path

        walk = load_path(path)
        headings = sum(w.yaw is not None for w in walk.waypoints)
        return (f"{path}: path ok ({len(walk.waypoints)} waypoints, {headings} with a heading, "
                f"{walk.length_m:.2f} m from the start)", [])
    if kind in ("plan script", "timeline"):
        from shc_cli.spec.timeline import load_timeline

        timeline = load_timeline(path, 0.01)
        return f"{path}: {kind} ok ({len(timeline.changes)} changes)", []
    from shc_cli.spec.autopose import load_pose_set

    loaded = load_pose_set(path)
    assert loaded.pose_set is not None
    return f"{path}: auto-pose set '{loaded.pose_set.name}' ok", []
