"""What a study writes besides its storage: ``trials.csv``, ``pareto.csv``, ``pareto/tNNNN.toml`` and the plots."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.domain.optimize.evaluate import number, stored
from shc_cli.domain.sweeps.results import Row, write_table
from shc_cli.spec.study import Study

if TYPE_CHECKING:
    import optuna


def trial_rows(study: Study, trials: list[optuna.trial.FrozenTrial]) -> tuple[list[str], list[Row]]:
    """``trials.csv``: columns and one row per trial in number order."""
    objectives = list(study.objectives)
    constraint_keys = [c.key for c in study.constraints if c.key not in study.objectives]
    columns = ["trial", "state", "feasible", *(d.key for d in study.space), *objectives,
               *(f"{k}_spread" for k in objectives), *constraint_keys, "fell_seeds", "seeds", "runs",
               "duplicate_of", "trial_wall_s", "sim_wall_s", "error"]
    rows = []
    for trial in sorted(trials, key=lambda t: t.number):
        attrs = stored(trial)
        row: Row = {"trial": trial.number, "state": trial.state.name.lower(),
                    "feasible": attrs.get("feasible", ""), **trial.params}
        for key in [*objectives, *constraint_keys]:
            row[key] = attrs.get(f"mean:{key}")
        for key in objectives:
            row[f"{key}_spread"] = attrs.get(f"spread:{key}")
        row.update(fell_seeds=attrs.get("fell_seeds"), seeds=len(study.seeds), runs=attrs.get("runs"),
                   duplicate_of=attrs.get("duplicate_of"),
                   trial_wall_s=attrs.get("trial_wall_s"), sim_wall_s=attrs.get("sim_wall_s"),
                   error=attrs.get("error", ""))
        rows.append(row)
    return columns, rows


def pareto_front(study: Study, rows: list[Row]) -> list[Row]:
    """The complete, feasible trials no other such trial dominates (at least as good in every objective, better in
    one), in trial order."""
    signs = [1.0 if d == "minimize" else -1.0 for d in study.objectives.values()]
    candidates = [r for r in rows if r["state"] == "complete" and r["feasible"] is True
                  and all(number(r[k]) is not None for k in study.objectives)]
    costs = [[s * float(r[k]) for s, k in zip(signs, study.objectives, strict=True)] for r in candidates]
    front = []
    for i, row in enumerate(candidates):
        dominated = any(all(a <= b for a, b in zip(other, costs[i], strict=True)) and other != costs[i]
                        for j, other in enumerate(costs) if j != i)
        if not dominated:
            front.append(row)
    return front


def pareto_robot(study: Study, row: Row) -> str:
    """A robot file that ``extends`` the study's robot with a trial's robot-file values (and its gait as
    ``walker.gait``); the simulation options it was found with are in the header's ``shc simulate`` line."""
    from shc_cli.domain.sweeps.checks import is_adjustable
    from shc_cli.domain.sweeps.options import point_config, simulate_flags
    from shc_cli.spec.loading import data_dir, load_robot, resolve
    from shc_cli.spec.sweep import variant_text

    params = {d.key: row[d.key] for d in study.space}
    point = study.points(int(row["trial"]), params)[0]
    config = point_config(point)
    overrides = dict(point.overrides)
    if config.gait:
        overrides["walker.gait"] = config.gait
    base = resolve("robots", study.robot)
    robot = load_robot(base).robot
    adjustable = {path for path in overrides if is_adjustable(robot, path)}
    bundled = base.resolve().parent == data_dir("robots").resolve()
    flags = simulate_flags(config)
    objectives = ", ".join(f"{k} {float(row[k]):.4g}" for k in study.objectives)
    header = (f"# shc optimize {study.name}: Pareto trial {row['trial']} ({objectives}; mean over seeds "
              f"{', '.join(map(str, study.seeds))}).\n"
              f"# Found with: shc simulate THIS_FILE {' '.join(flags)}\n")
    return header + variant_text(base, overrides, adjustable, study.robot if bundled else None)


def write_outputs(study: Study, out: Path, trials: list[optuna.trial.FrozenTrial],
                  figures: bool) -> tuple[list[Row], list[Row]]:
    """trials.csv and (``figures``) pareto.csv, pareto/*.toml and the plots; returns the trial rows and the Pareto
    rows (none without ``figures``)."""
    from shc_cli.outputs import write_text

    columns, rows = trial_rows(study, trials)
    write_table(out / "trials.csv", columns, rows)
    if not figures:
        return rows, []
    front = pareto_front(study, rows)
    write_table(out / "pareto.csv", columns, front)
    folder = out / "pareto"
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir()
    for row in front:
        write_text(folder / f"t{int(row['trial']):04d}.toml", pareto_robot(study, row))
    from shc_cli.domain.optimize.plots import plot_importance, plot_parallel, plot_pareto_pairs

    plot_pareto_pairs(study, rows, front, out)
    plot_parallel(study, rows, front, out / "parallel.png")
    plot_importance(study, trials, out / "importance.png")
    return rows, front


