"""A study's output directory and Optuna's storage in it (SQLite), with the study's seeded sampler."""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.errors import Issue, OutputError, SpecError
from shc_cli.spec.study import Study

if TYPE_CHECKING:
    import sqlite3

    import optuna

STORAGE = "study.db"
"""Optuna's storage in the output directory: every trial, its parameters, objectives and state."""
STUDY_FILE = "study.toml"
"""The study file as run, in the output directory (a resumed study must be the same)."""


def prepare_output(spec: Study, out: Path, resume: bool, overwrite: bool) -> None:
    """Make ``out`` ready: a resumed study must have its storage and the same study file; a new one needs an empty
    (or, with ``overwrite``, shc's own) folder. The study file is copied in."""
    copy = out / STUDY_FILE
    if resume and overwrite:
        raise SpecError([Issue(None, None, "--overwrite", "cannot be combined with --resume", "choose one")])
    if resume:
        if not (out / STORAGE).exists():
            raise OutputError(f"{out}: no {STORAGE} to resume (run without --resume first)")
        if copy.exists() and copy.read_bytes() != spec.path.read_bytes():
            raise OutputError(f"{out}: was started with a different study file ({copy}); resume it with that "
                              "file or choose another --out")
    else:
        from shc_cli.record.runlog import clear_output

        clear_output(out, overwrite,
                     "add --resume to continue it, --overwrite to start it again, or choose another --out")
    (out / "runs").mkdir(parents=True, exist_ok=True)
    if spec.path.resolve() != copy.resolve():
        shutil.copyfile(spec.path, copy)


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


def open_study(spec: Study, out: Path, resume: bool) -> optuna.study.Study:
    """The study in ``out/study.db``: created, or (``resume``) loaded — with the same objectives."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    path = (out / STORAGE).resolve()

    def connect() -> sqlite3.Connection:
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
        close_storage(storage)
        raise SpecError([Issue(spec.path, None, "objectives", f"the stored study in {out / STORAGE} has other "
                               "objectives", "resume with the same study file, or choose another --out")])
    _OPEN[id(study)] = storage
    return study


_OPEN: dict[int, optuna.storages.RDBStorage] = {}
"""The storage of each study :func:`open_study` opened and :func:`close_study` has not closed, by ``id(study)``."""


def close_storage(storage: optuna.storages.RDBStorage) -> None:
    """Close every connection to the SQLite file: the last one checkpoints the write-ahead log into ``study.db``
    and removes ``study.db-wal`` and ``study.db-shm`` (a finished study left them beside it)."""
    storage.remove_session()
    storage.engine.dispose()


def close_study(study: optuna.study.Study) -> None:
    """Close the storage of a study :func:`open_study` opened (once; then the study is not to be used)."""
    storage = _OPEN.pop(id(study), None)
    if storage is not None:
        close_storage(storage)
