"""What a new user met in the first hour (issue 26): the defaults, one overwrite rule for every output, figures that
cannot be measured, refused inputs, and messages that point at the right command."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .conftest import GOLDEN
from .test_cli import run


def test_simulate_defaults_to_mujoco_the_papers_bullet_and_its_calibrated_servos(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                                  monkeypatch) -> None:
    out = tmp_path / "walk"
    code, stdout, err = run(["simulate", "--duration", "1", "--out", str(out), "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text())
    assert (summary["engine"], summary["robot"], summary["servo_model"]) == ("mujoco", "bullet", "Dynamixel MX-106")
    assert summary["mass_kg"] == pytest.approx(10.07, abs=0.01)  # Table I, arrangement A (+ 6 g of feet)
    assert "bullet / tripod / WG on flat (mujoco)" in stdout and "generic servos" not in stdout
    from shc_cli.spec.loading import load_robot

    robot = load_robot(out / "robot.toml").robot
    assert robot is not None and robot.servo.control == "dynamixel"


def test_a_robot_without_servo_data_says_its_power_is_indicative(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, stdout, err = run(["simulate", "openshc_default", "--duration", "1", "--out", str(tmp_path / "r"),
                             "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    assert stdout.count("note: generic servos — power is indicative") == 1


@pytest.mark.parametrize("scenario", ["SA", "WA", "SG"])
def test_the_standing_and_air_scenarios_print_their_power_without_cot_or_progress(
        scenario: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """Walk air is not meant to go anywhere: no NO PROGRESS flag, and no CoT (it printed 'CoT None')."""
    code, stdout, err = run(["simulate", "--scenario", scenario, "--duration", "1", "--out", str(tmp_path / "r"),
                             "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    assert "mean power" in stdout and "CoT" not in stdout and "NO PROGRESS" not in stdout and "None" not in stdout


def test_figures_without_walking_say_so(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The summary line of a run with no walking window, and of a NO PROGRESS run, never prints a number that cannot
    be measured (it printed 'CoT None', 'mean power 0.0 W' after a Ctrl-C during start-up, and a NO PROGRESS run's
    CoT 137.88)."""
    from shc_cli.analysis.run_line import simulation_line
    from shc_cli.record.summary import RunSummary

    base = {"robot": "r", "gait": "tripod", "scenario": "WG", "engine": "mujoco", "sim_time_s": 3.0,
            "wall_time_s": 1.0, "distance_m": 0.0, "path_speed_mps": 0.0, "displacement_speed_mps": 0.0,
            "servo_model": "Dynamixel MX-106"}
    startup = simulation_line(RunSummary.model_validate({**base, "analysed_time_s": 0.0, "mean_power_w": None,
                                                         "cot": None}), "flat", Path("x"), ", stopped by SIGINT")
    assert "power: not enough walking to measure" in startup and "0.0 W" not in startup and "CoT" not in startup
    stuck = simulation_line(RunSummary.model_validate({**base, "analysed_time_s": 5.0, "mean_power_w": 120.0,
                                                       "cot": 137.88, "no_progress": True, "walked_share": 0.02,
                                                       "commanded_distance_m": 1.0}), "flat", Path("x"))
    assert "CoT: not enough walking to measure" in stuck and "137.88" not in stuck and "NO PROGRESS" in stuck
    assert "mean power 120.0 W" in stuck


@pytest.mark.parametrize("velocity", ["2,0,0", "0,-1.01,0", "0,0,3"])
def test_a_throttle_beyond_one_is_refused_not_clamped(velocity: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err = run(["plan", "bullet", "--velocity", velocity, "--out", str(tmp_path / "p")], capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "outside the throttle range −1…1" in err and not (tmp_path / "p").exists()


def test_every_out_refuses_an_existing_output_without_overwrite(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """One rule for every --out: an existing output is refused before any work (one line, exit 2) and replaced
    with --overwrite — workspace, analyze, render, replay and export urdf overwrote silently."""
    out = tmp_path / "ws"
    assert run(["workspace", "bullet", "--out", str(out)], capsys, monkeypatch)[0] == 0
    stamp = (out / "workspace.csv").stat().st_mtime_ns
    code, _, err = run(["workspace", "bullet", "--out", str(out)], capsys, monkeypatch)
    assert code == 2 and "already exists (add --overwrite" in err and len(err.strip().splitlines()) == 1
    assert (out / "workspace.csv").stat().st_mtime_ns == stamp
    assert run(["workspace", "bullet", "--out", str(out), "--overwrite"], capsys, monkeypatch)[0] == 0

    planned = tmp_path / "plan"
    assert run(["plan", "bullet", "--duration", "1", "--out", str(planned), "--no-plots"], capsys, monkeypatch)[0] == 0
    analysed = tmp_path / "analysis"
    assert run(["analyze", str(planned), "--out", str(analysed)], capsys, monkeypatch)[0] == 0
    code, _, err = run(["analyze", str(planned), "--out", str(analysed)], capsys, monkeypatch)
    assert code == 2 and "analysis.json: already exists (add --overwrite" in err
    assert run(["analyze", str(planned), "--out", str(analysed), "--overwrite"], capsys, monkeypatch)[0] == 0

    video = tmp_path / "walk.gif"
    video.write_bytes(b"GIF89a")
    code, _, err = run(["render", str(planned), "--out", str(video)], capsys, monkeypatch)
    assert code == 2 and "walk.gif: already exists (add --overwrite" in err and video.read_bytes() == b"GIF89a"
    code, _, err = run(["simulate", "--out", str(tmp_path / "s"), "--video", str(video)], capsys, monkeypatch)
    assert code == 2 and "already exists (add --overwrite" in err and not (tmp_path / "s").exists()

    urdf = tmp_path / "bullet.urdf"
    urdf.write_text("mine")
    code, _, err = run(["export", "urdf", "bullet", "--out", str(urdf)], capsys, monkeypatch)
    assert code == 2 and urdf.read_text() == "mine"


def test_render_says_the_video_length_and_the_render_time_apart(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("PIL")
    planned = tmp_path / "plan"
    code, _, _ = run(["plan", "bullet", "--duration", "0.2", "--out", str(planned), "--no-plots"], capsys, monkeypatch)
    assert code == 0
    code, stdout, err = run(["render", str(planned), "--out", str(tmp_path / "v.gif"), "--fps", "5", "--size",
                             "160x90"], capsys, monkeypatch)
    assert code == 0, err
    frames = int(stdout.split("(")[1].split()[0])
    assert f"{frames / 5:.1f} s of video ({frames} frames at 5 fps, 160x90), rendered in " in stdout


def test_messages_point_at_the_right_command(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    planned = tmp_path / "walk"
    code, _, _ = run(["plan", "bullet", "--duration", "0.2", "--out", str(planned), "--no-plots"], capsys, monkeypatch)
    assert code == 0
    code, _, err = run(["replay", str(planned), "--robot", "bullet"], capsys, monkeypatch)
    assert code == 2 and "an shc run, not an OpenSHC recording" in err and f"shc view {planned}" in err

    sweep = tmp_path / "sweep"
    (sweep / "runs").mkdir(parents=True)
    (sweep / "results.csv").write_text("index,slug\n")
    code, _, err = run(["analyze", str(sweep)], capsys, monkeypatch)
    assert code == 2 and "a sweep's output, not a run directory" in err and str(sweep / "runs" / "*") in err

    code, _, err = run(["view", str(tmp_path / "runs" / "nothere")], capsys, monkeypatch)
    assert code == 2 and "no such run directory or bag" in err and "robot file" in err

    code, out, _ = run(["--help"], capsys, monkeypatch)
    commands = out.split("Commands:")[1]
    assert code == 0 and "..." not in commands and "…" not in commands


def test_replaying_a_recording_on_the_wrong_robot_hints_at_it(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The mammalian recording replayed with the insectoid robot differs by radians: the report says which option is
    probably wrong; replayed on its own robot it has no hint."""
    source = str(GOLDEN / "openshc-runs" / "mammalian_excerpt")
    code, out, _ = run(["replay", source, "--robot", "bullet_openshc", "--gait", "bipod"], capsys, monkeypatch)
    assert code == 0 and "hint: joints differ by up to" in out and "--robot" in out
    code, out, _ = run(["replay", source, "--robot", "bullet_mammalian"], capsys, monkeypatch)
    assert code == 0 and "hint:" not in out


@pytest.mark.parametrize(("name", "said"), [
    ("sweeps/ci_smoke.toml", "sweep 'ci_smoke' ok (8 runs, 4 robot variants checked)"),
    ("studies/bullet_flat.toml", "study 'bullet_flat' ok (5 parameters, 4 robot variants checked"),
    ("poses/tripod.toml", "auto-pose set 'tripod' ok"),
    ("gaits/wave.toml", "gait 'wave' ok"),
])
def test_validate_checks_every_shc_file_as_what_it_is(name: str, said: str, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A sweep or study was read as a robot file ("grid: unknown key 'grid'")."""
    from .conftest import ROOT

    code, out, err = run(["validate", str(ROOT / name)], capsys, monkeypatch)
    assert (code, err) == (0, "") and said in out


def test_validate_checks_a_sweeps_robot_variants_and_a_plan_script(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Every point's robot variant is checked without running it: a body clearance no leg reaches is an error at
    its line; a plan script is read as a plan script (its typo named at its line)."""
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('name = "high"\nduration = 1.0\n[grid]\n"walker.body_clearance" = [0.2, 0.6]\n'
                     '[fixed]\nrobot = "bullet"\n')
    code, _, err = run(["validate", str(sweep)], capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert f"{sweep}:4:" in err and "walker.body_clearance = 0.6" in err and "no leg reaches its stance" in err
    script = tmp_path / "plan.toml"
    script.write_text('[[step]]\nat = 0.0\nvelocity = [1, 0, 0]\n[[step]]\nat = 2.0\ngait = "wave"\n')
    code, out, _ = run(["validate", str(script)], capsys, monkeypatch)
    assert code == 0 and "plan script ok (2 changes)" in out
    script.write_text('[[step]]\nat = 0.0\nvelocty = [1, 0, 0]\n')
    code, _, err = run(["validate", str(script)], capsys, monkeypatch)
    assert code == 2 and "unknown key 'velocty'" in err
