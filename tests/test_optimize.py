"""``shc optimize``: study files, a small study end to end, determinism, interrupt and resume."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shc_cli.spec.study import load_study

from .conftest import ROOT
from .test_cli import run
from .test_sweep import _rows
from .test_sweep import _write as write_file

pytest.importorskip("optuna", reason="shc optimize needs optuna (python3 -m uv pip install --python .venv -e .)")

SMALL = """
name = "small"
robot = "bullet"
terrain = "flat"
duration = {duration}
seeds = {seeds}

[fixed]
"start_up.time_to_start" = 1.0   # a short start-up keeps each run ~2 s simulated

[space]
gait = {{ choices = ["tripod", "bipod"] }}
"walker.step_frequency" = {{ low = 0.8, high = 1.6, step = 0.1 }}
"walker.swing_height" = {{ low = 0.05, high = 0.12 }}
stride_percent = {{ low = 50, high = 100 }}

[objectives]
cot = "minimize"
mean_speed_mps = "maximize"

[constraints]
fell = false
mean_speed_mps = {{ min = 0.01 }}

[sampler]
name = "nsga2"
seed = 7
population = 2
"""


def _write(tmp_path: Path, text: str, name: str = "study.toml") -> Path:
    return write_file(tmp_path, text, name)


# -- the file ----------------------------------------------------------------------------------------------------


def test_shipped_studies_load_and_check() -> None:
    from shc_cli.domain.optimize.checks import check_study

    flat = load_study(ROOT / "studies" / "bullet_flat.toml")
    assert {d.key for d in flat.space} == {"gait", "walker.step_frequency", "stride_percent", "walker.swing_height",
                                          "walker.body_clearance"}
    assert next(d for d in flat.space if d.key == "gait").choices == ("tripod", "bipod", "ripple")
    assert flat.objectives["cot"] == "minimize" and flat.trials == 200
    ramp = load_study(ROOT / "studies" / "athena_ramp.toml")
    assert {d.key for d in ramp.space} == {"posture.kz", "posture.ka", "posture.kb", "posture.plane"}
    for study in (flat, ramp):
        check_study(study)


def test_a_pareto_robots_header_repeats_every_option_that_is_not_the_default() -> None:
    """The 'Found with: shc simulate' line of a Pareto robot file: velocity, terrain, scenario and duration, then the
    options the study changed (as SimulationConfig has them) — each a flag shc simulate takes."""
    import typer

    from shc_cli.backends.engine_registry import DEFAULT_ENGINE, ENGINES
    from shc_cli.cli import app
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.sweeps.options import simulate_flags

    other = next(e for e in ENGINES if e != DEFAULT_ENGINE)
    assert simulate_flags(SimulationConfig(velocity="0.5,0,0")) == [
        "--velocity 0.5,0,0", "--terrain flat", "--scenario WG", "--duration 20"]
    flags = simulate_flags(SimulationConfig(velocity="0.5,0,0", duration=8, physics_rate=800, friction=0.5,
                                            stand=False, admittance=True, engine=other, seed=3))
    assert flags == ["--velocity 0.5,0,0", "--terrain flat", "--scenario WG", "--duration 8", "--physics-rate 800",
                     "--friction 0.5", "--ground", "--admittance", f"--engine {other}"]
    simulate = typer.main.get_command(app).commands["simulate"]  # type: ignore[attr-defined]
    known = {name for param in simulate.params for name in (*param.opts, *param.secondary_opts)}
    assert {flag.split()[0] for flag in flags} <= known


def test_study_points_carry_seeds_options_and_robot_values(tmp_path: Path) -> None:
    study = load_study(_write(tmp_path, SMALL.format(duration=0.5, seeds="[3, 4]")))
    points = study.points(12, {"gait": "bipod", "walker.step_frequency": 1.2, "walker.swing_height": 0.07,
                               "stride_percent": 80})
    assert [p.slug for p in points] == ["t0012-s3", "t0012-s4"]
    assert [p.options["seed"] for p in points] == [3, 4]
    assert points[0].options["gait"] == "bipod" and points[0].options["stride_percent"] == 80
    assert points[0].options["duration"] == 0.5 and points[0].options["robot"] == "bullet"
    assert points[0].overrides == {"start_up.time_to_start": 1.0, "walker.step_frequency": 1.2,
                                   "walker.swing_height": 0.07}


@pytest.mark.parametrize(("text", "line", "message"), [
    ('robot = "bullet"\ncolour = 1\n', 2, "unknown key 'colour'"),
    ('[space]\nspeed = { low = 1, high = 2 }\n[objectives]\ncot = "minimize"\n', 2,
     "'speed' is not a simulation option"),
    ('[space]\n"walker.step_frequency" = { low = 2.0, high = 1.0 }\n[objectives]\ncot = "minimize"\n', 2,
     "low (2) must be below high (1)"),
    ('[space]\n"walker.swing_height" = { low = 0.0, high = 0.1, log = true }\n[objectives]\ncot = "minimize"\n', 2,
     "log range needs low > 0"),
    ('[space]\ngait = { choices = [] }\n[objectives]\ncot = "minimize"\n', 2, "non-empty list"),
    ('[space]\ngait = { choices = ["tripod"] }\n[objectives]\ncost = "minimize"\n', 4, "'cost' is not an analyze key"),
    ('[space]\ngait = { choices = ["tripod"] }\n[objectives]\ncot = "lowest"\n', 4, "is not a direction"),
    ('[space]\ngait = { choices = ["tripod"] }\n[objectives]\ncot = "minimize"\n[constraints]\nfell = true\n', 6,
     "is not a constraint"),
    ('[space]\ngait = { choices = ["tripod"] }\n[objectives]\ncot = "minimize"\n[sampler]\nname = "cmaes"\n', 6,
     "is not a sampler"),
    ('engine = "ode"\n[space]\ngait = { choices = ["tripod"] }\n[objectives]\ncot = "minimize"\n', 1,
     "'ode' is not a physics engine"),
    ('[space]\nterrain = { low = 1, high = 2 }\n[objectives]\ncot = "minimize"\n', 2, "'terrain' is not numeric"),
    ('[space]\nfriction = { choices = ["high"] }\n[objectives]\ncot = "minimize"\n', 2,
     "'high' is not a int or float"),
    ('seeds = [1, 1]\n', 1, "distinct integers"),
    ('seeds = [-1]\n', 1, "distinct integers ≥ 0"),
    ('[space]\ngait = { choices = ["tripod"] }\n[objectives]\ncot = "minimize"\n[sampler]\nseed = 4294967296\n', 6,
     "is not an integer in [0, 2**32 - 1]"),  # found by tests/test_fuzz_inputs.py: Optuna's ValueError
    ('[space]\n"walker.step_frequency" = { low = 0.8, high = 1.6, step = 1e-320 }\n[objectives]\ncot = "minimize"\n',
     2, "makes more than 1e+09 values"),  # found by the fuzzer: Optuna's decimal.InvalidOperation
    ('[space]\n"walker.step_frequency" = { low = 0.8, high = 1.6, step = 5.0 }\n[objectives]\ncot = "minimize"\n',
     2, "exceeds the range high - low = 0.8"),  # found by the fuzzer: Optuna warned and searched [0.8, 0.8]
    ('[space]\nseed = { low = 0, high = 9 }\n', 2, "set once per study"),
    ('[space]\n"walker.step_freq" = { low = 0.5, high = 1.0 }\n[objectives]\ncot = "minimize"\n', 2,
     "has no field 'walker.step_freq'"),
    ('[space]\ngait = { choices = ["tripod", "trot"] }\n[objectives]\ncot = "minimize"\n', 2, "trot"),
    ('[space]\n"walker.swing_height" = { low = 0.05, high = 0.5 }\n[objectives]\ncot = "minimize"\n', 2,
     "leaves the robot's range"),
])
def test_bad_study_files_are_one_line_with_the_line(tmp_path: Path, text: str, line: int, message: str, capsys,  # type: ignore[no-untyped-def]
                                                     monkeypatch) -> None:
    path = _write(tmp_path, text)
    code, _, err = run(["optimize", str(path), "--out", str(tmp_path / "out")], capsys, monkeypatch)
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    assert f"{path}:{line}:" in err and message in err, err
    assert not (tmp_path / "out").exists()  # nothing ran


# -- running -----------------------------------------------------------------------------------------------------


@pytest.mark.slow  # whole studies of simulated trials
def test_small_study_end_to_end(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Storage, trials and Pareto tables, robot files that validate and reproduce their trial, figures."""
    import optuna

    path = _write(tmp_path, SMALL.format(duration=0.5, seeds="[0, 1]"))
    out = tmp_path / "out"
    code, stdout, err = run(["optimize", str(path), "--trials", "3", "--workers", "2", "--out", str(out)], capsys,
                            monkeypatch)
    assert code == 0, err
    assert "3 trials" in stdout
    stored = optuna.load_study(study_name="small", storage=f"sqlite:///{out / 'study.db'}")
    assert [t.state.name for t in stored.trials] == ["COMPLETE"] * 3
    rows = _rows(out / "trials.csv")
    assert [r["trial"] for r in rows] == ["0", "1", "2"]
    for row, trial in zip(rows, stored.trials, strict=True):
        assert float(row["cot"]) == pytest.approx(trial.values[0], rel=1e-5)
        assert row["gait"] == trial.params["gait"]
        assert float(row["cot_spread"]) == 0.0  # flat ground without noise: both seeds give the same run
        runs = row["runs"].split(";")
        assert [Path(r).name for r in runs] == [f"t{int(row['trial']):04d}-s0", f"t{int(row['trial']):04d}-s1"]
        assert all((Path(r) / "summary.json").exists() for r in runs)
    pareto = _rows(out / "pareto.csv")
    assert pareto and {r["trial"] for r in pareto} <= {r["trial"] for r in rows if r["feasible"] == "True"}
    files = sorted((out / "pareto").glob("t*.toml"))
    assert [f.stem for f in files] == [f"t{int(r['trial']):04d}" for r in pareto]
    code, _, err = run(["validate", *map(str, files)], capsys, monkeypatch)
    assert code == 0, err
    from shc_cli.spec.loading import load_robot

    first = pareto[0]
    robot = load_robot(files[0]).robot
    assert robot.walker.gait == first["gait"]
    assert robot.walker.step_frequency.default == pytest.approx(float(first["walker.step_frequency"]), rel=1e-5)
    assert robot.walker.swing_height.default == pytest.approx(float(first["walker.swing_height"]), rel=1e-5)
    assert robot.start_up.time_to_start == 1.0
    assert f"--velocity {int(first['stride_percent']) / 100:g},0,0" in files[0].read_text()
    for name in ("pareto_cot__mean_speed_mps.png", "parallel.png", "importance.png"):
        assert (out / name).stat().st_size > 5000


def _study_params(out: Path) -> list[tuple[str, ...]]:
    keys = ("gait", "walker.step_frequency", "walker.swing_height", "stride_percent", "cot", "mean_speed_mps")
    return [tuple(r[k] for k in keys) for r in _rows(out / "trials.csv")]


@pytest.mark.slow  # whole studies of simulated trials
def test_same_seed_and_sampler_give_the_same_trials(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """NSGA-II with population 2: trials 2–4 are bred from told trials, so the whole loop must be deterministic."""
    path = _write(tmp_path, SMALL.format(duration=0.3, seeds="[0]"))
    tables = []
    for name in ("a", "b"):
        code, _, err = run(["optimize", str(path), "--trials", "5", "--workers", "1", "--out", str(tmp_path / name)],
                           capsys, monkeypatch)
        assert code == 0, err
        tables.append(_study_params(tmp_path / name))
    assert tables[0] == tables[1]
    assert len(set(tables[0])) > 1


@pytest.mark.slow  # whole studies of simulated trials
def test_interrupted_study_resumes_without_losing_or_rerunning_trials(tmp_path: Path) -> None:
    """SIGINT after two finished trials: they stay in the storage and trials.csv; --resume finishes the study
    without simulating them again (their run directories are untouched)."""
    path = _write(tmp_path, SMALL.format(duration=0.5, seeds="[0]"))
    out = tmp_path / "out"
    command = [sys.executable, "-m", "shc_cli.cli", "optimize", str(path), "--trials", "12", "--workers", "1",
               "--out", str(out)]
    env = {**os.environ, "CI": "1"}
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline:
        if (out / "trials.csv").exists() and len(_rows(out / "trials.csv")) >= 2:
            break
        if process.poll() is not None:
            pytest.fail(f"the study ended before it was interrupted: {process.communicate()}")
        time.sleep(0.1)
    else:
        process.kill()
        pytest.fail("no trial finished in time")
    process.send_signal(signal.SIGINT)
    _, err = process.communicate(timeout=120)
    assert process.returncode == 130, err  # interrupted: 128 + SIGINT, as plan and simulate
    assert "interrupted by SIGINT" in err and "--resume" in err
    before = {r["trial"]: r for r in _rows(out / "trials.csv") if r["state"] == "complete"}
    assert 2 <= len(before) < 12  # (5 trials were sometimes all done before the signal arrived)
    stamps = {run: (Path(run) / "summary.json").stat().st_mtime_ns for r in before.values()
              for run in r["runs"].split(";")}
    finished = subprocess.run([*command, "--resume"], capture_output=True, text=True, env=env, timeout=300)
    assert finished.returncode == 0, finished.stderr
    after = _rows(out / "trials.csv")
    assert [r["trial"] for r in after] == [str(trial) for trial in range(12)]
    assert all(r["state"] == "complete" for r in after), [(r["trial"], r["state"], r["error"]) for r in after]
    for number, row in before.items():
        assert {k: v for k, v in after[int(number)].items() if k != "trial_wall_s"} == \
            {k: v for k, v in row.items() if k != "trial_wall_s"}
    assert {run: (Path(run) / "summary.json").stat().st_mtime_ns for run in stamps} == stamps  # not re-run
    params = [tuple(r[k] for k in ("gait", "walker.step_frequency", "walker.swing_height", "stride_percent"))
              for r in after if not r["duplicate_of"]]  # (a sampler's repeat is a copy of its first, not a run)
    assert len(set(params)) == len(params)


def test_a_trial_with_the_values_of_a_finished_one_is_not_simulated_again(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                           monkeypatch) -> None:
    """Four trials over two possible values: at least two repeat an earlier trial and reuse its runs."""
    text = SMALL.format(duration=0.3, seeds="[0]")
    text = text[:text.index("[space]")] + '[space]\ngait = { choices = ["tripod", "bipod"] }\n' + \
        text[text.index("[objectives]"):].replace('name = "nsga2"', 'name = "random"').replace("population = 2\n", "")
    path = _write(tmp_path, text)
    out = tmp_path / "out"
    code, _, err = run(["optimize", str(path), "--trials", "4", "--workers", "1", "--out", str(out)], capsys,
                       monkeypatch)
    assert code == 0, err
    rows = _rows(out / "trials.csv")
    copies = [r for r in rows if r["duplicate_of"]]
    assert len(copies) >= 2
    for row in copies:
        first = rows[int(row["duplicate_of"])]
        assert first["gait"] == row["gait"] and not first["duplicate_of"]
        assert (row["cot"], row["mean_speed_mps"], row["runs"]) == \
            (first["cot"], first["mean_speed_mps"], first["runs"])
        assert not (out / "runs" / f"t{int(row['trial']):04d}-s0").exists()
    assert len(list((out / "runs").iterdir())) == len(rows) - len(copies)


def test_the_api_returns_the_study_and_prints_nothing(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    import shc_cli

    out = tmp_path / "out"
    result = shc_cli.optimize(_write(tmp_path, SMALL.format(duration=1.0, seeds="[0]")), trials=2, workers=1, out=out)
    assert capsys.readouterr().out == ""
    assert isinstance(result, shc_cli.StudyResult) and result.path == out
    assert result.trials == _rows(out / "trials.csv") and [r["trial"] for r in result.trials] == ["0", "1"]
    assert result.pareto == _rows(out / "pareto.csv") and result.pareto
    assert {r["trial"] for r in result.pareto} <= {r["trial"] for r in result.trials if r["feasible"] == "True"}
    report = result.report
    assert (report.ran, report.complete, report.workers, report.executor) == (2, 2, 1, "local")
    assert report.feasible == sum(r["feasible"] == "True" for r in result.trials)
    assert 0.0 < report.overhead_s < report.elapsed_s
    # the storage is closed: SQLite's write-ahead log is checkpointed into study.db, nothing beside it (issue 42)
    assert sorted(p.name for p in out.glob("study.db*")) == ["study.db"]
    import sqlite3
    from contextlib import closing

    with closing(sqlite3.connect(out / "study.db")) as db:  # and study.db alone holds every trial
        assert db.execute("SELECT COUNT(*) FROM trials").fetchone() == (2,)


@pytest.mark.slow  # whole studies of simulated trials
def test_an_existing_study_is_refused_unless_resumed_or_overwritten(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    path = _write(tmp_path, SMALL.format(duration=0.3, seeds="[0]"))
    out = tmp_path / "out"
    argv = ["optimize", str(path), "--trials", "1", "--workers", "1", "--out", str(out)]
    assert run(argv, capsys, monkeypatch)[0] == 0
    code, _, err = run(argv, capsys, monkeypatch)
    assert code == 2 and "already exists" in err and "--overwrite" in err
    code, _, err = run([*argv, "--resume", "--overwrite"], capsys, monkeypatch)
    assert code == 2 and "cannot be combined" in err
    (out / "trials.csv").write_text("stale\n", encoding="utf-8")
    code, _, err = run([*argv, "--overwrite"], capsys, monkeypatch)
    assert code == 0, err
    assert _rows(out / "trials.csv")[0]["trial"] == "0"
    other = tmp_path / "mine"
    other.mkdir()
    (other / "notes.txt").write_text("keep\n", encoding="utf-8")
    code, _, err = run([*argv[:-1], str(other), "--overwrite"], capsys, monkeypatch)
    assert code == 2 and "leaves it alone" in err
    assert (other / "notes.txt").exists()


def test_a_trial_interrupted_before_all_its_values_were_drawn_is_completed_on_resume(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                                      monkeypatch) -> None:
    """Ctrl-C between Optuna's ask and the last suggestion leaves a running trial with some values: --resume keeps
    them, draws the rest and runs it under its number."""
    import optuna

    path = _write(tmp_path, SMALL.format(duration=0.3, seeds="[0]"))
    out = tmp_path / "out"
    argv = ["optimize", str(path), "--workers", "1", "--out", str(out)]
    assert run([*argv, "--trials", "1"], capsys, monkeypatch)[0] == 0
    stored = optuna.load_study(study_name="small", storage=f"sqlite:///{out / 'study.db'}")
    stored.ask().suggest_categorical("gait", ["tripod", "bipod"])
    gait = stored.trials[1].params["gait"]
    code, _, err = run([*argv, "--trials", "2", "--resume"], capsys, monkeypatch)
    assert code == 0, err
    rows = _rows(out / "trials.csv")
    assert [(r["trial"], r["state"]) for r in rows] == [("0", "complete"), ("1", "complete")]
    assert rows[1]["gait"] == gait and rows[1]["walker.step_frequency"]


def test_ctrl_c_inside_a_run_stops_the_study_instead_of_failing_the_run(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """simulate turns Ctrl-C into a one-line error; run_point must not record that as a failed run and go on."""
    from shc_cli.domain.sweeps import points
    from shc_cli.errors import ShcError

    def interrupted(*_: object) -> None:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise ShcError("interrupted: the cycles completed so far are in …") from None

    def broken(*_: object) -> None:
        raise ShcError("a terrain file is missing")

    point = load_study(_write(tmp_path, SMALL.format(duration=0.3, seeds="[0]"))).points(0, {"gait": "tripod"})[0]
    monkeypatch.setattr(points, "simulate_point", interrupted)
    with pytest.raises(KeyboardInterrupt):
        points.run_point(point, str(tmp_path))
    monkeypatch.setattr(points, "simulate_point", broken)
    row = points.run_point(point, str(tmp_path))
    assert row["status"] == "failed" and "terrain file is missing" in row["error"]


@pytest.mark.slow  # whole studies of simulated trials
def test_dask_and_local_workers_give_the_same_trials(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Batches of --workers trials told in number order: the trials do not depend on which runs finish first, so a
    Dask LocalCluster and local worker processes (2 each) give the same study."""
    pytest.importorskip("dask.distributed", reason="the Dask executor needs dask[distributed]")
    path = _write(tmp_path, SMALL.format(duration=0.3, seeds="[0, 1]"))
    tables = []
    for executor in ("local", "dask"):
        out = tmp_path / executor
        code, _, err = run(["optimize", str(path), "--trials", "4", "--workers", "2", "--executor", executor,
                            "--out", str(out)], capsys, monkeypatch)
        assert code == 0, err
        tables.append(_study_params(out))
    assert tables[0] == tables[1]


@pytest.mark.slow  # whole studies of simulated trials
def test_a_study_on_mujoco_runs_its_trials_in_mujoco(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """``engine = "mujoco"`` reaches every run of every trial (summary.json names the engine)."""
    import json

    pytest.importorskip("mujoco")
    text = SMALL.format(duration=0.3, seeds="[0]").replace('terrain = "flat"\n',
                                                           'terrain = "flat"\nengine = "mujoco"\n')
    path = _write(tmp_path, text)
    code, _, err = run(["optimize", str(path), "--trials", "2", "--workers", "1", "--out", str(tmp_path / "mj")],
                       capsys, monkeypatch)
    assert code == 0, err
    rows = _rows(tmp_path / "mj" / "trials.csv")
    assert len(rows) == 2
    runs = [Path(r) for row in rows for r in row["runs"].split(";")]
    engines = {json.loads((run_dir / "summary.json").read_text())["engine"] for run_dir in runs}
    assert engines == {"mujoco"}
