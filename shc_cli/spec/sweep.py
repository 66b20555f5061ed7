"""Sweep files: a grid of simulations (OpenSHC paper eq. 21, Π = C × A × G × L_s × F_s) in TOML.

```toml
name = "bullet_cot"              # optional; default: the file name
duration = 20.0                  # seconds of walking after start-up (default 20)

[grid]                           # every combination of these lists, in this order
robot = ["bullet", "bullet_mammalian"]
gait = ["tripod", "bipod"]
stride_percent = [60, 75, 90, 100]
"walker.step_frequency" = [0.4, 0.6, 0.8]

[fixed]                          # one value for every run
terrain = "flat"
```

Several ``[[grid]]`` tables instead of one ``[grid]`` run each product in turn (e.g. one gain at a time).

A key is either a simulation option (a key without a dot: an option of ``shc simulate``, or ``stride_percent``) or a
dotted robot-file path (``walker.body_clearance``, ``servo.stall_torque``); a number given for an adjustable
parameter (``{ default, min, max, step }``) sets its ``default``. ``stride_percent`` is the stride as a percentage
of the largest the walkspace allows: the forward velocity input in throttle mode (100 % = input 1).

This module reads the file's structure. The simulation options' names, types and defaults are those of
:class:`shc_cli.domain.config.SimulationConfig`, which checks a sweep's values (with the file's lines) before any
run (:mod:`shc_cli.domain.sweeps.options`): the one place they are declared.
"""

from __future__ import annotations

import itertools
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.source import Document

STRIDE = "stride_percent"
"""The sweep files' own option: the stride as a percentage of the largest (sets the velocity input)."""
DEFAULT_DURATION = 20.0
"""Seconds of walking after start-up when a sweep or study file gives no ``duration`` (``shc simulate``'s default
for a constant velocity)."""
TOP_LEVEL = {"name", "description", "duration", "grid", "fixed"}


@dataclass(frozen=True)
class Point:
    """One simulation of a sweep.

    Attributes:
        index: position in the grid (row order of the results).
        slug: directory name of its run, built from its grid values.
        values: its grid values, by key (for the results table).
        options: the simulation options the file sets for it (keys without a dot; the others keep
            ``shc simulate``'s defaults), unchecked: :mod:`shc_cli.domain.sweeps.options` checks them and makes the
            run's :class:`~shc_cli.domain.config.SimulationConfig`.
        overrides: robot-file values by dotted path.
    """

    index: int
    slug: str
    values: dict[str, Any]
    options: dict[str, Any]
    overrides: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Sweep:
    """A loaded sweep file."""

    path: Path
    name: str
    description: str
    grid: dict[str, list[Any]]
    fixed: dict[str, Any]
    points: list[Point]


def is_option(key: str) -> bool:
    """A simulation option (``stride_percent`` or an option of ``shc simulate``), not a dotted robot-file path."""
    return "." not in key


def slug_value(value: object) -> str:
    """A value as part of a run's directory name."""
    text = f"{value:g}" if isinstance(value, float) else str(value)
    return re.sub(r"[^A-Za-z0-9._+-]", "_", Path(text).stem if text.endswith(".toml") else text)


def check_value(document: Document, where: tuple[str, ...], key: str, value: object) -> None:
    """A plain value (one finite number, string or boolean); ``duration`` and ``stride_percent`` numbers in their
    ranges. The simulation options' own types and values are checked against ``shc simulate``'s before any run
    (:mod:`shc_cli.domain.sweeps.options`)."""
    if not isinstance(value, (int, float, str, bool)) or (isinstance(value, float) and not math.isfinite(value)):
        raise SpecError([Issue(document.path, document.line(where), ".".join(where),
                               f"{value!r} is not a single finite number, string or boolean",
                               "give plain values")])
    if key in ("duration", STRIDE) and (isinstance(value, bool) or not isinstance(value, (int, float))):
        raise SpecError([Issue(document.path, document.line(where), ".".join(where),
                               f"{value!r} is not a int or float", f"give {key} as a int or float")])
    if key == STRIDE and not 0.0 < float(value) <= 100.0:
        raise SpecError([Issue(document.path, document.line(where), ".".join(where),
                               f"stride {value}% is outside (0, 100]", "give a percentage of the maximum stride")])


def load_sweep(path: Path) -> Sweep:
    """Read and check a sweep file; one-line :class:`SpecError` (file, line, key) on any mistake."""
    document = Document(Path(path))
    data = document.data
    for key in data:
        if key not in TOP_LEVEL:
            raise SpecError([Issue(document.path, document.line((key,)), key, f"unknown key '{key}'",
                                   f"top-level keys: {', '.join(sorted(TOP_LEVEL))}")])
    grid_data = data.get("grid", {})
    fixed = dict(data.get("fixed", {}))
    grids = grid_data if isinstance(grid_data, list) else [grid_data]
    if not all(isinstance(g, dict) for g in grids) or not isinstance(fixed, dict):
        bad = "fixed" if not isinstance(fixed, dict) else "grid"
        raise SpecError([Issue(document.path, document.line((bad,)), bad, "must be a table",
                               f"write [{bad}]" + (" or [[grid]] tables" if bad == "grid" else ""))])
    if "duration" in data:
        check_value(document, ("duration",), "duration", data["duration"])
        fixed.setdefault("duration", data["duration"])
    for key, value in fixed.items():
        check_value(document, ("fixed", key), key, value)
    grid: dict[str, list[Any]] = {}  # every key of every grid, with its values in order of first appearance
    points: list[Point] = []
    for one in grids:
        for key, values in one.items():
            where = ("grid", key)
            if not isinstance(values, list) or not values:
                raise SpecError([Issue(document.path, document.line(where), ".".join(where),
                                       "must be a non-empty list of values", f'e.g. {key} = [...]')])
            for value in values:
                check_value(document, where, key, value)
            if key in fixed:
                raise SpecError([Issue(document.path, document.line(where), ".".join(where),
                                       f"'{key}' is both in [grid] and in [fixed]", "keep one")])
            grid.setdefault(key, [])
            grid[key] += [v for v in values if v not in grid[key]]
        if "stride_percent" in {**one, **fixed} and ("velocity" in one or "velocity" in fixed):
            table = "grid" if "stride_percent" in one else "fixed"
            raise SpecError([Issue(document.path, document.line((table, "stride_percent")),
                                   f"{table}.stride_percent", "stride_percent and velocity both set the velocity "
                                   "input", "keep one")])
        keys = list(one)
        for combination in itertools.product(*one.values()):
            values = dict(zip(keys, combination, strict=True))
            merged = {**fixed, **values}
            options = {key: value for key, value in merged.items() if is_option(key)}
            overrides = {key: value for key, value in merged.items() if not is_option(key)}
            slug = "-".join(f"{slug_value(v)}" if k in ("robot", "gait") else f"{k}={slug_value(v)}"
                            for k, v in values.items()) or "run"
            points.append(Point(len(points), slug, values, options, overrides))
    slugs = [p.slug for p in points]
    if len(set(slugs)) != len(slugs):
        raise SpecError([Issue(document.path, document.line(("grid",)), "grid",
                               "two grid points have the same name", "make the grid values distinct")])
    name = str(data.get("name") or document.path.stem)
    return Sweep(document.path, name, str(data.get("description", "")), grid, fixed, points)


def variant_text(base: Path, overrides: dict[str, Any], adjustable: set[str], parent: str | None = None) -> str:
    """A robot file that ``extends`` ``base`` (or the robot named ``parent``) with ``overrides`` (dotted paths);
    paths in ``adjustable`` are ``{ default, min, max, step }`` tables, whose ``default`` a plain number sets."""
    from shc_cli.spec.toml_out import dump_toml

    tree: dict[str, Any] = {}
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node = tree
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = {"default": value} if dotted in adjustable and not isinstance(value, dict) else value
    return f'extends = "{parent or base.resolve().as_posix()}"\n\n' + dump_toml(tree)
