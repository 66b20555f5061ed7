"""What a new user met (issue 15): two speeds named apart, runs that get nowhere, --overwrite, the workspace table
on a narrow terminal, robot paths that do not exist, reach errors in one unit."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from shc_cli.analysis.progress import cycle_path_length, progress_fields, progress_note
from shc_cli.record.summary import RunSummary

from .test_cli import run

# -- two speeds ------------------------------------------------------------------------------------------------


def test_plan_and_analyze_give_the_same_path_and_displacement_speeds(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                     monkeypatch) -> None:
    out = tmp_path / "arc"
    code, stdout, err = run(["plan", "bullet_openshc", "--velocity", "0.5,0,0.2", "--duration", "20", "--out", str(out),
                             "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert "path speed" in stdout and "displacement speed" in stdout and "NO PROGRESS" not in stdout
    code, stdout, _ = run(["analyze", str(out), "--json"], capsys, monkeypatch)
    result = json.loads(stdout)
    for key in ("path_speed_mps", "displacement_speed_mps"):
        assert result[key] == pytest.approx(summary[key], rel=1e-6), key
    # an arc: the straight line from start to end is shorter than the path; the 0.0767 m/s
    assert result["displacement_speed_mps"] == pytest.approx(0.0767, abs=5e-5)
    assert result["path_speed_mps"] > 1.15 * result["displacement_speed_mps"]
    assert result["mean_speed_mps"] == result["displacement_speed_mps"]  # the old key, for old readers
    # the path speed of the ideal path is the commanded speed
    assert result["path_speed_mps"] == pytest.approx(result["commanded_speed_mps"], rel=1e-3)


def test_velocity_help_says_throttle_unless_real(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    for command in ("plan", "simulate", "run-hw"):
        code, stdout, _ = run([command, "--help"], capsys, monkeypatch)
        assert code == 0
        text = " ".join(stdout.split())
        assert "throttle fractions" in text and "velocity_input_mode is 'real'" in text, command


# -- no progress -----------------------------------------------------------------------------------------------


def test_progress_counts_the_path_per_gait_cycle_not_the_sway() -> None:
    period, cycles = 100, 10
    t = np.arange(period * cycles + 1)
    sway = np.column_stack([0.03 * np.sin(2 * np.pi * t / period * 4), 0.02 * np.cos(2 * np.pi * t / period)])
    assert cycle_path_length(sway, period) == pytest.approx(0.0, abs=1e-12)  # back where it was every cycle
    radius = 0.5  # a full circle: no displacement, but the whole circumference walked
    angle = 2 * np.pi * t / len(t - 1)
    circle = radius * np.column_stack([np.cos(angle), np.sin(angle)])
    assert cycle_path_length(circle, period) == pytest.approx(2 * np.pi * radius, rel=0.02)

    stuck = progress_fields(0.1, commanded_speed_mps=0.05, window_s=20.0)
    assert stuck["no_progress"] and stuck["walked_share"] == pytest.approx(0.1)
    assert progress_note(RunSummary(**stuck)) == ", NO PROGRESS (walked 10% of the 1.00 m commanded)"
    assert not progress_fields(0.9, 0.05, 20.0)["no_progress"]
    standing = progress_fields(0.0, 0.0, 20.0)  # not commanded to walk: nothing to say
    assert not standing["no_progress"] and standing["walked_share"] is None
    assert progress_note(RunSummary(**standing)) == ""
    assert not progress_fields(0.0, 0.01, 2.0)["no_progress"]  # 0.02 m commanded: too short to judge


@pytest.mark.slow  # a long simulation on blocks
def test_athena_stuck_at_the_blocks_says_so(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "blocks"
    code, stdout, err = run(["simulate", "athena", "--terrain", "blocks", "--seed", "3", "--out", str(out),
                             "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["no_progress"] and summary["walked_share"] < 0.25
    assert "NO PROGRESS (walked" in stdout
    flat = tmp_path / "flat"
    code, stdout, err = run(["simulate", "athena", "--duration", "8", "--out", str(flat), "--no-plots"], capsys,
                            monkeypatch)
    assert code == 0, err
    summary = json.loads((flat / "summary.json").read_text())
    assert not summary["no_progress"] and summary["walked_share"] > 0.7 and "NO PROGRESS" not in stdout


# -- --overwrite -----------------------------------------------------------------------------------------------


def test_overwrite_replaces_a_finished_run_and_nothing_else(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "run"
    plan = ["plan", "openshc_default", "--no-plots", "--out", str(out)]
    assert run([*plan, "--duration", "1"], capsys, monkeypatch)[0] == 0
    first = json.loads((out / "summary.json").read_text())["cycles"]
    code, _, err = run([*plan, "--duration", "2"], capsys, monkeypatch)
    assert code == 2 and "already exists" in err and "--overwrite" in err
    assert json.loads((out / "summary.json").read_text())["cycles"] == first
    code, _, err = run([*plan, "--duration", "2", "--overwrite"], capsys, monkeypatch)
    assert code == 0, err
    assert json.loads((out / "summary.json").read_text())["cycles"] == first + 50  # 1 s more at 50 Hz
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no .partial, no set-aside copy
    # a folder shc did not write is never deleted
    precious = tmp_path / "thesis"
    precious.mkdir()
    (precious / "chapter1.tex").write_text("...")
    code, _, err = run(["plan", "openshc_default", "--no-plots", "--out", str(precious), "--overwrite"], capsys,
                       monkeypatch)
    assert code == 2 and "not a run directory" in err
    assert (precious / "chapter1.tex").read_text() == "..."
    assert not list(tmp_path.glob("*.partial"))


def test_sweep_overwrite_refuses_foreign_folders_and_resume(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from .conftest import ROOT

    sweep = str(ROOT / "sweeps" / "ci_smoke.toml")
    precious = tmp_path / "data"
    precious.mkdir()
    (precious / "notes.txt").write_text("keep")
    code, _, err = run(["sweep", sweep, "--out", str(precious), "--overwrite"], capsys, monkeypatch)
    assert code == 2 and "not a run directory" in err and (precious / "notes.txt").exists()
    code, _, err = run(["sweep", sweep, "--out", str(precious), "--overwrite", "--resume"], capsys, monkeypatch)
    assert code == 2 and "--resume" in err


# -- workspace table, robot paths, units -------------------------------------------------------------------------


def test_workspace_table_fits_the_terminal(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setenv("COLUMNS", "100")
    code, stdout, _ = run(["workspace", "athena", "--bearings", "72"], capsys, monkeypatch)
    assert code == 0
    lines = stdout.rstrip("\n").splitlines()
    assert max(len(line) for line in lines) <= 100
    headers = [line for line in lines if line.startswith("leg ")]
    bearings = [int(cell.rstrip("°")) for line in headers for cell in line.split("bearing", 1)[1].split()]
    assert bearings == list(range(0, 360, 5))  # every bearing, once, in order
    assert sum(line.startswith("max linear speed") for line in lines) == len(headers)
    monkeypatch.setenv("COLUMNS", "800")  # wide enough (697 characters): one block, as before
    code, stdout, _ = run(["workspace", "athena", "--bearings", "72"], capsys, monkeypatch)
    assert sum(line.startswith("leg ") for line in stdout.splitlines()) == 1


def test_a_robot_path_that_does_not_exist_is_not_the_bundled_robot(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.chdir(tmp_path)
    for given in ("robots/bullet.toml", "bullet.toml"):
        code, stdout, err = run(["validate", given], capsys, monkeypatch)
        assert (code, stdout) == (2, ""), given
        assert err.startswith(f"error: {given}: no such robot file") and "'bullet'" in err
    code, _, err = run(["plan", "robots/athena.toml", "--no-plots"], capsys, monkeypatch)
    assert code == 2 and "no such robot file" in err and not list(tmp_path.iterdir())
    assert run(["validate", "bullet"], capsys, monkeypatch)[0] == 0  # the bundled name still works


def test_unreachable_clearance_is_reported_in_metres(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    robot = tmp_path / "tall.toml"
    robot.write_text('extends = "bullet"\n\n[walker]\nbody_clearance = 0.6\n')
    code, _, err = run(["validate", str(robot)], capsys, monkeypatch)
    assert code == 2
    assert "body_clearance 0.6 m (short by" in err and " mm" not in err
    short = [float(x) for x in err.split("short by ")[1].split(" m ")[0].split(" to ")]
    assert all(0.05 < value < 0.6 and math.isfinite(value) for value in short)  # metres, not millimetres
