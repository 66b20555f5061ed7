"""``shc optimize``: a multi-objective search (Optuna) over simulated runs, resumable from its SQLite storage.

Layout of the output directory::

    OUT/study.toml            the study file, as run (a resumed study must be the same)
    OUT/study.db              Optuna's storage (SQLite): every trial, its parameters, objectives and state
    OUT/variants/tNNNN-sS.toml robot files of the runs (extends + the trial's values)
    OUT/runs/tNNNN-sS/        one simulate run directory per trial and seed
    OUT/trials.csv            one row per trial (rewritten after each trial, so an interruption keeps them)
    OUT/pareto.csv            the feasible non-dominated trials
    OUT/pareto/tNNNN.toml     a robot file per Pareto trial that extends the study's robot with its values
    OUT/pareto_A__B.png       each pair of objectives, the front highlighted
    OUT/importance.png        parameter importance per objective
    OUT/parallel.png          parallel coordinates of the feasible trials

One process, the coordinator, talks to the storage (ask, tell); the runs execute in worker processes or on Dask
through the sweep machinery (:class:`shc_cli.commands.sweep.RunPool`, :func:`~shc_cli.commands.sweep.run_point`).
Trials go in batches of ``--workers``: the batch's runs (trials × seeds) share the workers and the trials are told
in number order when the batch ends, so the same sampler seed gives the same trials whatever the timing.
"""

from __future__ import annotations

import csv
import io
import math
import os
import shutil
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from shc_cli.errors import Issue, OutputError, ShcError, SpecError
from shc_cli.spec.study import Dimension, Study, load_study

if TYPE_CHECKING:
    import optuna

STORAGE = "study.db"
ATTRIBUTE = "shc"
"""The user attribute holding a trial's results (one attribute: each is a storage commit)."""
SUMMARY_KEYS = ("wall_time_s",)


@dataclass
class Outcome:
    """A finished trial as the coordinator computed it from its runs' rows."""

    values: list[float] | None
    attrs: dict[str, Any]


def results(trial: optuna.trial.FrozenTrial) -> dict[str, Any]:
    """What shc stored with a trial: runs, means and spreads (``mean:KEY``, ``spread:KEY``), constraints, timings."""
    stored = trial.user_attrs.get(ATTRIBUTE)
    return dict(stored) if isinstance(stored, dict) else dict(trial.user_attrs)


def metric_keys(study: Study) -> tuple[str, ...]:
    """The analyze keys the runs must report: objectives and constraints (``fell`` comes with every row)."""
    keys = [*study.objectives, *(c.key for c in study.constraints if c.key != "fell"), "mean_speed_mps", "cot"]
    return tuple(dict.fromkeys(k for k in keys if k not in ("fell", "max_tilt_rad")))


def _float(value: Any) -> float | None:
    if value is None or value == "":
        return None
    if isinstance(value, bool):
        return float(value)
    try:
        number = float(value)
    except (TypeError, ValueError):
        return None
    return number if math.isfinite(number) else None


def _mean_std(values: list[float | None]) -> tuple[float | None, float | None]:
    if not values or any(v is None for v in values):
        return None, None
    numbers = [float(v) for v in values if v is not None]
    mean = sum(numbers) / len(numbers)
    spread = math.sqrt(sum((v - mean) ** 2 for v in numbers) / (len(numbers) - 1)) if len(numbers) > 1 else 0.0
    return mean, spread


def _run_value(row: dict[str, Any], key: str) -> float | None:
    if key == "fell":
        return 1.0 if str(row.get("fell")) == "True" else 0.0
    return _float(row.get(key))


def evaluate(study: Study, rows: list[dict[str, Any]], directory: Path) -> Outcome:
    """A trial's objectives (means over its seeds), their spread (sample standard deviation), its constraint
    values (≤ 0 satisfied, Optuna's convention) and what ``trials.csv`` shows; ``values`` is ``None`` for a
    failed trial (a run failed, or an objective is null, e.g. the CoT of a robot that did not move)."""
    rows = sorted(rows, key=lambda r: int(r["index"]))
    attrs: dict[str, Any] = {
        "runs": [str(directory / "runs" / r["slug"]) for r in rows],
        "fell_seeds": sum(1 for r in rows if str(r.get("fell")) == "True"),
        "sim_wall_s": sum(_float(r.get("wall_time_s")) or 0.0 for r in rows),
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


def suggest(trial: optuna.trial.Trial, dimension: Dimension) -> Any:
    """The trial's value of one searched parameter."""
    if dimension.kind == "categorical":
        return trial.suggest_categorical(dimension.key, list(dimension.choices))
    if dimension.kind == "int":
        return trial.suggest_int(dimension.key, int(dimension.low), int(dimension.high),
                                 step=int(dimension.step or 1), log=dimension.log)
    return trial.suggest_float(dimension.key, dimension.low, dimension.high, step=dimension.step, log=dimension.log)


def make_sampler(study: Study) -> optuna.samplers.BaseSampler:
    """The study's sampler, seeded. Constraints reach it through ``Trial.set_constraint`` (infeasible trials rank
    behind feasible ones in NSGA-II/III and TPE)."""
    import optuna

    if study.sampler == "nsga2":
        return optuna.samplers.NSGAIISampler(population_size=study.population or 20, seed=study.sampler_seed)
    if study.sampler == "nsga3":
        return optuna.samplers.NSGAIIISampler(population_size=study.population or 20, seed=study.sampler_seed)
    if study.sampler == "tpe":
        return optuna.samplers.TPESampler(seed=study.sampler_seed)
    return optuna.samplers.RandomSampler(seed=study.sampler_seed)


def check_study(study: Study) -> None:
    """Before any run: the robot loads, every robot-file path exists (and lies inside an adjustable parameter's
    [min, max]), every gait choice fits — one line with the study file's line, exit 2."""
    from shc_cli.commands.sweep import _field, check_runs
    from shc_cli.spec.loading import load_robot, resolve
    from shc_cli.spec.robot import Adjustable

    base = {d.key: (d.choices[0] if d.kind == "categorical" else d.low) for d in study.space}
    points = study.points(0, base)[:1]
    for dimension in study.space:
        if dimension.kind == "categorical" and dimension.key in ("gait", "robot"):
            points += [study.points(0, {**base, dimension.key: c})[0] for c in dimension.choices[1:]]
    check_runs(study.path, points, study.lines)
    robot = load_robot(resolve("robots", study.robot)).robot
    for dimension in study.space:
        value = _field(robot, dimension.key)
        if isinstance(value, Adjustable) and dimension.kind != "categorical" and not (
                value.min <= dimension.low and dimension.high <= value.max):
            raise SpecError([Issue(study.path, dimension.line, f"space.{dimension.key}",
                                   f"[{dimension.low:g}, {dimension.high:g}] leaves the robot's range "
                                   f"[{value.min:g}, {value.max:g}]", "search inside it")])


def _format(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, float):
        return "" if math.isnan(value) else f"{value:.6g}"
    if isinstance(value, list):
        return ";".join(_format(v) for v in value)
    return str(value)


def trial_rows(study: Study, trials: list[optuna.trial.FrozenTrial]) -> tuple[list[str], list[dict[str, Any]]]:
    """``trials.csv``: columns and one row per trial in number order."""
    objectives = list(study.objectives)
    constraint_keys = [c.key for c in study.constraints if c.key not in study.objectives]
    columns = ["trial", "state", "feasible", *(d.key for d in study.space), *objectives,
               *(f"{k}_spread" for k in objectives), *constraint_keys, "fell_seeds", "seeds", "runs",
               "duplicate_of", "trial_wall_s", "sim_wall_s", "error"]
    rows = []
    for trial in sorted(trials, key=lambda t: t.number):
        attrs = results(trial)
        row: dict[str, Any] = {"trial": trial.number, "state": trial.state.name.lower(),
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


def pareto_front(study: Study, rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The complete, feasible trials no other such trial dominates (at least as good in every objective, better in
    one), in trial order."""
    signs = [1.0 if d == "minimize" else -1.0 for d in study.objectives.values()]
    candidates = [r for r in rows if r["state"] == "complete" and r["feasible"] is True
                  and all(_float(r[k]) is not None for k in study.objectives)]
    costs = [[s * float(r[k]) for s, k in zip(signs, study.objectives, strict=True)] for r in candidates]
    front = []
    for i, row in enumerate(candidates):
        dominated = any(all(a <= b for a, b in zip(other, costs[i], strict=True)) and other != costs[i]
                        for j, other in enumerate(costs) if j != i)
        if not dominated:
            front.append(row)
    return front


def write_csv(path: Path, columns: list[str], rows: list[dict[str, Any]]) -> None:
    """A table, atomically."""
    from shc_cli.outputs import write_text

    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_format(row.get(c)) for c in columns])
    write_text(path, buffer.getvalue())


def pareto_robot(study: Study, row: dict[str, Any]) -> str:
    """A robot file that ``extends`` the study's robot with a trial's robot-file values (and its gait as
    ``walker.gait``); the simulation options it was found with are in the header's ``shc simulate`` line."""
    from shc_cli.commands.sweep import _is_adjustable
    from shc_cli.spec.loading import data_dir, load_robot, resolve
    from shc_cli.spec.sweep import OPTIONS, variant_text

    params = {d.key: row[d.key] for d in study.space}
    point = study.points(int(row["trial"]), params)[0]
    overrides = dict(point.overrides)
    if point.options["gait"]:
        overrides["walker.gait"] = point.options["gait"]
    base = resolve("robots", study.robot)
    robot = load_robot(base).robot
    adjustable = {path for path in overrides if _is_adjustable(robot, path)}
    bundled = base.resolve().parent == data_dir("robots").resolve()
    options = point.options
    velocity = options["velocity"] if options["stride_percent"] is None else \
        f"{float(options['stride_percent']) / 100.0:g},0,0"
    flags = [f"--velocity {velocity}", f"--terrain {options['terrain']}", f"--scenario {options['scenario']}",
             f"--duration {float(options['duration']):g}"]
    flags += [f"--{key.replace('_', '-')} {options[key]:g}" for key in ("physics_rate", "friction", "restitution",
                                                                          "imu_noise")
              if options[key] != OPTIONS[key][1]]
    objectives = ", ".join(f"{k} {float(row[k]):.4g}" for k in study.objectives)
    header = (f"# shc optimize {study.name}: Pareto trial {row['trial']} ({objectives}; mean over seeds "
              f"{', '.join(map(str, study.seeds))}).\n"
              f"# Found with: shc simulate THIS_FILE {' '.join(flags)}\n")
    return header + variant_text(base, overrides, adjustable, study.robot if bundled else None)


def write_outputs(study: Study, out: Path, trials: list[optuna.trial.FrozenTrial],
                  figures: bool) -> list[dict[str, Any]]:
    """trials.csv, pareto.csv, pareto/*.toml and (``figures``) the plots; returns the Pareto rows."""
    from shc_cli.outputs import write_text

    columns, rows = trial_rows(study, trials)
    write_csv(out / "trials.csv", columns, rows)
    if not figures:
        return []
    front = pareto_front(study, rows)
    write_csv(out / "pareto.csv", columns, front)
    folder = out / "pareto"
    if folder.exists():
        shutil.rmtree(folder)
    folder.mkdir()
    for row in front:
        write_text(folder / f"t{int(row['trial']):04d}.toml", pareto_robot(study, row))
    from shc_cli.study_plots import plot_importance, plot_parallel, plot_pareto_pairs

    plot_pareto_pairs(study, rows, front, out)
    plot_parallel(study, rows, front, out / "parallel.png")
    plot_importance(study, trials, out / "importance.png")
    return front


def _key(params: dict[str, Any]) -> str:
    return repr(sorted(params.items()))


def _tell_copy(study: optuna.study.Study, trial: optuna.trial.Trial, same: optuna.trial.FrozenTrial) -> None:
    """Tell ``trial`` the result of the finished trial ``same`` that had the same values: same inputs and seeds give
    the same runs (``shc simulate``'s guarantee), so they are not simulated again."""
    from optuna.trial import TrialState

    trial.set_user_attr(ATTRIBUTE, {**results(same), "trial_wall_s": 0.0, "sim_wall_s": 0.0,
                                    "duplicate_of": same.number})
    for key, value in results(same).get("constraints", {}).items():
        trial.set_constraint(key, value)
    if same.state == TrialState.COMPLETE and same.values is not None:
        study.tell(trial, list(same.values))
    else:
        study.tell(trial, state=TrialState.FAIL)


def _open_study(spec: Study, out: Path, resume: bool) -> optuna.study.Study:
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    path = (out / STORAGE).resolve()

    def connect() -> Any:
        """SQLite in write-ahead-log mode with normal sync: a commit per suggested value costs ~1 ms instead of an
        fsync; a power cut may lose the last trials' commits but never corrupts the file (SQLite's guarantee)."""
        import sqlite3

        connection = sqlite3.connect(path, timeout=60.0, check_same_thread=False)
        connection.execute("PRAGMA journal_mode=WAL")
        connection.execute("PRAGMA synchronous=NORMAL")
        return connection

    storage = optuna.storages.RDBStorage(f"sqlite:///{path.as_posix()}", engine_kwargs={"creator": connect})
    directions = spec.directions()
    try:
        study = optuna.create_study(study_name=spec.name, storage=storage, directions=directions,
                                    sampler=make_sampler(spec), load_if_exists=resume)
    except optuna.exceptions.DuplicatedStudyError:
        raise OutputError(f"{out / STORAGE}: already holds study '{spec.name}' (add --resume)") from None
    if list(d.name.lower() for d in study.directions) != directions:
        raise SpecError([Issue(spec.path, None, "objectives", f"the stored study in {out / STORAGE} has other "
                               "objectives", "resume with the same study file, or choose another --out")])
    return study


def run_optimize(file: Path, trials: int | None, workers: int | None, executor: str, scheduler: str | None,
                 out: Path | None, resume: bool, overwrite: bool = False) -> Path:
    """Check the study, run trials until ``trials`` have finished (counting earlier ones on ``--resume``), write
    the tables, robot files and plots; returns the output directory (``overwrite``: delete an existing output
    directory of shc's first)."""
    from shc_cli.commands.sweep import RunPool, check_executor

    try:
        import optuna
    except ImportError:
        raise SpecError([Issue(None, None, "optimize", "optuna is not installed",
                               "pip install 'shc[optimize]' (optuna, optuna-dashboard)")]) from None
    spec = load_study(file)
    check_executor(executor, scheduler)
    check_study(spec)
    total = trials or spec.trials or 20
    if total < 1:
        raise SpecError([Issue(None, None, "--trials", f"{total} is not a positive number of trials", "e.g. 50")])
    out = out or Path("runs") / spec.name
    copy = out / "study.toml"
    if resume and overwrite:
        raise SpecError([Issue(None, None, "--overwrite", "cannot be combined with --resume", "choose one")])
    if resume:
        if not (out / STORAGE).exists():
            raise OutputError(f"{out}: no {STORAGE} to resume (run without --resume first)")
        if copy.exists() and copy.read_bytes() != spec.path.read_bytes():
            raise OutputError(f"{out}: was started with a different study file ({copy}); resume it with that "
                              "file or choose another --out")
    else:
        from shc_cli.loop.runlog import clear_output

        clear_output(out, overwrite,
                     "add --resume to continue it, --overwrite to start it again, or choose another --out")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    if spec.path.resolve() != copy.resolve():
        shutil.copyfile(spec.path, copy)
    count = workers or os.cpu_count() or 1
    study = _open_study(spec, out, resume)
    from optuna.trial import TrialState

    keys = metric_keys(spec)
    started = time.perf_counter()
    ran = 0
    coordinator = 0.0  # [s] asking, telling, storage and trials.csv: the overhead of the search itself
    try:
        with RunPool(executor, count, scheduler) as pool:
            while True:
                iteration = time.perf_counter()
                stored = study.get_trials(deepcopy=False)
                finished = sum(1 for t in stored if t.state.is_finished())
                pending = sorted((t for t in stored if t.state == TrialState.RUNNING), key=lambda t: t.number)
                if finished >= total and not pending:
                    break
                batch = [optuna.trial.Trial(study, t._trial_id) for t in pending[:count]]  # interrupted: re-run
                # a stored value is returned as it was; one the interruption came before is sampled now
                params = {t.number: {d.key: suggest(t, d) for d in spec.space} for t in batch}
                for _ in range(min(count - len(batch), total - finished - len(pending))):
                    trial = study.ask()
                    params[trial.number] = {d.key: suggest(trial, d) for d in spec.space}
                    batch.append(trial)
                earlier = {_key(t.params): t for t in stored if t.state.is_finished() and "runs" in results(t)}
                for trial in [t for t in batch if _key(params[t.number]) in earlier]:
                    _tell_copy(study, trial, earlier[_key(params[trial.number])])
                    batch.remove(trial)
                    ran += 1
                if not batch:
                    coordinator += time.perf_counter() - iteration
                    continue
                begun = time.perf_counter()
                coordinator += begun - iteration
                points = [p for t in batch for p in spec.points(t.number, params[t.number])]
                rows: dict[int, list[dict[str, Any]]] = {t.number: [] for t in batch}
                for row in pool.results(points, out, keys, spec.skip):
                    rows[int(row["index"]) // len(spec.seeds)].append(row)
                ended = time.perf_counter()
                elapsed = (ended - begun) / len(batch)
                for trial in batch:  # in number order: the same seed gives the same sampling
                    outcome = evaluate(spec, rows[trial.number], out)
                    trial.set_user_attr(ATTRIBUTE, {**outcome.attrs, "trial_wall_s": elapsed})
                    for key, value in outcome.attrs["constraints"].items():
                        trial.set_constraint(key, value)
                    if outcome.values is None:
                        study.tell(trial, state=TrialState.FAIL)
                    else:
                        study.tell(trial, outcome.values)
                    ran += 1
                write_outputs(spec, out, study.get_trials(deepcopy=False), figures=False)
                coordinator += time.perf_counter() - ended
    except KeyboardInterrupt:
        write_outputs(spec, out, study.get_trials(deepcopy=False), figures=False)
        done = sum(1 for t in study.get_trials(deepcopy=False) if t.state.is_finished())
        raise ShcError(f"interrupted: {done} trials finished, kept in {out / STORAGE} and {out / 'trials.csv'}; "
                       "continue with --resume") from None
    front = write_outputs(spec, out, study.get_trials(deepcopy=False), figures=True)
    stored = study.get_trials(deepcopy=False)
    complete = sum(1 for t in stored if t.state == TrialState.COMPLETE)
    feasible = sum(1 for t in stored if t.state == TrialState.COMPLETE and results(t).get("feasible"))
    typer.echo(f"{spec.name}: {ran} trials in {time.perf_counter() - started:.1f} s with {count} {executor} "
               f"worker{'s' if count != 1 else ''} ({len(stored)} in the study: {complete} complete, {feasible} "
               f"feasible, {len(stored) - complete} failed); {len(front)} on the Pareto front → {out / 'pareto.csv'}; "
               f"search overhead {1000 * coordinator / max(ran, 1):.0f} ms per trial")
    return out
