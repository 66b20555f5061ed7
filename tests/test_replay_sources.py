"""``shc replay`` on every kind of source: the recorder's CSVs, ROS 1 and ROS 2 (mcap) bags built from the same
recording with OpenSHC's own LegState, and the unusable ones (one line, exit 2).

The bag tests use the first 1,000 cycles of the insectoid recording (the start-up, the settling and the first 2.8 s
of walking at throttle 0.5, so a velocity change is in it): the path through the bag is what they test; the whole
recording is replayed once, in test_replay_golden.py.
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from shc_cli.control.controller import RobotState
from shc_cli.errors import ShcError
from shc_cli.interop.bag import LEG_STATE_MSG
from shc_cli.replay import replay
from shc_cli.replay.opening import open_source
from shc_cli.replay.source import Recorded
from shc_cli.replay.states import infer_states
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot

from .conftest import GOLDEN
from .openshc_bags import write_openshc_bag
from .test_cli import run

RUNS = GOLDEN / "openshc-runs"
CYCLES = 1000
SOURCE_KEYS = ("source", "kind", "topics")
"""Report keys that name the source rather than the comparison."""


@pytest.fixture(scope="module")
def head() -> Recorded:
    return open_source(RUNS / "insectoid").head(CYCLES)


@pytest.fixture(scope="module")
def csv_prefix(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The first 1,000 cycles of the insectoid recording as a recording of its own (the same printed text)."""
    folder = tmp_path_factory.mktemp("recording")
    for part in ("joints", "tips", "body"):
        with gzip.open(RUNS / f"insectoid_{part}.csv.gz", "rt") as source:
            lines = [next(source) for _ in range(CYCLES + 1)]
        with gzip.open(folder / f"head_{part}.csv.gz", "wt") as target:
            target.writelines(lines)
    return folder / "head"


@pytest.fixture(scope="module")
def bags(head: Recorded, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("bags")
    return {"ros1": write_openshc_bag(head, folder / "insectoid.bag", ros1=True),
            "mcap": write_openshc_bag(head, folder / "insectoid_mcap", ros1=False)}


def replay_json(source: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
                *extra: str) -> dict[str, Any]:
    code, out, err = run(["replay", str(source), "--robot", "bullet_openshc", "--json", *extra], capsys, monkeypatch)
    assert (code, err) == (0, ""), err
    report: dict[str, Any] = json.loads(out)
    return report


def test_our_legstate_is_openshcs() -> None:
    """The LegState shc registers for bags without embedded definitions is OpenSHC's, field for field."""
    def fields(text: str) -> list[str]:
        return [" ".join(line.split()) for line in text.splitlines() if line.strip()]

    theirs = fields((GOLDEN / "openshc" / "msg" / "LegState.msg").read_text())
    assert theirs[0] == "Header header" and len(theirs) == 19
    assert fields(LEG_STATE_MSG) == ["std_msgs/Header header", *theirs[1:]]


@pytest.mark.parametrize("fmt", ["ros1", "mcap"])
def test_a_bag_replays_to_exactly_the_csv_figures(fmt: str, bags: dict[str, Path], csv_prefix: Path,
                                                  capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    from_csv = replay_json(csv_prefix, capsys, monkeypatch)
    from_bag = replay_json(bags[fmt], capsys, monkeypatch)
    assert from_bag["kind"] == ("ROS 1 bag" if fmt == "ros1" else "ROS 2 bag")
    assert "/syropod_remote/robot_state" in from_bag["topics"]
    same = {k: v for k, v in from_csv.items() if k not in SOURCE_KEYS}
    assert {k: v for k, v in from_bag.items() if k not in SOURCE_KEYS} == same
    assert from_csv["cycles"] == CYCLES
    assert from_csv["states"]["running"] == 509
    assert from_csv["at_cycle"]["velocity"] >= 723  # the throttle change is inside the slice, and compared
    assert max(v for v in from_csv["worst"].values()) < 1e-4


def test_a_bag_with_only_the_joints_and_inputs_compares_the_joints(head: Recorded, tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str],
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    bag = write_openshc_bag(head, tmp_path / "joints.bag", ros1=True,
                            topics={"/desired_joint_states", "/syropod_remote/desired_velocity"},
                            more_inputs=("/syropod_remote/gait_selection",))
    code, out, _ = run(["replay", str(bag), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert code == 0
    assert "compared: joints (30)\n" in out
    assert "inputs not replayed (expect differences where they act): /syropod_remote/gait_selection" in out
    assert "not in the source: tips and phase progress (/shc/LEG/state), body velocity (/shc/velocity)" in out
    report = replay_json(bag, capsys, monkeypatch)
    assert report["worst"]["model_tip_m"] is None
    assert report["worst"]["joints_rad"] < 2e-6
    assert report["states"]["running"] == 509  # the joints alone show it


def test_out_writes_the_per_cycle_differences_and_a_plot(csv_prefix: Path, tmp_path: Path,
                                                         capsys: pytest.CaptureFixture[str],
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    code, out, _ = run(["replay", str(csv_prefix), "--robot", "bullet_openshc", "--out", str(tmp_path / "d")],
                       capsys, monkeypatch)
    assert code == 0
    assert "worst difference:" in out and "joints" in out
    lines = (tmp_path / "d" / "differences.csv").read_text().splitlines()
    assert lines[0] == ("cycle,t,robot_state,walk_state,joints_rad,model_tip_m,walker_tip_m,poser_tip_m,velocity,"
                        "progress,pose")
    assert len(lines) == CYCLES + 1
    rows = [line.split(",") for line in lines[1:]]
    assert rows[0][2] == "PACKED" and rows[508][2] == "READY" and rows[509][2] == "RUNNING"
    assert rows[0][7] == ""  # the unposed poser tips were not compared
    assert max(float(r[4]) for r in rows) < 2e-6
    assert (tmp_path / "d" / "differences.png").read_bytes()[:4] == b"\x89PNG"


def test_tolerance_joints_exit_1_only_when_exceeded(csv_prefix: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err = run(["replay", str(csv_prefix), "--robot", "bullet_openshc", "--tolerance-joints", "1e-3"], capsys,
                       monkeypatch)
    assert (code, err) == (0, "")
    code, _, err = run(["replay", str(csv_prefix), "--robot", "bullet_openshc", "--tolerance-joints", "1e-9"], capsys,
                       monkeypatch)
    assert code == 1
    assert "more than --tolerance-joints 1e-09" in err


def test_absurd_and_non_finite_recorded_values_are_skipped_and_counted(head: Recorded, bullet: Robot,
                                                                       tripod: Gait) -> None:
    clean = replay(head, bullet, tripod).comparison
    assert head.tips is not None
    tips = {k: v.copy() for k, v in head.tips.items()}
    tips["walker"][700, 2, 0] = 2147483647.0  # as OpenSHC prints an undefined tip
    tips["model"][800, 0, 1] = np.nan
    joints = head.joints.copy()
    joints[900, 5] = np.inf
    broken = Recorded(head.source, head.kind, head.t, head.joint_names, joints, head.command, None, head.legs, tips,
                      head.progress, head.velocity, head.pose)
    result = replay(broken, bullet, tripod).comparison
    assert result.skipped["walker_tip_m"] == clean.skipped["walker_tip_m"] + 1
    assert result.skipped["model_tip_m"] == clean.skipped["model_tip_m"] + 1
    assert result.skipped["joints_rad"] == 1
    assert result.worst == clean.worst  # not compared, so no difference appears


def test_later_state_requests_come_from_the_recorded_input(head: Recorded, bullet: Robot) -> None:
    states = np.full(head.cycles, 2.0)
    states[800:] = 1.0  # the remote asks for READY from cycle 800
    plan = infer_states(Recorded(head.source, head.kind, head.t, head.joint_names, head.joints, head.command, states,
                                 head.legs, head.tips, head.progress), bullet)
    assert plan.later == [(801, RobotState.READY)]  # used one cycle after the recorder saw it
    assert plan.requests[800] == RobotState.RUNNING and plan.requests[801] == RobotState.READY


def test_a_source_that_starts_while_running_is_refused(head: Recorded, bullet: Robot) -> None:
    with pytest.raises(ShcError, match="already RUNNING in the first recorded cycle"):
        infer_states(head.rows(600, 700), bullet)


def _one_line_exit_2(argv: list[str], capsys, monkeypatch) -> str:  # type: ignore[no-untyped-def]
    code, out, err = run(argv, capsys, monkeypatch)
    assert code == 2, (out, err)
    assert out == "" and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    return err


def test_a_bag_without_the_joint_topic_is_one_line(head: Recorded, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str],
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    bag = write_openshc_bag(head.head(20), tmp_path / "no_joints", ros1=False,
                            topics={"/shc/velocity", "/syropod_remote/desired_velocity"})
    err = _one_line_exit_2(["replay", str(bag), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "no /desired_joint_states in the bag" in err and "rosbag record" in err


def test_a_bag_without_the_velocity_input_is_one_line(head: Recorded, tmp_path: Path,
                                                      capsys: pytest.CaptureFixture[str],
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    bag = write_openshc_bag(head.head(20), tmp_path / "no_input.bag", ros1=True, topics={"/desired_joint_states"})
    err = _one_line_exit_2(["replay", str(bag), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "no /syropod_remote/desired_velocity in the bag" in err


@pytest.mark.parametrize("ros1", [True, False])
def test_an_empty_bag_is_one_line(ros1: bool, head: Recorded, tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    bag = write_openshc_bag(head.head(0), tmp_path / ("empty.bag" if ros1 else "empty"), ros1=ros1)
    err = _one_line_exit_2(["replay", str(bag), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "the bag is empty" in err


def test_another_robots_joints_are_one_line(head: Recorded, tmp_path: Path,
                                            capsys: pytest.CaptureFixture[str],
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    bag = write_openshc_bag(head.head(20), tmp_path / "insectoid", ros1=False)
    err = _one_line_exit_2(["replay", str(bag), "--robot", "quadruped"], capsys, monkeypatch)
    assert "are not those of robot 'quadruped'" in err and "--robot" in err
    err = _one_line_exit_2(["replay", str(bag), "--robot", "octopod"], capsys, monkeypatch)
    assert "are not those of robot 'octopod': 6 of its 24 joints are missing, e.g. DR_coxa_joint" in err


def test_unusable_paths_and_files_are_one_line(csv_prefix: Path, tmp_path: Path,
                                               capsys: pytest.CaptureFixture[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    err = _one_line_exit_2(["replay", str(tmp_path / "nothing"), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "no such bag" in err
    (tmp_path / "notes.txt").write_text("hello\n")
    err = _one_line_exit_2(["replay", str(tmp_path / "notes.txt"), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "not a ROS 1 bag" in err
    err = _one_line_exit_2(["replay", str(tmp_path), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "without metadata.yaml" in err
    (tmp_path / "fake.bag").write_bytes(b"#ROSBAG V2.0\n" + b"\0" * 20)
    err = _one_line_exit_2(["replay", str(tmp_path / "fake.bag"), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "not a readable ROS 1 bag" in err
    folder = tmp_path / "bad"
    folder.mkdir()
    for part in ("joints", "tips", "body"):
        with gzip.open(f"{csv_prefix}_{part}.csv.gz", "rt") as handle:
            lines = handle.read().splitlines()[:30]
        if part == "joints":
            cells = lines[12].split(",")
            cells[4] = "oops"
            lines[12] = ",".join(cells)
        with gzip.open(folder / f"run_{part}.csv.gz", "wt") as handle:
            handle.write("\n".join(lines) + "\n")
    err = _one_line_exit_2(["replay", str(folder / "run"), "--robot", "bullet_openshc"], capsys, monkeypatch)
    assert "run_joints.csv.gz:13: AR_femur_joint: 'oops' is not a number" in err
    err = _one_line_exit_2(["replay", str(csv_prefix), "--robot", "bullet_openshc", "--tolerance-joints", "-1"],
                           capsys, monkeypatch)
    assert "--tolerance-joints" in err


def test_a_start_up_hidden_by_the_print_precision_is_found(head: Recorded, bullet: Robot) -> None:
    """A small start-up move printed with 6 decimals shows nothing in its first cycle; the start (and so RUNNING,
    a start-up's length later) is found from the fit of OpenSHC's cubic move, not from the first visible change."""
    steps, start = 500, 9
    n = start + steps + 20
    q0, target = np.zeros(30), np.linspace(-0.03, 0.03, 30)  # the largest joint move is 0.03 rad
    joints = np.tile(target, (n, 1))
    joints[:start] = q0
    u = np.arange(1, steps + 1) / steps
    joints[start:start + steps] = q0 + np.outer(3 * u**2 - 2 * u**3, target - q0)
    joints = np.round(joints, 6)
    assert np.flatnonzero(np.abs(np.diff(joints, axis=0)).max(axis=1) > 0)[0] + 1 == start + 1  # first visible: 10
    progress = np.full((n, 6, 2), -1.0)
    progress[start + steps:, :, 0] = 0.0  # RUNNING from 509, its joints still (a 3-DOF robot would not move them)
    recorded = Recorded(head.source, head.kind, np.arange(n) * 0.01, head.joint_names, joints, np.zeros((n, 3)),
                        None, head.legs, None, progress)
    plan = infer_states(recorded, bullet)
    assert (plan.first_motion, plan.running, plan.evidence) == (start, start + steps, "leg progress")


def test_a_recording_under_the_urdfs_joint_names_replays_through_the_servo_map(head: Recorded) -> None:
    """A robot recorded with its URDF's joint names (``j_c1_rf``, …): [hardware.servos]'s ``joint`` names them, and
    the comparison takes the same columns as for OpenSHC's names; without the map it is refused."""
    import dataclasses

    from shc_cli.replay.compare import Comparer
    from shc_cli.spec.loading import load_robot

    robot = load_robot("bullet").robot
    renamed = {name: f"urdf_{k}_{name.lower()}" for k, name in enumerate(head.joint_names)}
    recorded = dataclasses.replace(head, joint_names=[renamed[name] for name in head.joint_names][::-1],
                                   joints=head.joints[:, ::-1])
    servos = {key: servo.model_copy(update={"joint": renamed[f"{key}_joint"]})
              for key, servo in robot.hardware.servos.items()}
    mapped = robot.model_copy(update={"hardware": robot.hardware.model_copy(update={"servos": servos})})
    assert np.array_equal(Comparer(recorded, mapped).joints, Comparer(head, robot).joints)
    with pytest.raises(ShcError, match="are not those of robot 'bullet'"):
        Comparer(recorded, robot)
