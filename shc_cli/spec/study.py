"""Study files: a multi-objective search over simulated runs (``shc optimize``) in TOML.

```toml
name = "bullet_flat"               # optional; default: the file name
robot = "bullet"                   # the robot every trial extends
terrain = "flat"
scenario = "WG"
engine = "mujoco"                  # the default; or "pybullet"
duration = 10.0                    # seconds of walking after start-up, per run
skip = 0.0                         # seconds of walking the analysis leaves out (shc analyze --skip)
seeds = [0]                        # one run per seed; a trial's objectives are the mean over its seeds
trials = 200                       # default of --trials

[fixed]                            # further simulation options or robot-file values, the same for every trial
friction = 0.9

[space]                            # what the sampler chooses, per trial
"walker.step_frequency" = { low = 0.4, high = 2.2, step = 0.1 }
stride_percent = { low = 50, high = 100 }                   # integers: an int range
"walker.swing_height" = { low = 0.03, high = 0.15, log = true }
gait = { choices = ["tripod", "bipod", "ripple"] }

[objectives]                       # shc analyze keys and a direction
cot = "minimize"
mean_speed_mps = "maximize"

[constraints]                      # a trial that breaks one is infeasible (kept, never on the Pareto front)
fell = false                       # no seed fell
mean_speed_mps = { min = 0.05 }    # analyze keys (mean over seeds) with min and/or max
joint_limit_fraction = { max = 0.0 }

[sampler]
name = "nsga2"                     # nsga2 | nsga3 | tpe | random
seed = 1
population = 20                    # nsga2 / nsga3 generation size
```

Keys of ``[space]`` and ``[fixed]`` are the simulation options of sweeps (``shc simulate``'s options and
``stride_percent``; ``seed``, ``duration`` and ``robot`` excepted) or dotted robot-file paths, as in sweep files.
The options' types and values are checked against ``shc simulate``'s before any run
(:mod:`shc_cli.domain.sweeps.options`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.metric_names import OBJECTIVE_KEYS
from shc_cli.spec.source import Document
from shc_cli.spec.sweep import DEFAULT_DURATION, Point, check_value, is_option, slug_value

TOP_LEVEL = {"name", "description", "robot", "terrain", "scenario", "engine", "duration", "skip", "seeds", "trials",
             "fixed", "space", "objectives", "constraints", "sampler"}
SAMPLERS = ("nsga2", "nsga3", "tpe", "random")
SAMPLER_KEYS = {"name", "seed", "population"}
MAX_SAMPLER_SEED = 2**32 - 1
"""Largest sampler seed (Optuna seeds NumPy's ``RandomState``: 0 … 2³² − 1)."""
MAX_STEPS = 1e9
"""Most values a ``step`` may make of a range (Optuna counts them exactly in decimal arithmetic)."""
NOT_SEARCHED = ("seed", "duration", "robot")
"""Simulation options a study sets once (``seeds``, ``duration``, ``robot``), never per trial."""
RUN_KEYS = ("fell", "max_tilt_rad")
"""Run-summary keys a constraint or objective may name besides the analyze keys."""


@dataclass(frozen=True)
class Dimension:
    """One searched parameter.

    Attributes:
        key: a simulation option or dotted robot-file path.
        kind: ``float``, ``int`` or ``categorical``.
        low, high: bounds (numeric kinds), inclusive.
        step: grid of the values from ``low`` (``None``: continuous).
        log: sample on a log scale.
        choices: the values of a categorical.
        line: the study file's line.
    """

    key: str
    kind: str
    low: float = 0.0
    high: float = 0.0
    step: float | None = None
    log: bool = False
    choices: tuple[Any, ...] = ()
    line: int | None = None


@dataclass(frozen=True)
class Constraint:
    """``key`` (a mean over seeds) must lie in [``min``, ``max``]; ``fell = false``: no seed may fall."""

    key: str
    min: float | None = None
    max: float | None = None
    line: int | None = None


@dataclass(frozen=True)
class Study:
    """A loaded study file."""

    path: Path
    name: str
    description: str
    robot: str
    engine: str | None
    seeds: tuple[int, ...]
    skip: float
    trials: int | None
    fixed: dict[str, Any]
    space: list[Dimension]
    objectives: dict[str, str]
    constraints: list[Constraint]
    sampler: str
    sampler_seed: int | None
    population: int | None
    lines: dict[str, int | None] = field(default_factory=dict)

    def directions(self) -> list[Literal["minimize", "maximize"]]:
        """Optuna's directions of the objectives, in order."""
        return ["minimize" if d == "minimize" else "maximize" for d in self.objectives.values()]

    def points(self, number: int, params: dict[str, Any]) -> list[Point]:
        """The runs of trial ``number`` with the sampled ``params``: one per seed, named ``t0042-s0``."""
        out = []
        for k, seed in enumerate(self.seeds):
            merged = {**self.fixed, **params, "seed": seed}
            options = {key: value for key, value in merged.items() if is_option(key)}
            options["robot"] = self.robot
            overrides = {key: value for key, value in merged.items() if not is_option(key)}
            out.append(Point(number * len(self.seeds) + k, f"t{number:04d}-s{slug_value(seed)}", dict(params),
                             options, overrides))
        return out


def _issue(document: Document, where: tuple[str, ...], problem: str, fix: str) -> SpecError:
    return SpecError([Issue(document.path, document.line(where), ".".join(where), problem, fix)])


def _number(document: Document, where: tuple[str, ...], value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _issue(document, where, f"{value!r} is not a finite number", "give a plain number")
    return float(value)


def _dimension(document: Document, key: str, spec: object) -> Dimension:
    where = ("space", key)
    line = document.line(where)
    if key in NOT_SEARCHED:
        raise _issue(document, where, f"'{key}' is set once per study, not searched",
                     "give seeds, duration and robot at the top of the file")
    if not isinstance(spec, dict):
        raise _issue(document, where, "must be a table", f'e.g. {key} = {{ low = 0.5, high = 1.5 }} or '
                     f'{{ choices = [...] }}')
    unknown = set(spec) - {"low", "high", "step", "log", "choices"}
    if unknown:
        bad = sorted(unknown)[0]
        raise _issue(document, (*where, bad), f"unknown key '{bad}'", "use low, high, step, log or choices")
    if "choices" in spec:
        if set(spec) != {"choices"}:
            raise _issue(document, where, "choices cannot be combined with low/high/step/log", "keep one form")
        choices = spec["choices"]
        if not isinstance(choices, list) or not choices:
            raise _issue(document, (*where, "choices"), "must be a non-empty list", f"e.g. {key} = "
                         '{ choices = ["tripod", "bipod"] }')
        for value in choices:
            check_value(document, where, key, value)
        if len(set(map(repr, choices))) != len(choices):
            raise _issue(document, (*where, "choices"), "a choice is repeated", "list each value once")
        return Dimension(key, "categorical", choices=tuple(choices), line=line)
    if "low" not in spec or "high" not in spec:
        raise _issue(document, where, "needs low and high (or choices)", f"e.g. {key} = {{ low = 0.5, high = 1.5 }}")
    low = _number(document, (*where, "low"), spec["low"])
    high = _number(document, (*where, "high"), spec["high"])
    if not low < high:
        raise _issue(document, where, f"low ({low:g}) must be below high ({high:g})", "swap or widen them")
    for bound in ("low", "high"):
        check_value(document, (*where, bound), key, spec[bound])
    log = spec.get("log", False)
    if not isinstance(log, bool):
        raise _issue(document, (*where, "log"), f"{log!r} is not true or false", "write log = true")
    step = None
    if "step" in spec:
        step = _number(document, (*where, "step"), spec["step"])
        if step <= 0.0:
            raise _issue(document, (*where, "step"), f"step {step:g} is not positive", "give a positive step")
        if log:
            raise _issue(document, where, "log and step cannot be combined", "drop one of them")
        if step > high - low:
            raise _issue(document, (*where, "step"), f"step {step:g} exceeds the range high - low = {high - low:g}",
                         "give a smaller step")
        if (high - low) / step > MAX_STEPS:
            raise _issue(document, (*where, "step"), f"step {step:g} makes more than {MAX_STEPS:.0e} values",
                         "give a coarser step, or drop it for a continuous range")
    if log and low <= 0.0:
        raise _issue(document, (*where, "low"), f"a log range needs low > 0 (got {low:g})", "raise low")
    integer = all(isinstance(spec[k], int) for k in ("low", "high") if k in spec) and (
        step is None or isinstance(spec["step"], int))
    return Dimension(key, "int" if integer else "float", low, high, step, log, line=line)


def _constraint(document: Document, key: str, spec: object) -> Constraint:
    where = ("constraints", key)
    line = document.line(where)
    if key == "fell":
        if spec is not False:
            raise _issue(document, where, f"fell = {spec!r} is not a constraint", "write fell = false (no seed falls)")
        return Constraint("fell", max=0.0, line=line)
    if key not in OBJECTIVE_KEYS and key not in RUN_KEYS:
        raise _issue(document, where, f"'{key}' is not an analyze key",
                     f"use one of {', '.join(OBJECTIVE_KEYS)} or fell")
    if not isinstance(spec, dict) or not spec or set(spec) - {"min", "max"}:
        raise _issue(document, where, "must be a table with min and/or max", f"e.g. {key} = {{ min = 0.05 }}")
    low = _number(document, (*where, "min"), spec["min"]) if "min" in spec else None
    high = _number(document, (*where, "max"), spec["max"]) if "max" in spec else None
    if low is not None and high is not None and low > high:
        raise _issue(document, where, f"min ({low:g}) exceeds max ({high:g})", "swap them")
    return Constraint(key, low, high, line)


def load_study(path: Path) -> Study:
    """Read and check a study file; one-line :class:`SpecError` (file, line, key) on any mistake."""
    document = Document(Path(path))
    data = document.data
    for key in data:
        if key not in TOP_LEVEL:
            raise _issue(document, (key,), f"unknown key '{key}'", f"top-level keys: {', '.join(sorted(TOP_LEVEL))}")
    for table in ("fixed", "space", "objectives", "constraints", "sampler"):
        if not isinstance(data.get(table, {}), dict):
            raise _issue(document, (table,), "must be a table", f"write [{table}]")
    fixed: dict[str, Any] = {}
    for key in ("terrain", "scenario", "duration"):
        if key in data:
            check_value(document, (key,), key, data[key])
            fixed[key] = data[key]
    robot = data.get("robot", "bullet")
    if not isinstance(robot, str):
        raise _issue(document, ("robot",), f"{robot!r} is not a robot name or file", 'e.g. robot = "bullet"')
    engine = data.get("engine")  # None: shc simulate's default
    if engine is not None:
        check_value(document, ("engine",), "engine", engine)
        fixed["engine"] = engine
    seeds = data.get("seeds", [0])
    if (not isinstance(seeds, list) or not seeds
            or not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds)
            or len(set(seeds)) != len(seeds)):
        raise _issue(document, ("seeds",), f"{seeds!r} is not a list of distinct integers ≥ 0",
                     "e.g. seeds = [0, 1, 2]")
    skip = data.get("skip", 0.0)
    if isinstance(skip, bool) or not isinstance(skip, (int, float)) or not 0.0 <= skip < float(
            fixed.get("duration", DEFAULT_DURATION)):
        raise _issue(document, ("skip",), f"{skip!r} is not a number of seconds in [0, duration)",
                     "e.g. skip = 2.0")
    trials = data.get("trials")
    if trials is not None and (not isinstance(trials, int) or isinstance(trials, bool) or trials < 1):
        raise _issue(document, ("trials",), f"{trials!r} is not a positive integer", "e.g. trials = 100")
    for key, value in data.get("fixed", {}).items():
        if key in NOT_SEARCHED:
            raise _issue(document, ("fixed", key), f"'{key}' is set at the top of the file", f"move {key} there")
        if key in fixed:
            raise _issue(document, ("fixed", key), f"'{key}' is also set at the top of the file", "keep one")
        check_value(document, ("fixed", key), key, value)
        fixed[key] = value
    space = [_dimension(document, key, spec) for key, spec in data.get("space", {}).items()]
    if not space:
        raise _issue(document, ("space",), "nothing to search", 'add [space] with e.g. "walker.step_frequency" = '
                     "{ low = 0.4, high = 2.2 }")
    for dim in space:
        if dim.key in fixed:
            raise _issue(document, ("space", dim.key), f"'{dim.key}' is both in [space] and fixed", "keep one")
    keys = {dim.key for dim in space} | set(fixed)
    if "stride_percent" in keys and "velocity" in keys:
        raise _issue(document, ("space", "stride_percent") if "stride_percent" in data.get("space", {})
                     else ("fixed", "stride_percent"), "stride_percent and velocity both set the velocity input",
                     "keep one")
    objectives: dict[str, str] = {}
    for key, direction in data.get("objectives", {}).items():
        where = ("objectives", key)
        if key not in OBJECTIVE_KEYS and key not in RUN_KEYS:
            raise _issue(document, where, f"'{key}' is not an analyze key", f"use one of {', '.join(OBJECTIVE_KEYS)}")
        if direction not in ("minimize", "maximize"):
            raise _issue(document, where, f"{direction!r} is not a direction", 'write "minimize" or "maximize"')
        objectives[key] = str(direction)
    if not objectives:
        raise _issue(document, ("objectives",), "no objective", 'add [objectives] with e.g. cot = "minimize"')
    constraints = [_constraint(document, key, spec) for key, spec in data.get("constraints", {}).items()]
    sampler_data = data.get("sampler", {})
    for key in sampler_data:
        if key not in SAMPLER_KEYS:
            raise _issue(document, ("sampler", key), f"unknown key '{key}'", "use name, seed or population")
    sampler = sampler_data.get("name", "nsga2" if len(objectives) > 1 else "tpe")
    if sampler not in SAMPLERS:
        raise _issue(document, ("sampler", "name"), f"'{sampler}' is not a sampler", f"use {', '.join(SAMPLERS)}")
    sampler_seed = sampler_data.get("seed")
    if sampler_seed is not None and (not isinstance(sampler_seed, int) or isinstance(sampler_seed, bool)
                                     or not 0 <= sampler_seed <= MAX_SAMPLER_SEED):
        raise _issue(document, ("sampler", "seed"), f"{sampler_seed!r} is not an integer in [0, 2**32 - 1]",
                     "e.g. seed = 1")
    population = sampler_data.get("population")
    if population is not None and (not isinstance(population, int) or isinstance(population, bool)
                                   or population < 2):
        raise _issue(document, ("sampler", "population"), f"{population!r} is not an integer ≥ 2",
                     "e.g. population = 20")
    if population is not None and sampler not in ("nsga2", "nsga3"):
        raise _issue(document, ("sampler", "population"), f"the {sampler} sampler has no population",
                     "drop it or use nsga2 / nsga3")
    lines = {dim.key: dim.line for dim in space}
    lines.update({key: document.line(("fixed", key)) or document.line((key,)) for key in fixed})
    lines["robot"] = document.line(("robot",))
    gait_line = document.line(("space", "gait")) or document.line(("fixed", "gait"))
    lines["gait"] = gait_line or lines["robot"]
    name = str(data.get("name") or document.path.stem)
    return Study(document.path, name, str(data.get("description", "")), robot, engine, tuple(seeds),
                 float(skip), trials,
                 fixed, space, objectives, constraints, str(sampler), sampler_seed, population, lines)
