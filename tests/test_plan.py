"""``shc plan`` end to end, and controller properties over random command streams."""

from __future__ import annotations

import copy
import csv
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.walk import WalkState
from shc_cli.spec.loading import load_gait, load_robot

from .test_cli import run


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as handle:
        return list(csv.DictReader(handle))


def test_plan_writes_the_run_directory(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "run"
    code, stdout, err = run(["plan", "bullet_openshc", "--duration", "8", "--out", str(out)], capsys, monkeypatch)
    assert (code, err) == (0, "")
    assert "bullet_openshc / tripod" in stdout and str(out) in stdout
    assert {p.name for p in out.iterdir()} == {"joints.csv", "tips.csv", "body.csv", "summary.json", "gait.png",
                                                "tips.png", "joints.png", "robot.toml", "events.log"}
    from shc_cli.spec.loading import load_robot

    assert load_robot(out / "robot.toml").robot == load_robot("bullet_openshc").robot  # the expanded robot, loadable
    summary = json.loads((out / "summary.json").read_text())
    joints = _rows(out / "joints.csv")
    assert len(joints) == summary["cycles"] == summary["startup_cycles"] + 1 + 800  # + the cycle entering RUNNING
    assert list(joints[0])[:4] == ["cycle", "t", "AR_coxa", "AR_coxat"]
    tips = _rows(out / "tips.csv")
    assert "CL_poser_z" in tips[0] and "AL_swing_progress" in tips[0]
    body = _rows(out / "body.csv")
    assert body[-1]["robot_state"] == "RUNNING" and body[-1]["walk_state"] == "MOVING"
    assert float(body[-1]["vel_x"]) == pytest.approx(0.231884058, rel=1e-8)  # full throttle = v_max(0°)
    assert summary["achieved_mean_speed_mps"] == pytest.approx(summary["eq16_speed_mps"], rel=0.01)
    assert summary["ik_deviation_count"] == 0
    assert not list(tmp_path.glob("*.partial"))


def test_plan_follows_a_csv_timeline(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    timeline = tmp_path / "cmds.csv"
    timeline.write_text("cycle,vx,vy,wz\n0,0,0.5,0\n300,0,0,0\n")
    out = tmp_path / "run"
    code, _, _ = run(["plan", "openshc_default", "--commands", str(timeline), "--out", str(out), "--no-plots"],
                     capsys, monkeypatch)
    assert code == 0
    body = _rows(out / "body.csv")
    running = [r for r in body if r["robot_state"] == "RUNNING"][1:]  # after the cycle that entered RUNNING
    assert len(running) == 300 + 50  # last row + 1 s at 50 Hz
    assert running[0]["cmd_vy"] == "0.5" and running[299]["cmd_vy"] == "0.5" and running[300]["cmd_vy"] == "0"
    assert max(float(r["vel_y"]) for r in running) > 0.0
    assert all(float(r["vel_x"]) == 0.0 for r in running)


def test_plan_script_poses_the_body(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    script = tmp_path / "plan.toml"
    script.write_text('[[step]]\nat = 0.0\npose_velocity = [0, 0, 1, 0, 0, 0]\n'
                      '[[step]]\nat = 0.2\npose_velocity = [0, 0, 0, 0, 0, 0]\n')
    out = tmp_path / "run"
    code, _, err = run(["plan", "openshc_default", "--commands", str(script), "--duration", "1", "--out", str(out),
                        "--no-plots"], capsys, monkeypatch)
    assert (code, err) == (0, "")
    body = _rows(out / "body.csv")
    heights = [float(r["pose_z"]) for r in body if r["robot_state"] == "RUNNING"]
    # 10 cycles at input 1 × 0.05 m/s × 0.02 s = 0.01 m up from the body clearance, then held.
    assert heights[-1] == pytest.approx(0.1 + 0.01, abs=1e-9)


@pytest.mark.parametrize(("content", "message"), [
    ("cycle,vx,vy\n0,1,0\n", "expected the header 'cycle,vx,vy,wz'"),
    ("cycle,vx,vy,wz\n10,1,0,0\n5,0,0,0\n", "cmds.csv:3: cycle: cycle 5 is not after the previous row's 10"),
    ("cycle,vx,vy,wz\n0,fast,0,0\n", "cmds.csv:2: not numbers"),
    ("cycle,vx,vy,wz\n", "no command rows"),
])
def test_bad_timelines_are_one_line(tmp_path: Path, content: str, message: str, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    timeline = tmp_path / "cmds.csv"
    timeline.write_text(content)
    code, out, err = run(["plan", "openshc_default", "--commands", str(timeline), "--out", str(tmp_path / "r")],
                         capsys, monkeypatch)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and message in err


def test_bad_plan_script_names_the_line(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    script = tmp_path / "plan.toml"
    script.write_text("[[step]]\nat = 0.0\nvelocty = [1, 0, 0]\n")
    code, _, err = run(["plan", "openshc_default", "--commands", str(script)], capsys, monkeypatch)
    assert code == 2
    assert err.strip() == (f"error: {script}:3: step.0.velocty: unknown key 'velocty' (did you mean 'velocity'?)")


def test_bad_velocity_option_is_one_line(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err = run(["plan", "bullet", "--velocity", "fast"], capsys, monkeypatch)
    assert code == 2
    assert err.strip() == "error: --velocity: 'fast' is not three numbers VX,VY,WZ (e.g. --velocity 0.5,0,0)"


@pytest.fixture(scope="module")
def running_controllers() -> dict[str, Controller]:
    """Controllers that have completed their start-up (copied for each example)."""
    out = {}
    for name in ("openshc_default", "bullet_mammalian"):
        robot = load_robot(name).robot
        gait = load_gait(robot.walker.gait).gait
        controller = Controller(robot, gait)
        while controller.state != RobotState.RUNNING:
            controller.step(Command(state_request=RobotState.RUNNING))
        out[name] = controller
    return out


velocity = st.tuples(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.floats(-1.5, 1.5))
segments = st.lists(st.tuples(velocity, st.integers(1, 60)), min_size=1, max_size=6)


@pytest.mark.parametrize("name", ["openshc_default", "bullet_mammalian"])
@settings(max_examples=12, deadline=None)
@given(plan=segments)
def test_joint_targets_stay_finite_and_within_limits(name: str, plan: list, running_controllers) -> None:  # type: ignore[no-untyped-def,type-arg]
    controller = copy.deepcopy(running_controllers[name])
    chains = controller.model.chains
    for command_velocity, cycles in plan:
        for _ in range(cycles):
            out = controller.step(Command(velocity=command_velocity))
            assert np.all(np.isfinite(out.joints))
            assert np.all(out.joints >= chains.lower) and np.all(out.joints <= chains.upper)
            assert np.all(np.isfinite(out.walker_tips))
            walker = controller.walker
            assert walker is not None
            fastest = max(limit.angular_speed for limit in walker.limits.bearings.values())
            assert abs(out.velocity[2]) <= fastest + 1e-12


def test_robot_stops_at_its_default_stance(running_controllers) -> None:  # type: ignore[no-untyped-def]
    controller = copy.deepcopy(running_controllers["openshc_default"])
    for _ in range(200):
        controller.step(Command(velocity=(1.0, 0.0, 0.0)))
    out = None
    for _ in range(600):
        out = controller.step(Command())
    assert out is not None and out.walk_state == WalkState.STOPPED
    identity = np.array([[leg.stance.x, leg.stance.y] for leg in controller.robot.legs.values()])
    assert np.abs(out.walker_tips[:, :2] - identity).max() < 0.01  # OpenSHC's TIP_TOLERANCE


def test_plan_script_switches_gait_and_parameters(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    script = tmp_path / "plan.toml"
    script.write_text('[[step]]\nat = 0.0\nvelocity = [1, 0, 0]\n'
                      '[[step]]\nat = 3.0\ngait = "wave"\nparameters = { swing_height = 0.03 }\n')
    out = tmp_path / "run"
    code, _, err = run(["plan", "openshc_default", "--commands", str(script), "--duration", "12", "--out", str(out),
                        "--no-plots"], capsys, monkeypatch)
    assert (code, err) == (0, "")
    body = _rows(out / "body.csv")
    states = [r["walk_state"] for r in body if float(r["t"]) > 6.0 + 3.0]
    assert "STOPPED" in states and states[-1] in ("STARTING", "MOVING")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["gait"] == "wave"


def test_plan_script_rejects_unknown_parameters_and_gaits(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    script = tmp_path / "plan.toml"
    script.write_text('[[step]]\nat = 0.0\nparameters = { body_height = 0.2 }\n')
    code, _, err = run(["plan", "openshc_default", "--commands", str(script)], capsys, monkeypatch)
    assert code == 2 and "'body_height' is not a run-time parameter" in err and len(err.strip().splitlines()) == 1
    script.write_text('[[step]]\nat = 0.0\ngait = "trot"\n')
    code, _, err = run(["plan", "openshc_default", "--commands", str(script)], capsys, monkeypatch)
    assert code == 2 and "gait 'trot' does not fit robot 'openshc_default'" in err


def test_plan_script_manipulates_a_leg(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    script = tmp_path / "plan.toml"
    script.write_text('[[step]]\nat = 0.0\nleg_toggle = "AR"\n'
                      '[[step]]\nat = 3.0\ntip_velocity = { AR = [0, 0, 1] }\n'
                      '[[step]]\nat = 4.0\ntip_velocity = { AR = [0, 0, 0] }\n')
    out = tmp_path / "run"
    code, _, err = run(["plan", "openshc_default", "--commands", str(script), "--duration", "5", "--out", str(out),
                        "--no-plots"], capsys, monkeypatch)
    assert (code, err) == (0, "")
    tips = _rows(out / "tips.csv")
    z = [float(r["AR_model_z"]) for r in tips]
    assert max(z) > -0.1 + 0.02 + 0.04  # lifted to swing height above the body, then 1 s up at 0.05 m/s


def test_plan_script_rejects_an_unknown_leg(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    script = tmp_path / "plan.toml"
    script.write_text('[[step]]\nat = 0.0\nleg_toggle = "XX"\n')
    code, _, err = run(["plan", "openshc_default", "--commands", str(script)], capsys, monkeypatch)
    assert code == 2 and "no leg 'XX' on robot 'openshc_default'" in err and len(err.strip().splitlines()) == 1


def test_a_gait_switch_names_every_gait_and_a_short_run_measures_no_stance_speed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """A plan script that switches gait titles the run with both gaits in order (it said the last one); a run
    without a MOVING cycle says its stance-feet speed cannot be measured (it printed 0.0000 m/s, eq. 16: 0.0000)."""
    script = tmp_path / "plan.toml"
    script.write_text("[[step]]\nat = 0.0\nvelocity = [1, 0, 0]\n[[step]]\nat = 1.0\ngait = \"wave\"\n")
    out = tmp_path / "run"
    code, stdout, err = run(["plan", "openshc_default", "--commands", str(script), "--duration", "10", "--out",
                             str(out), "--no-plots"], capsys, monkeypatch)
    assert (code, err) == (0, "")
    assert "openshc_default / tripod → wave:" in stdout
    assert json.loads((out / "summary.json").read_text())["gaits"] == ["tripod", "wave"]
    code, stdout, _ = run(["plan", "bullet", "--duration", "0.05", "--out", str(tmp_path / "short"), "--no-plots"],
                          capsys, monkeypatch)
    assert code == 0 and "stance feet: not enough walking to measure" in stdout and "0.0000 m/s (eq. 16" not in stdout
