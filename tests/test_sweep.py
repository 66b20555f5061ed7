"""``shc sweep``: sweep files, the grid, robot variants, failures, resume, Dask = local, and the golden CI sweep."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

from shc_cli.errors import SpecError
from shc_cli.spec.sweep import load_sweep

from .conftest import GOLDEN, ROOT
from .test_cli import run

GOLDEN_SWEEP = GOLDEN / "sweeps" / "ci_smoke.csv"
GOLDEN_TABLE4 = GOLDEN / "sweeps" / "ci_table4.csv"
TOLERANCES = {"cot": 0.05, "mean_speed_mps": 0.05, "mean_power_w": 0.05}
"""Relative tolerances of the golden CI sweeps (MuJoCo, the default engine): the engines are deterministic on one
machine; these leave room for other CPUs and library builds while catching real changes of the controller, the
physics model or the analysis."""
TIMING = {"wall_time_s", "physics_time_s"}


def _write(tmp_path: Path, text: str, name: str = "sweep.toml") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


# -- the file ----------------------------------------------------------------------------------------------------


def test_grid_is_the_product_in_file_order(tmp_path: Path) -> None:
    sweep = load_sweep(_write(tmp_path, """
duration = 2.0
[grid]
gait = ["tripod", "bipod"]
stride_percent = [60, 100]
"walker.step_frequency" = [0.8, 1.0, 1.2]
[fixed]
robot = "bullet_mammalian"
"""))
    assert len(sweep.points) == 12
    first, last = sweep.points[0], sweep.points[-1]
    assert first.values == {"gait": "tripod", "stride_percent": 60, "walker.step_frequency": 0.8}
    assert last.values == {"gait": "bipod", "stride_percent": 100, "walker.step_frequency": 1.2}
    assert first.slug == "tripod-stride_percent=60-walker.step_frequency=0.8"
    assert first.options["robot"] == "bullet_mammalian" and first.options["duration"] == 2.0
    assert first.overrides == {"walker.step_frequency": 0.8}
    assert len({p.slug for p in sweep.points}) == 12


def test_engine_is_a_sweepable_option_and_sweep_engine_fills_it_in(tmp_path: Path) -> None:
    from shc_cli.backends.engine_registry import DEFAULT_ENGINE
    from shc_cli.domain.sweeps.options import point_config
    from shc_cli.domain.sweeps.run import with_engine

    both = load_sweep(_write(tmp_path, '[grid]\nengine = ["pybullet", "mujoco"]\n"walker.step_frequency" = [1.0]\n'))
    assert [p.options["engine"] for p in both.points] == ["pybullet", "mujoco"]
    assert [p.slug for p in both.points] == ["engine=pybullet-walker.step_frequency=1",
                                            "engine=mujoco-walker.step_frequency=1"]
    assert with_engine(both, "mujoco") == both  # the file chooses
    plain = load_sweep(ROOT / "sweeps" / "bullet_cot.toml")
    assert not any("engine" in p.options for p in plain.points)
    assert {point_config(p).engine for p in plain.points} == {DEFAULT_ENGINE} == {"mujoco"}  # simulate's default
    assert {p.options["engine"] for p in with_engine(plain, "pybullet").points} == {"pybullet"}
    assert [p.slug for p in with_engine(plain, "pybullet").points] == [p.slug for p in plain.points]
    for name in ("engines_agreement.toml", "engines_agreement_paper.toml"):
        agreement = load_sweep(ROOT / "sweeps" / name)
        assert len(agreement.points) == 12 and {p.options["engine"] for p in agreement.points} == {"pybullet", "mujoco"}


def test_the_options_are_simulates_and_each_run_is_one_config(tmp_path: Path) -> None:
    """Every option of shc simulate but the per-run ones is a sweep option, checked by SimulationConfig with the
    sweep file's line; a point's run is the SimulationConfig of its options (stride_percent as the velocity)."""
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.sweeps.checks import check_points
    from shc_cli.domain.sweeps.options import OPTIONS, PER_RUN, point_config

    assert set(OPTIONS) == (set(SimulationConfig.model_fields) - PER_RUN) | {"stride_percent"}
    assert {"posture", "inclination", "admittance", "imu_posing", "engine", "stand"} <= set(OPTIONS)
    sweep = load_sweep(_write(tmp_path, '[grid]\nstride_percent = [50]\ninclination = ["off", "openshc"]\n'
                                        '[fixed]\nfriction = 1\nscenario = "wg"\nstand = false\n'))
    check_points(sweep)
    config = point_config(sweep.points[1], out=tmp_path / "run", plots=False)
    assert config == SimulationConfig(velocity="0.5,0,0", inclination="openshc", friction=1.0, scenario="WG",
                                      stand=False, out=tmp_path / "run", plots=False)
    bad = load_sweep(_write(tmp_path, '[fixed]\nrobot = "bullet"\nposture = "kz=2"\n'))
    with pytest.raises(SpecError, match=r"sweep.toml:3: fixed.posture: kz='2' is not a gain in \[0, 1\]"):
        check_points(bad)


def test_shipped_sweeps_load_and_bullet_cot_is_the_papers_grid() -> None:
    sweep = load_sweep(ROOT / "sweeps" / "bullet_cot.toml")
    assert sweep.grid["stride_percent"] == [60, 75, 90, 100]  # paper eq. 21 L_s
    assert sweep.grid["walker.step_frequency"] == [0.4, 0.6, 0.8, 1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 2.2]  # F_s
    assert len(sweep.points) == 2 * 2 * 4 * 10
    assert len(load_sweep(ROOT / "sweeps" / "ci_smoke.toml").points) <= 8


def test_the_papers_table4_and_cot_sweeps_are_its_rows_and_figures() -> None:
    """Table IV: the paper's five rows × SA/WA/SG at 100 % stride; CoT: Fig. 14 (mammalian A, four strides), Fig. 15
    (insectoid A tripod and bipod at 100 %), Fig. 16 (arrangement B, insectoid also at 60.27 %)."""
    table4 = load_sweep(ROOT / "sweeps" / "openshc_table4.toml")
    rows = {(p.values["robot"], p.values["gait"]) for p in table4.points}
    assert rows == {("bullet_mammalian_a", "tripod"), ("bullet_mammalian_b", "tripod"),
                    ("bullet_insectoid_a", "tripod"), ("bullet_insectoid_a", "bipod"), ("bullet_insectoid_b", "tripod")}
    assert len(table4.points) == 15 and table4.fixed["stride_percent"] == 100
    short = load_sweep(ROOT / "sweeps" / "ci_table4.toml")
    assert [p.values for p in short.points] == [p.values for p in table4.points]
    cot = load_sweep(ROOT / "sweeps" / "openshc_cot.toml")
    cells = {(p.values["robot"], p.values["gait"], p.values["stride_percent"]) for p in cot.points}
    assert ("bullet_mammalian_a", "tripod", 60) in cells and ("bullet_insectoid_a", "bipod", 100) in cells
    assert ("bullet_insectoid_b", "tripod", 60.27) in cells and ("bullet_mammalian_b", "tripod", 100) in cells


def test_a_variant_changes_only_the_swept_default(tmp_path: Path) -> None:
    from shc_cli.domain.sweeps.points import robot_for
    from shc_cli.spec.loading import load_robot

    sweep = load_sweep(_write(tmp_path, '[grid]\n"walker.step_frequency" = [0.6]\n"walker.body_clearance" = [0.2]\n'))
    variant = load_robot(robot_for(sweep.points[0], tmp_path)).robot
    base = load_robot("bullet").robot
    assert variant.walker.step_frequency.default == 0.6
    assert (variant.walker.step_frequency.min, variant.walker.step_frequency.max) == (
        base.walker.step_frequency.min, base.walker.step_frequency.max)
    assert variant.walker.body_clearance == 0.2
    assert variant.model_copy(update={"walker": base.walker}) == base


@pytest.mark.parametrize(("text", "line", "message"), [
    ('[grid]\nrobot = ["bullet"]\nspeed = [1]\n', 3, "'speed' is not a simulation option"),
    ('[grid]\nrobot = "bullet"\n', 2, "must be a non-empty list"),
    ('[grid]\nstride_percent = [50, 120]\n', 2, "outside (0, 100]"),
    ('[grid]\nseed = [1.5]\n', 2, "is not a int"),
    ('[fixed]\nstride_percent = 50\n[grid]\nvelocity = ["1,0,0"]\n', 2, "both set the velocity input"),
    ('[grid]\n"walker.step_freq" = [1.0]\n', 2, "has no field 'walker.step_freq'"),
    ('[grid]\ngait = ["tripod", "trot"]\n', 2, "trot"),
    ('colour = "red"\n', 1, "unknown key 'colour'"),
    ('[grid]\nengine = ["pybullet", "ode"]\n', 2, "'ode' is not a physics engine"),
])
def test_bad_sweep_files_are_one_line_with_the_line(tmp_path: Path, text: str, line: int, message: str, capsys,  # type: ignore[no-untyped-def]
                                                     monkeypatch) -> None:
    path = _write(tmp_path, text)
    code, _, err = run(["sweep", str(path), "--out", str(tmp_path / "out")], capsys, monkeypatch)
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    assert f"{path}:{line}:" in err and message in err
    assert not (tmp_path / "out" / "runs").exists()  # nothing ran


# -- running -----------------------------------------------------------------------------------------------------


TWO = """
duration = 0.3
[grid]
terrain = ["flat", "heightfield:{missing}"]
[fixed]
robot = "bullet"
gait = "tripod"
"""


@pytest.mark.slow  # whole sweeps of simulations
def test_local_and_dask_give_the_same_results_and_a_failure_is_a_row(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A point whose terrain file is missing fails without stopping the sweep; a Dask LocalCluster gives the same
    table as the local worker processes (timings aside)."""
    path = _write(tmp_path, TWO.format(missing=tmp_path / "missing.csv"))
    tables = {}
    for executor in ("local", "dask"):
        out = tmp_path / executor
        code, stdout, err = run(["sweep", str(path), "--out", str(out), "--workers", "2", "--executor", executor],
                                capsys, monkeypatch)
        assert code == 0, err
        assert "2 runs" in stdout and "1 ok" in stdout and "1 failed" in stdout
        rows = _rows(out / "results.csv")
        assert [r["status"] for r in rows] == ["ok", "failed"]
        assert "missing.csv" in rows[1]["error"] and "\n" not in rows[1]["error"]
        assert float(rows[0]["mean_power_w"]) > 0.0
        tables[executor] = [{k: v for k, v in r.items() if k not in TIMING} for r in rows]
    assert tables["local"] == tables["dask"]


def test_a_programming_error_is_a_row_that_keeps_its_traceback(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                                caplog: pytest.LogCaptureFixture) -> None:
    """A bug in shc fails its point like a user error does, but its traceback is kept in the run directory (and
    logged) and the row says where; a user error stays one line; the next attempt runs the point again."""
    from shc_cli.domain.sweeps import points
    from shc_cli.errors import ShcError

    def buggy(*_: object) -> None:
        raise KeyError("no such column")

    def missing(*_: object) -> None:
        raise ShcError("a terrain file is missing")

    point = load_sweep(_write(tmp_path, "[grid]\nseed = [1]\n")).points[0]
    monkeypatch.setattr(points, "simulate_point", buggy)
    row = points.run_point(point, str(tmp_path / "out"))
    log = tmp_path / "out" / "runs" / "seed=1" / "error.log"
    assert row["status"] == "failed" and row["error"] == f"KeyError: 'no such column' (traceback in {log})"
    text = log.read_text(encoding="utf-8")
    assert text.startswith("Traceback") and "in buggy" in text and text.rstrip().endswith("'no such column'")
    assert str(log) in caplog.text
    monkeypatch.setattr(points, "simulate_point", missing)
    row = points.run_point(point, str(tmp_path / "out"))
    assert row["status"] == "failed" and row["error"] == "ShcError: a terrain file is missing"
    assert not log.exists()


@pytest.mark.slow  # whole sweeps of simulations
def test_ci_smoke_sweep_matches_its_golden_results(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The reviewed CoT, speed and power of sweeps/ci_smoke.toml (regenerate deliberately: docs/commands.md)."""
    out = tmp_path / "ci_smoke"
    code, _, err = run(["sweep", str(ROOT / "sweeps" / "ci_smoke.toml"), "--out", str(out), "--workers", "2"],
                       capsys, monkeypatch)
    assert code == 0, err
    golden = {r["slug"]: r for r in _rows(GOLDEN_SWEEP)}
    now = {r["slug"]: r for r in _rows(out / "results.csv")}
    assert set(now) == set(golden)
    problems = []
    for slug, want in golden.items():
        got = now[slug]
        if (got["status"], got["fell"]) != (want["status"], want["fell"]):
            problems.append(f"{slug}: status/fell {got['status']}/{got['fell']} (golden {want['status']}/"
                            f"{want['fell']})")
        for key, tolerance in TOLERANCES.items():
            a, b = float(got[key]), float(want[key])
            if abs(a - b) > tolerance * abs(b):
                problems.append(f"{slug}: {key} {a:.6g} vs golden {b:.6g} ({(a - b) / b:+.1%}, tolerance "
                                f"±{tolerance:.0%})")
    assert not problems, "ci_smoke moved beyond the golden tolerances:\n" + "\n".join(problems)
    # every run walks long enough to hold its speed for a whole gait cycle: no empty steady-speed column
    assert all(float(r["steady_speed_mps"]) > 0.0 for r in now.values())

    # --resume with every run finished re-reads them: same table, no simulation
    logs = sorted((out / "runs").glob("*/log.csv"))
    stamps = [p.stat().st_mtime_ns for p in logs]
    shutil.move(out / "results.csv", tmp_path / "first.csv")
    code, _, err = run(["sweep", str(ROOT / "sweeps" / "ci_smoke.toml"), "--out", str(out), "--resume"],
                       capsys, monkeypatch)
    assert code == 0, err
    assert [p.stat().st_mtime_ns for p in logs] == stamps
    assert _rows(out / "results.csv") == _rows(tmp_path / "first.csv")


@pytest.mark.slow  # whole sweeps of simulations
def test_ci_table4_sweep_matches_its_golden_results(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The paper's Table IV cells in short runs (sweeps/ci_table4.toml): the reviewed power of every cell within ±5 %
    (golden/sweeps/ci_table4.csv), no falls, and the paper's ordering walk air > stance air in every row."""
    out = tmp_path / "ci_table4"
    code, _, err = run(["sweep", str(ROOT / "sweeps" / "ci_table4.toml"), "--out", str(out), "--workers", "2"],
                       capsys, monkeypatch)
    assert code == 0, err
    golden = {r["slug"]: r for r in _rows(GOLDEN_TABLE4)}
    now = {r["slug"]: r for r in _rows(out / "results.csv")}
    assert set(now) == set(golden) and len(now) == 15
    problems = []
    for slug, want in golden.items():
        got = now[slug]
        if (got["status"], got["fell"]) != ("ok", "False"):
            problems.append(f"{slug}: status/fell {got['status']}/{got['fell']}")
        a, b = float(got["mean_power_w"]), float(want["mean_power_w"])
        if abs(a - b) > 0.05 * b:
            problems.append(f"{slug}: mean_power_w {a:.6g} vs golden {b:.6g} ({(a - b) / b:+.1%}, tolerance ±5%)")
    assert not problems, "ci_table4 moved beyond the golden tolerances:\n" + "\n".join(problems)
    power = {(r["robot"], r["gait"], r["scenario"]): float(r["mean_power_w"]) for r in now.values()}
    for (robot, gait, scenario), watts in power.items():
        if scenario == "WA":
            assert watts > power[(robot, gait, "SA")] + 5.0, (robot, gait)


def test_an_existing_output_needs_resume(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    (tmp_path / "out").mkdir()
    (tmp_path / "out" / "results.csv").write_text("x\n")
    code, _, err = run(["sweep", str(ROOT / "sweeps" / "ci_smoke.toml"), "--out", str(tmp_path / "out")], capsys,
                       monkeypatch)
    assert code == 2 and "--resume" in err


@pytest.mark.slow  # whole sweeps of simulations
def test_grids_with_different_keys_and_step_frequencies_make_one_table(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Two [[grid]] tables naming different keys (a step-frequency grid and a scenario grid) run, and the CoT plot
    groups the rows by the keys each has (it raised KeyError on the key the other grid lacks)."""
    path = _write(tmp_path, """
name = "mixed"
duration = 0.5
[[grid]]
"walker.step_frequency" = [0.8, 1.2]
[[grid]]
scenario = ["SA"]
[fixed]
robot = "bullet"
gait = "tripod"
""")
    out = tmp_path / "out"
    code, stdout, err = run(["sweep", str(path), "--out", str(out), "--workers", "2"], capsys, monkeypatch)
    assert code == 0, err
    assert "3 runs" in stdout and "3 ok" in stdout
    rows = _rows(out / "results.csv")
    assert [r["status"] for r in rows] == ["ok", "ok", "ok"]
    assert [r["scenario"] for r in rows] == ["", "", "SA"]
    assert (out / "cot.png").exists()


def test_engine_warnings_reach_the_results_table_and_the_terminal(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A run whose engine warned (here PyBullet's explicit-stability check on a light robot with a stiff servo law)
    says so in its results row and in one note after the sweep; a run without warnings has an empty cell."""
    _write(tmp_path, 'extends = "quadruped"\nname = "quad_dxl"\n[servo]\ncontrol = "dynamixel"\n', "quad_dxl.toml")
    path = _write(tmp_path, f"""
name = "warned"
duration = 0.5
[[grid]]
robot = ["quadruped", "{tmp_path / 'quad_dxl.toml'}"]
[fixed]
engine = "pybullet"
""")
    out = tmp_path / "out"
    code, stdout, err = run(["sweep", str(path), "--out", str(out), "--workers", "1"], capsys, monkeypatch)
    assert code == 0, err
    rows = _rows(out / "results.csv")
    assert rows[0]["engine_warnings"] == ""
    assert "too stiff for 400 Hz physics" in rows[1]["engine_warnings"]
    [note] = [line for line in stdout.splitlines() if line.startswith("note: 1 run had engine warnings")]
    assert rows[1]["slug"] in note
