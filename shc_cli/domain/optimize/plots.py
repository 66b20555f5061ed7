"""Figures of an optimisation study (``shc optimize``): Pareto fronts, parallel coordinates, parameter importance.

matplotlib is imported here only, with the Agg backend; ``trials.csv`` rows are the input (see
:func:`shc_cli.domain.optimize.outputs.trial_rows`).
"""

from __future__ import annotations

import itertools
import math
import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shc_cli.plots import fitted_title

if TYPE_CHECKING:
    import optuna

    from shc_cli.domain.sweeps.results import Row
    from shc_cli.spec.study import Study


def _pyplot() -> Any:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _number(value: Any) -> float | None:
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def _label(study: Study, key: str) -> str:
    arrow = {"minimize": " (↓ better)", "maximize": " (↑ better)"}.get(study.objectives.get(key, ""), "")
    return f"{key}{arrow}"


def _front_2d(points: list[tuple[float, float, Any]], sense_a: str, sense_b: str) -> list[tuple[float, float, Any]]:
    """The points no other point beats in both plotted objectives (each minimised or maximised as the study says),
    in order of the first."""
    sign_a = 1.0 if sense_a == "minimize" else -1.0
    sign_b = 1.0 if sense_b == "minimize" else -1.0
    kept = [p for p in points if not any(sign_a * q[0] <= sign_a * p[0] and sign_b * q[1] <= sign_b * p[1]
                                         and (q[0], q[1]) != (p[0], p[1]) for q in points)]
    return sorted(kept, key=lambda p: p[0])


def plot_pareto_pairs(study: Study, rows: list[Row], front: list[Row], out: Path) -> list[Path]:
    """``pareto_A__B.png`` for each pair of objectives: feasible trials, infeasible ones, the front (joined in
    order of A); one objective: ``history.png``, its value per trial. Returns the files written."""
    plt = _pyplot()
    keys = list(study.objectives)
    complete = [r for r in rows if r["state"] == "complete"]
    written = []
    pairs = list(itertools.combinations(keys, 2)) or [("trial", keys[0])]
    for a, b in pairs:
        figure, axes = plt.subplots(figsize=(6.5, 5), dpi=120)
        for feasible, style in ((False, {"color": "0.75", "marker": "x", "label": "infeasible"}),
                                (True, {"color": "tab:blue", "marker": "o", "label": "feasible", "alpha": 0.5})):
            points = [(_number(r[a]), _number(r[b])) for r in complete if (r["feasible"] is True) == feasible]
            points = [(x, y) for x, y in points if x is not None and y is not None]
            if points:
                axes.scatter(*zip(*points, strict=True), s=14, lw=0.8, **style)
        values = [(_number(r[a]), _number(r[b]), r["trial"]) for r in front]
        line = sorted((x, y, n) for x, y, n in values if x is not None and y is not None)
        if line:
            xs, ys, _ = zip(*line, strict=True)
            if len(keys) == 2:  # the front of these two objectives: a line in order of A
                axes.plot(xs, ys, "o-", color="tab:red", ms=6, lw=1.0, label=f"Pareto front ({len(front)} trials)")
            else:  # a projection of a front in more objectives: no line, and its trials may be dominated here
                axes.plot(xs, ys, "o", color="tab:red", ms=6, mfc="none",
                          label=f"on the {len(keys)}-objective Pareto front ({len(front)} trials; may be "
                                "dominated in these two)")
                shown = _front_2d(line, study.objectives[a], study.objectives[b])
                axes.plot([p[0] for p in shown], [p[1] for p in shown], "-", color="tab:red", lw=0.8, alpha=0.6,
                          label=f"non-dominated in {a} and {b} ({len(shown)})")
            for x, y, n in line:
                axes.annotate(str(n), (x, y), textcoords="offset points", xytext=(4, 3), fontsize=6, color="tab:red")
        axes.set_xlabel(_label(study, a))
        axes.set_ylabel(_label(study, b))
        fitted_title(axes, f"{study.name}: {b} vs {a}, {len(complete)} complete trials")
        axes.grid(True, lw=0.3)
        axes.legend(fontsize=8)
        figure.tight_layout()
        path = out / (f"pareto_{a}__{b}.png" if a != "trial" else "history.png")
        figure.savefig(path, format="png")
        plt.close(figure)
        written.append(path)
    return written


def _axis_values(study: Study, rows: list[Row], key: str) -> tuple[list[float | None], list[str] | None]:
    """Values of one axis scaled to 0–1 and the tick labels of a categorical axis (``None`` for numeric ones)."""
    dimension = next((d for d in study.space if d.key == key), None)
    if dimension is not None and dimension.kind == "categorical":
        labels = [str(c) for c in dimension.choices]
        span = max(len(labels) - 1, 1)
        return [labels.index(str(r[key])) / span if str(r[key]) in labels else None for r in rows], labels
    values = [_number(r.get(key)) for r in rows]
    known = [v for v in values if v is not None]
    if not known:
        return values, None
    low, high = min(known), max(known)
    if dimension is not None:
        low, high = dimension.low, dimension.high
    width = high - low or 1.0
    return [None if v is None else (v - low) / width for v in values], None


def plot_parallel(study: Study, rows: list[Row], front: list[Row], path: Path) -> None:
    """Parallel coordinates: one axis per searched parameter (its search range) and per objective (its observed
    range); a line per complete feasible trial coloured by the first objective, the Pareto trials in red."""
    plt = _pyplot()
    keys = [*(d.key for d in study.space), *study.objectives]
    feasible = [r for r in rows if r["state"] == "complete" and r["feasible"] is True]
    figure, axes = plt.subplots(figsize=(max(7.0, 1.4 * len(keys)), 5), dpi=120)
    if feasible:
        columns = [_axis_values(study, feasible, k) for k in keys]
        first = next(iter(study.objectives))
        colour_values = [_number(r[first]) for r in feasible]
        known = [v for v in colour_values if v is not None] or [0.0]
        low, high = min(known), max(known)
        colours = plt.get_cmap("viridis")
        on_front = {r["trial"] for r in front}
        for i, row in enumerate(feasible):
            ys = [c[0][i] for c in columns]
            xs = [x for x, y in zip(range(len(keys)), ys, strict=True) if y is not None]
            ys = [y for y in ys if y is not None]
            if row["trial"] in on_front:
                axes.plot(xs, ys, color="tab:red", lw=1.6, alpha=0.9, zorder=3)
            else:
                shade = ((colour_values[i] or low) - low) / ((high - low) or 1.0)
                axes.plot(xs, ys, color=colours(shade), lw=0.7, alpha=0.4)
        for x, (key, (_, labels)) in enumerate(zip(keys, columns, strict=True)):
            axes.axvline(x, color="0.3", lw=0.8)
            if labels is not None:
                for k, label in enumerate(labels):
                    axes.annotate(label, (x, k / max(len(labels) - 1, 1)), fontsize=7, xytext=(3, 0),
                                  textcoords="offset points")
            else:
                dimension = next((d for d in study.space if d.key == key), None)
                raw = [_number(r.get(key)) for r in feasible]
                known_raw = [v for v in raw if v is not None] or [0.0]
                low_raw, high_raw = (dimension.low, dimension.high) if dimension else (min(known_raw), max(known_raw))
                axes.annotate(f"{low_raw:.3g}", (x, 0.0), fontsize=7, xytext=(3, -9), textcoords="offset points")
                axes.annotate(f"{high_raw:.3g}", (x, 1.0), fontsize=7, xytext=(3, 3), textcoords="offset points")
    axes.set_xticks(range(len(keys)))
    axes.set_xticklabels([_label(study, k) if k in study.objectives else k for k in keys], rotation=20, fontsize=8,
                         ha="right")
    axes.set_yticks([])
    axes.set_ylim(-0.08, 1.1)
    fitted_title(axes, f"{study.name}: {len(feasible)} feasible trials (red: Pareto front), colour = "
                 f"{next(iter(study.objectives))}")
    figure.tight_layout()
    figure.savefig(path, format="png")
    plt.close(figure)


def importances(study: Study, trials: list[optuna.trial.FrozenTrial]) -> dict[str, dict[str, float]]:
    """Per objective, each parameter's importance for reaching the best 10 % of the complete trials (Optuna's
    PED-ANOVA evaluator: deterministic, no scikit-learn, unlike fANOVA; shares sum to 1); empty when there are too
    few trials or nothing varies."""
    import optuna
    from optuna.importance import PedAnovaImportanceEvaluator, get_param_importances

    complete = [t for t in trials if t.state == optuna.trial.TrialState.COMPLETE]
    if len(complete) < 2:
        return {}
    storage = optuna.storages.InMemoryStorage()
    directions: list[Any] = list(study.objectives.values())
    copy = optuna.create_study(storage=storage, directions=directions)
    copy.add_trials(complete)
    out = {}
    for index, (key, direction) in enumerate(study.objectives.items()):
        sign = 1.0 if direction == "minimize" else -1.0  # PED-ANOVA takes lower as better
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out[key] = get_param_importances(copy, evaluator=PedAnovaImportanceEvaluator(),
                                                 target=lambda t, i=index, s=sign: s * t.values[i])  # type: ignore[misc]
        except (RuntimeError, ValueError, ImportError):
            continue
    return out


FEW_TRIALS = 20
"""Below this many complete trials importance.png says its shares are not to be trusted (the best 10 % is one or two
trials)."""


def plot_importance(study: Study, trials: list[optuna.trial.FrozenTrial], path: Path) -> None:
    """``importance.png``: a bar per parameter and objective (PED-ANOVA importance, each objective sums to 1)."""
    plt = _pyplot()
    values = importances(study, trials)
    keys = [d.key for d in study.space]
    figure, axes = plt.subplots(figsize=(7, 1.0 + 0.45 * len(keys) * max(len(values), 1)), dpi=120)
    height = 0.8 / max(len(values), 1)
    for k, (objective, shares) in enumerate(values.items()):
        axes.barh([i + k * height for i in range(len(keys))], [shares.get(key, 0.0) for key in keys], height=height,
                  label=objective)
    axes.set_yticks([i + height * (len(values) - 1) / 2 for i in range(len(keys))])
    axes.set_yticklabels(keys, fontsize=8)
    axes.invert_yaxis()
    axes.set_xlabel("importance for reaching the best 10 % of the objective (PED-ANOVA, sums to 1)")
    complete = sum(1 for t in trials if t.state.name == "COMPLETE")
    few = complete < FEW_TRIALS
    fitted_title(axes, f"{study.name}: parameter importance over {complete} complete trials"
                 + ("" if values else " (too few to tell)"))
    if values and few:
        axes.text(0.5, 0.02, f"only {complete} trials (fewer than {FEW_TRIALS}): the best 10 % is "
                  f"{max(1, complete // 10)} trial(s) — these shares are not to be trusted", transform=axes.transAxes,
                  ha="center", va="bottom", fontsize=8, color="tab:red")
    if values:
        axes.legend(fontsize=8)
    axes.grid(True, axis="x", lw=0.3)
    figure.tight_layout()
    figure.savefig(path, format="png")
    plt.close(figure)
