"""The simulation options of sweep and study files, checked and turned into each run's
:class:`~shc_cli.domain.config.SimulationConfig` — the one place their names, types and defaults come from.

A sweep or study key without a dot is an option: ``stride_percent`` (the sweep files' own, :data:`STRIDE`) or an
option of ``shc simulate`` other than the per-run ones (:data:`PER_RUN`: the sweep sets the run directory and
turns the plots off; a display, a timeline, exit codes and replacing runs make no sense in a grid).
"""

from __future__ import annotations

import types
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin

from shc_cli.domain.config import SimulationConfig
from shc_cli.errors import Issue, SpecError
from shc_cli.spec.source import Document
from shc_cli.spec.study import Study
from shc_cli.spec.sweep import DEFAULT_DURATION, STRIDE, Point, Sweep, is_option

PER_RUN = frozenset({"commands", "out", "plots", "gui", "overwrite", "fail_on_fall", "live", "live_port", "realtime",
                     "input_mode", "watchdog"})
"""Options of ``shc simulate`` a sweep or study cannot set."""
OPTIONS = (*(key for key in SimulationConfig.model_fields if key not in PER_RUN), STRIDE)
"""The simulation options a sweep or study can set, in ``shc simulate``'s order."""
PARSED_AT_RUN = frozenset({"terrain"})
"""Options only type-checked before the runs: a terrain is read when its run starts (a missing height-field file
fails that point, not the sweep)."""
SWITCHES = {"stand": ("--stand", "--ground")}
"""``shc simulate``'s on/off flags whose names are not ``--KEY`` / ``--no-KEY``."""


def kinds(key: str) -> tuple[type, ...]:
    """The file value types option ``key`` accepts (TOML's: str, int, float, bool), from its SimulationConfig
    field (``None`` = the default is not a file value; a Literal of strings is a str)."""
    if key == STRIDE:
        return (int, float)
    return _kinds(SimulationConfig.model_fields[key].annotation)


def _kinds(annotation: Any) -> tuple[type, ...]:
    origin = get_origin(annotation)
    if origin in (Union, types.UnionType):
        return tuple(dict.fromkeys(k for arg in get_args(annotation) if arg is not type(None) for k in _kinds(arg)))
    if origin is Literal:
        return tuple(dict.fromkeys(type(arg) for arg in get_args(annotation)))
    if annotation is float:
        return (int, float)
    if annotation is Path:
        return (str,)
    return (annotation,)


def _names(key: str) -> str:
    return " or ".join(kind.__name__ for kind in kinds(key))


def check_option(path: Path, line: int | None, field: str, key: str, value: object) -> None:
    """One value of option ``key`` (at ``field``, ``line`` of the file at ``path``): a known option, a value of its
    type, one ``shc simulate`` takes — else a one-line :class:`SpecError`."""
    if key not in OPTIONS:
        close = [k for k in OPTIONS if k.startswith(key[:3])]
        hint = f" (did you mean '{close[0]}'?)" if close else ""
        raise SpecError([Issue(path, line, field, f"'{key}' is not a simulation option{hint}",
                               f"use one of {', '.join(OPTIONS)} or a dotted robot-file path such as "
                               "walker.step_frequency")])
    accepted = kinds(key)
    if not isinstance(value, accepted) or (isinstance(value, bool) and bool not in accepted):
        raise SpecError([Issue(path, line, field, f"{value!r} is not a {_names(key)}",
                               f"give {key} as a {_names(key)}")])
    if key in PARSED_AT_RUN or key == STRIDE or (key == "gait" and value == ""):
        return
    try:
        SimulationConfig(**{key: value})
    except SpecError as error:
        issue = error.issues[0]
        raise SpecError([Issue(path, line, field, issue.problem, issue.fix)]) from None


def check_sweep(sweep: Sweep) -> None:
    """Every option value of the sweep file, with its line."""
    document = Document(sweep.path)
    for key, values in sweep.grid.items():
        for value in values:
            _check(document, ("grid", key), key, value)
    for key, value in sweep.fixed.items():
        where = ("fixed", key) if document.line(("fixed", key)) is not None else (key,)
        _check(document, where, key, value)


def check_study(study: Study) -> None:
    """Every option value of the study file (top level, ``[fixed]``, ``[space]``), with its line; a numeric range
    over an option that is not a number is refused."""
    document = Document(study.path)
    for key, value in study.fixed.items():
        where = ("fixed", key) if document.line(("fixed", key)) is not None else (key,)
        _check(document, where, key, value)
    for dimension in study.space:
        where = ("space", dimension.key)
        if not is_option(dimension.key):
            continue
        if dimension.kind == "categorical":
            for value in dimension.choices:
                _check(document, where, dimension.key, value)
        elif dimension.key in OPTIONS and not set(kinds(dimension.key)) & {int, float}:
            raise SpecError([Issue(study.path, document.line(where), ".".join(where),
                                   f"'{dimension.key}' is not numeric",
                                   f"give {dimension.key} as {{ choices = [...] }}")])
        else:
            for bound, value in _bounds(document, where):
                _check(document, (*where, bound), dimension.key, value)


def _bounds(document: Document, where: tuple[str, ...]) -> Iterator[tuple[str, Any]]:
    table = document.data
    for part in where:
        table = table[part]
    yield from ((bound, table[bound]) for bound in ("low", "high"))


def _check(document: Document, where: tuple[str, ...], key: str, value: object) -> None:
    if is_option(key):
        check_option(document.path, document.line(where), ".".join(where), key, value)


def option(point: Point, key: str) -> Any:
    """The point's value of option ``key``: the file's, else ``shc simulate``'s default."""
    return point.options.get(key, SimulationConfig.model_fields[key].default)


def velocity(options: Mapping[str, Any]) -> str | None:
    """The velocity input the options give: ``stride_percent`` as a throttle, else ``velocity`` (None: unset)."""
    if options.get(STRIDE) is not None:
        return f"{float(options[STRIDE]) / 100.0:g},0,0"
    value = options.get("velocity")
    return None if value is None else str(value)


def point_config(point: Point, **changes: Any) -> SimulationConfig:
    """The run's SimulationConfig: the point's options over ``shc simulate``'s defaults, ``stride_percent`` as the
    velocity input, then ``changes`` (e.g. the robot variant, the run directory)."""
    options = {key: value for key, value in point.options.items() if key != STRIDE}
    return SimulationConfig.from_options(options, velocity=velocity(point.options), **changes)


def simulate_flags(config: SimulationConfig) -> list[str]:
    """``shc simulate`` flags that repeat the run of ``config`` with its robot: velocity, terrain, scenario and
    duration, then every other option (but the robot, gait, seed and run directory) that differs from its
    default."""
    flags = [f"--velocity {config.velocity}", f"--terrain {config.terrain}", f"--scenario {config.scenario}",
             f"--duration {config.duration if config.duration is not None else DEFAULT_DURATION:g}"]
    for key, field in SimulationConfig.model_fields.items():
        value = getattr(config, key)
        if key in {"robot", "gait", "seed", "velocity", "terrain", "scenario", "duration"} | PER_RUN \
                or value is None or value == field.default:
            continue
        if isinstance(value, bool):
            on, off = SWITCHES.get(key, (f"--{key.replace('_', '-')}", f"--no-{key.replace('_', '-')}"))
            flags.append(on if value else off)
        else:
            flags.append(f"--{key.replace('_', '-')} {value:g}" if isinstance(value, float) else
                         f"--{key.replace('_', '-')} {value}")
    return flags
