"""The ask/tell loop of ``shc optimize``.

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
through the sweep machinery (:class:`~shc_cli.domain.sweeps.pool.RunPool`,
:func:`~shc_cli.domain.sweeps.points.run_point`). Trials go in batches of ``workers``: the batch's runs (trials ×
seeds) share the workers and the trials are told in number order when the batch ends, so the same sampler seed
gives the same trials whatever the timing. A trial whose values equal a finished one's is told that trial's result
instead of being simulated again (same inputs and seeds give the same runs).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shc_cli.domain.optimize.checks import check_study
from shc_cli.domain.optimize.evaluate import ATTRIBUTE, evaluate, metric_keys, stored
from shc_cli.domain.optimize.outputs import write_outputs
from shc_cli.domain.optimize.storage import STORAGE, close_study, open_study, prepare_output
from shc_cli.domain.sweeps.checks import check_executor
from shc_cli.domain.sweeps.points import clear_stop
from shc_cli.domain.sweeps.pool import RunPool
from shc_cli.domain.sweeps.results import Row
from shc_cli.errors import Interrupted, Issue, SpecError, install_hint, signal_name
from shc_cli.spec.study import Dimension, load_study

if TYPE_CHECKING:
    import optuna


@dataclass(frozen=True)
class StudyReport:
    """A finished (or resumed and finished) study.

    Attributes:
        name: the study's name.
        path: its output directory (``trials.csv``, ``pareto.csv``, ``study.db``).
        trials: the ``trials.csv`` rows, every trial of the study in number order (values, not yet table text).
        pareto: the ``pareto.csv`` rows: the complete, feasible, non-dominated trials.
        ran: trials finished by this call (simulated, or told a duplicate's result).
        workers: parallel runs it used.
        executor: ``local`` or ``dask``.
        elapsed_s: wall time of this call [s].
        overhead_s: time of the search itself (ask, tell, storage, trials.csv) [s].
    """

    name: str
    path: Path
    trials: list[Row]
    pareto: list[Row]
    ran: int
    workers: int
    executor: str
    elapsed_s: float
    overhead_s: float

    @property
    def complete(self) -> int:
        """Trials of the study that completed."""
        return sum(1 for r in self.trials if r["state"] == "complete")

    @property
    def notes(self) -> list[str]:
        """What the user should know about the result (printed as ``note:`` lines): too few trials to trust
        importance.png."""
        from shc_cli.domain.optimize.plots import FEW_TRIALS

        if self.complete >= FEW_TRIALS:
            return []
        return [f"only {self.complete} complete trials: importance.png's shares are not to be trusted below "
                f"{FEW_TRIALS} (run more with --resume --trials N)"]

    @property
    def feasible(self) -> int:
        """Complete trials that meet every constraint."""
        return sum(1 for r in self.trials if r["state"] == "complete" and bool(r["feasible"]))


class _SignalLatch:
    """Remembers a SIGINT while the study runs, so that one whose KeyboardInterrupt landed in a callback that Python
    ignores (SQLAlchemy's garbage-collection hook: "Exception ignored in … _collection_gced") still interrupts the
    study at the next batch instead of being lost (the study then ran to its end and exited 0)."""

    def __init__(self) -> None:
        self.received = False
        self._previous: object = None

    def __enter__(self) -> _SignalLatch:
        import signal
        import threading

        if threading.current_thread() is threading.main_thread():
            self._previous = signal.getsignal(signal.SIGINT)
            signal.signal(signal.SIGINT, self._handle)
        return self

    def _handle(self, signum: int, frame: object) -> None:
        self.received = True
        previous = self._previous
        if callable(previous):  # (SIG_IGN and SIG_DFL are not callable)
            previous(signum, frame)
        raise KeyboardInterrupt

    def check(self) -> None:
        """Raise the remembered interruption (a SIGINT whose KeyboardInterrupt was swallowed)."""
        if self.received:
            raise KeyboardInterrupt

    def __exit__(self, *exc: object) -> None:
        import signal
        import threading

        previous = self._previous
        if previous is not None and threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, previous)  # type: ignore[arg-type]  # (what getsignal gave)


def suggest(trial: optuna.trial.Trial, dimension: Dimension) -> Any:
    """The trial's value of one searched parameter."""
    if dimension.kind == "categorical":
        return trial.suggest_categorical(dimension.key, list(dimension.choices))
    if dimension.kind == "int":
        return trial.suggest_int(dimension.key, int(dimension.low), int(dimension.high),
                                 step=int(dimension.step or 1), log=dimension.log)
    return trial.suggest_float(dimension.key, dimension.low, dimension.high, step=dimension.step, log=dimension.log)


def _key(params: dict[str, Any]) -> str:
    return repr(sorted(params.items()))


def tell_copy(study: optuna.study.Study, trial: optuna.trial.Trial, same: optuna.trial.FrozenTrial) -> None:
    """Tell ``trial`` the result of the finished trial ``same`` that had the same values: same inputs and seeds give
    the same runs (``shc simulate``'s guarantee), so they are not simulated again."""
    from optuna.trial import TrialState

    trial.set_user_attr(ATTRIBUTE, {**stored(same), "trial_wall_s": 0.0, "sim_wall_s": 0.0,
                                    "duplicate_of": same.number})
    for key, value in stored(same).get("constraints", {}).items():
        trial.set_constraint(key, value)
    if same.state == TrialState.COMPLETE and same.values is not None:
        study.tell(trial, list(same.values))
    else:
        study.tell(trial, state=TrialState.FAIL)


def run_optimize(file: Path, trials: int | None = None, workers: int | None = None, executor: str = "local",
                 scheduler: str | None = None, out: Path | None = None, resume: bool = False,
                 overwrite: bool = False) -> StudyReport:
    """Check the study, run trials until ``trials`` have finished (counting earlier ones on ``resume``), write the
    tables, robot files and plots.

    Args:
        file: the study file.
        trials: trials to finish, earlier ones included (None: the study's ``trials``, else 20).
        workers: parallel runs, and trials per batch (None: every core).
        executor: ``local`` (worker processes) or ``dask``.
        scheduler: the Dask scheduler's address (None: a LocalCluster).
        out: the output directory (None: ``runs/<study name>``).
        resume: continue the study in ``out`` from its storage.
        overwrite: delete an existing output directory (shc's own) first.
    """
    try:
        import optuna
    except ImportError:
        raise SpecError([Issue(None, None, "optimize", "optuna is not installed",
                               install_hint())]) from None
    spec = load_study(file)
    check_executor(executor, scheduler)
    check_study(spec)
    total = trials or spec.trials or 20
    if total < 1:
        raise SpecError([Issue(None, None, "--trials", f"{total} is not a positive number of trials", "e.g. 50")])
    out = out or Path("runs") / spec.name
    prepare_output(spec, out, resume, overwrite)
    clear_stop(out)  # an earlier interrupted study's stop request
    count = workers or os.cpu_count() or 1
    study = open_study(spec, out, resume)
    from optuna.trial import TrialState

    keys = metric_keys(spec)
    started = time.perf_counter()
    ran = 0
    coordinator = 0.0  # [s] asking, telling, storage and trials.csv: the overhead of the search itself
    signals = _SignalLatch()
    try:
        with RunPool(executor, count, scheduler) as pool, signals:
            while True:
                signals.check()
                iteration = time.perf_counter()
                existing = study.get_trials(deepcopy=False)
                finished = sum(1 for t in existing if t.state.is_finished())
                pending = sorted((t for t in existing if t.state == TrialState.RUNNING), key=lambda t: t.number)
                if finished >= total and not pending:
                    break
                batch = [optuna.trial.Trial(study, t._trial_id) for t in pending[:count]]  # interrupted: re-run
                # a stored value is returned as it was; one the interruption came before is sampled now
                params = {t.number: {d.key: suggest(t, d) for d in spec.space} for t in batch}
                for _ in range(min(count - len(batch), total - finished - len(pending))):
                    trial = study.ask()
                    params[trial.number] = {d.key: suggest(trial, d) for d in spec.space}
                    batch.append(trial)
                earlier = {_key(t.params): t for t in existing if t.state.is_finished() and "runs" in stored(t)}
                for trial in [t for t in batch if _key(params[t.number]) in earlier]:
                    tell_copy(study, trial, earlier[_key(params[trial.number])])
                    batch.remove(trial)
                    ran += 1
                if not batch:
                    coordinator += time.perf_counter() - iteration
                    continue
                begun = time.perf_counter()
                coordinator += begun - iteration
                points = [p for t in batch for p in spec.points(t.number, params[t.number])]
                rows: dict[int, list[Row]] = {t.number: [] for t in batch}
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
        rows_all, front = write_outputs(spec, out, study.get_trials(deepcopy=False), figures=True)
    except KeyboardInterrupt as error:
        write_outputs(spec, out, study.get_trials(deepcopy=False), figures=False)
        done = sum(1 for t in study.get_trials(deepcopy=False) if t.state.is_finished())
        raise Interrupted(f"{done} trials finished, kept in {out / STORAGE} and {out / 'trials.csv'}; continue "
                          "with --resume", signal_name(error)) from None
    finally:
        close_study(study)
    return StudyReport(spec.name, out, rows_all, front, ran, count, executor, time.perf_counter() - started,
                       coordinator)
