"""A trial's result from its runs' rows: objectives (means over its seeds), their spread, constraint values."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shc_cli.domain.sweeps.results import Row
from shc_cli.spec.study import Study

if TYPE_CHECKING:
    import optuna

ATTRIBUTE = "shc"
"""The user attribute holding a trial's results (one attribute: each is a storage commit)."""


@dataclass
class Outcome:
    """A finished trial as the coordinator computed it from its runs' rows.

    Attributes:
        values: the objectives, in the study's order (``None``: the trial failed).
        attrs: what is stored with the trial (:func:`stored`).
    """

    values: list[float] | None
    attrs: dict[str, Any]


def stored(trial: optuna.trial.FrozenTrial) -> dict[str, Any]:
    """What shc stored with a trial: runs, means and spreads (``mean:KEY``, ``spread:KEY``), constraints, timings."""
    attrs = trial.user_attrs.get(ATTRIBUTE)
    return dict(attrs) if isinstance(attrs, dict) else dict(trial.user_attrs)


def metric_keys(study: Study) -> tuple[str, ...]:
    """The analyze keys the runs must report: objectives and constraints (``fell`` comes with every row)."""
    keys = [*study.objectives, *(c.key for c in study.constraints if c.key != "fell"), "mean_speed_mps", "cot"]
    return tuple(dict.fromkeys(k for k in keys if k not in ("fell", "max_tilt_rad")))


def number(value: Any) -> float | None:
    """A table value as a finite float (a boolean as 0/1), else ``None``."""
    if value is None or value == "":
        return None
    if isinstance(value, bool):
        return float(value)
    try:
        result = float(value)
    except (TypeError, ValueError):
        return None
    return result if math.isfinite(result) else None


def _mean_std(values: list[float | None]) -> tuple[float | None, float | None]:
    if not values or any(v is None for v in values):
        return None, None
    numbers = [float(v) for v in values if v is not None]
    mean = sum(numbers) / len(numbers)
    spread = math.sqrt(sum((v - mean) ** 2 for v in numbers) / (len(numbers) - 1)) if len(numbers) > 1 else 0.0
    return mean, spread


def _run_value(row: Row, key: str) -> float | None:
    if key == "fell":
        return 1.0 if str(row.get("fell")) == "True" else 0.0
    return number(row.get(key))


def evaluate(study: Study, rows: list[Row], directory: Path) -> Outcome:
    """A trial's objectives (means over its seeds), their spread (sample standard deviation), its constraint
    values (≤ 0 satisfied, Optuna's convention) and what ``trials.csv`` shows; ``values`` is ``None`` for a
    failed trial (a run failed, or an objective is null, e.g. the CoT of a robot that did not move)."""
    rows = sorted(rows, key=lambda r: int(r["index"]))
    attrs: dict[str, Any] = {
        "runs": [str(directory / "runs" / r["slug"]) for r in rows],
        "fell_seeds": sum(1 for r in rows if str(r.get("fell")) == "True"),
        "sim_wall_s": sum(number(r.get("wall_time_s")) or 0.0 for r in rows),
        "error": "; ".join(str(r["error"]) for r in rows if r.get("status") != "ok"),
    }
    means: dict[str, float | None] = {}
    for key in dict.fromkeys([*study.objectives, *(c.key for c in study.constraints)]):
        mean, spread = _mean_std([_run_value(r, key) for r in rows])
        means[key] = mean
        attrs[f"mean:{key}"] = mean
        attrs[f"spread:{key}"] = spread
    constraints: dict[str, float] = {}
    for constraint in study.constraints:
        value = means.get(constraint.key)
        if constraint.min is not None:
            constraints[f"{constraint.key}:min"] = 1.0 if value is None else constraint.min - value
        if constraint.max is not None:
            constraints[f"{constraint.key}:max"] = 1.0 if value is None else value - constraint.max
    attrs["constraints"] = constraints
    attrs["feasible"] = all(c <= 0.0 for c in constraints.values())
    if attrs["error"]:
        return Outcome(None, attrs)
    values = [means[key] for key in study.objectives]
    if any(v is None for v in values):
        missing = [k for k, v in zip(study.objectives, values, strict=True) if v is None]
        attrs["error"] = f"objective {', '.join(missing)} is null (see the run's analyze)"
        return Outcome(None, attrs)
    return Outcome([float(v) for v in values if v is not None], attrs)
