"""A start-up that never throws a robot (issue 37, point 9): validate refuses a standing pose with a link below the
ground; falls, flips and launches count from the first cycle, start-up included; no start-up commands a joint
faster than its servo's limit. The description: tests/data/startup/knees_below_feet.toml (femurs that may only
point down, tibias that may only bend up: the knees stand below the feet)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.loop.physics_summary import DIVERGED, FALL_TILT, MAX_BODY_SPEED, START_UP_GRACE_S, PhysicsRecord
from shc_cli.spec.loading import bundled, load_gait, load_robot

from .conftest import ROOT
from .test_cli import run

KNEES = ROOT / "tests" / "data" / "startup" / "knees_below_feet.toml"


def knee_depth_by_hand() -> float:
    """The knees' depth below the ground from the file's numbers by planar two-link IK (not shc's): the foot 0.10 m
    out from the femur joint (stance 0.23 m from the centre − base 0.10 − coxa 0.03) and 0.03 m down, femur 0.12 m,
    tibia 0.09 m, the femur pointing down; the ground is the foot radius (0.012 m) below the feet."""
    x, z, femur, tibia = 0.10, -0.03, 0.12, 0.09
    reach = math.hypot(x, z)
    inner = math.acos((femur**2 + reach**2 - tibia**2) / (2 * femur * reach))
    down = math.atan2(z, x) - inner  # the femur below the line to the foot: the knee-down solution
    knee_z = femur * math.sin(down)
    return (z - 0.012) - knee_z


def test_validate_refuses_a_standing_pose_with_the_knees_below_the_feet(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """One line, exit 2, no traceback: the link and its depth (0.065 m by hand)."""
    depth = knee_depth_by_hand()
    assert depth == pytest.approx(0.065, abs=0.001)
    code, out, err = run(["validate", str(KNEES)], capsys, monkeypatch)
    assert code == 2 and "Traceback" not in err
    [line] = [line for line in (out + err).splitlines() if line.strip()]
    assert "knees_below_feet.toml:14: walker.body_clearance" in line
    assert f"link AR_femur_link (leg AR) {depth:.3f} m below the ground" in line, line
    assert "(and 11 more links)" in line  # the other five femurs and the six tibias, whose far ends are the knees


def test_the_knees_up_solution_validates(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The fix the line suggests works: joint limits that let the femurs point up (tibias bending down) keep the
    knees above the feet."""
    fixed = tmp_path / "fixed.toml"
    text = KNEES.read_text().replace("min = -1.57, max = -0.8,", "min = -1.57, max = 1.0,")
    fixed.write_text(text.replace("min = 0.0, max = 2.4,", "min = -2.4, max = 0.0,").replace(
        "unpacked = 2.1", "unpacked = -1.0").replace("unpacked = -1.1", "unpacked = 0.3"))
    code, out, err = run(["validate", str(fixed)], capsys, monkeypatch)
    assert code == 0, out + err


@pytest.mark.parametrize("robot", bundled("robots"))
def test_every_bundled_robot_stands_above_the_ground(robot: str) -> None:
    """No false alarm: every bundled robot's standing pose keeps its links above the ground."""
    from shc_cli.validation import standing_depths

    assert standing_depths(load_robot(robot).robot) == []


def _record(state: RobotState, rpy: tuple[float, float, float], height: float) -> tuple[str | None, PhysicsRecord]:
    """A fall check of ``bullet`` fed one reading at cycle 3, and again as long after as a start-up fall waits
    (:data:`START_UP_GRACE_S`, 2 s): what the second call says (the first said nothing unless RUNNING)."""
    robot = load_robot("bullet").robot
    backend = SimpleNamespace(world=SimpleNamespace(physics_time=0.0))
    record = PhysicsRecord(robot, backend, airborne=False)  # type: ignore[arg-type]
    reading = SimpleNamespace(rpy=np.array(rpy), body_height=height, position=np.zeros(3),
                              linear_velocity=np.zeros(3))
    out = SimpleNamespace(robot_state=state)
    first = record(3, None, out, reading)  # type: ignore[arg-type]
    if state == RobotState.RUNNING:
        return first, record
    assert first is None and not record.fell
    later = 3 + round(START_UP_GRACE_S / robot.time_delta)
    return record(later, None, out, reading), record  # type: ignore[arg-type]


@pytest.mark.parametrize("state", [RobotState.PACKED, RobotState.READY, RobotState.UNKNOWN])
def test_a_flip_during_start_up_is_a_fall(state: RobotState) -> None:
    """Confirmed 2 s later (a blow-up would show its speed by then), dated by the cycle it was first seen."""
    reason, record = _record(state, (0.0, FALL_TILT + 0.05, 0.0), 0.05)
    assert reason == "fell" and record.fell and record.fall is not None
    assert record.fall.startswith("flipped during start-up at 0.03 s"), record.fall
    assert record.max_tilt == 0.0 and record.whole_max_tilt == pytest.approx(FALL_TILT + 0.05)


def test_a_blow_up_after_a_start_up_flip_is_named_diverged() -> None:
    """A reading past MAX_BODY_SPEED within the grace: the run stops as diverged, not fallen."""
    robot = load_robot("bullet").robot
    record = PhysicsRecord(robot, SimpleNamespace(world=SimpleNamespace(physics_time=0.0)),  # type: ignore[arg-type]
                           airborne=False)
    out = SimpleNamespace(robot_state=RobotState.READY)
    flipped = SimpleNamespace(rpy=np.array([FALL_TILT + 0.1, 0.0, 0.0]), body_height=0.1, position=np.zeros(3),
                              linear_velocity=np.zeros(3))
    assert record(5, None, out, flipped) is None  # type: ignore[arg-type]
    fast = SimpleNamespace(rpy=flipped.rpy, body_height=0.1, position=np.zeros(3),
                           linear_velocity=np.array([0.0, 0.0, MAX_BODY_SPEED + 1.0]))
    assert record(30, None, out, fast) == DIVERGED  # type: ignore[arg-type]
    assert not record.fell


def test_a_launch_is_a_fall_and_a_low_body_during_start_up_is_not() -> None:
    """bullet: thrown up past twice its body clearance plus its legs' length; a body still on the ground while
    it starts up (height 0) is the start, not a collapse; while walking it is."""
    robot = load_robot("bullet").robot
    legs = max(sum(math.hypot(j.r, j.d) for j in leg.joints.values()) for leg in robot.legs.values())
    limit = 2.0 * (robot.walker.body_clearance + legs)
    reason, record = _record(RobotState.READY, (0.0, 0.0, 0.0), limit + 0.01)
    assert reason == "fell" and record.fall is not None and record.fall.startswith("thrown up during start-up")
    assert record.high_height == pytest.approx(limit)
    assert _record(RobotState.READY, (0.0, 0.0, 0.0), 0.0)[0] is None
    reason, record = _record(RobotState.RUNNING, (0.0, 0.0, 0.0), 0.0)
    assert reason == "fell" and record.fall is not None and record.fall.startswith("collapsed walking")


def test_a_robot_thrown_up_in_its_start_up_stops_as_fallen_exit_4(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The robot validate refuses, simulated anyway (the check switched off): its knees start in the floor and
    MuJoCo throws it up in its first cycles. Before, falls were checked only while walking: it flew on with
    ``fell: false``. Now the run stops 2 s later (:data:`START_UP_GRACE_S`), says how and when, and exits 4 with
    --fail-on-fall."""
    import shc_cli.validation

    monkeypatch.setattr(shc_cli.validation, "_standing_in_ground", lambda loaded, robot: [])
    out_dir = tmp_path / "run"
    code, out, err = run(["simulate", str(KNEES), "--duration", "2", "--no-plots", "--fail-on-fall",
                          "--out", str(out_dir)], capsys, monkeypatch)
    summary = json.loads((out_dir / "summary.json").read_text())
    assert code == 4, out + err
    assert summary["fell"] is True and summary["stop_reason"] == "fell"
    assert summary["fall"].startswith("thrown up during start-up")
    assert summary["fall"].startswith("thrown up during start-up at 0.09 s")
    assert summary["sim_time_s"] < 3.0  # stopped 2 s after, within its start-up (6 s)
    assert "FELL (thrown up during start-up" in out


def test_no_start_up_of_the_knee_robot_commands_a_joint_faster_than_its_servo() -> None:
    """The speed guard holds in a start-up that must travel far fast: max_vel 1 rad/s and time_to_start 0.3 s
    (OpenSHC's 30 cycles would move the tibias at ~10 rad/s); every cycle moves each joint at most
    max_vel·dt = 0.01 rad."""
    robot = load_robot(KNEES).robot
    legs = {leg_id: leg.model_copy(update={"joints": {name: joint.model_copy(update={"max_vel": 1.0})
                                                       for name, joint in leg.joints.items()}})
            for leg_id, leg in robot.legs.items()}
    quick = robot.model_copy(update={"legs": legs,
                                     "start_up": robot.start_up.model_copy(update={"time_to_start": 0.3})})
    controller = Controller(quick, load_gait("tripod").gait)
    commands = [controller.model.joints.copy()]
    while controller.state != RobotState.RUNNING:
        commands.append(controller.step(Command(state_request=RobotState.RUNNING)).joints.copy())
        assert len(commands) < 5000
    steps = np.abs(np.diff(np.stack(commands), axis=0))
    travel = np.abs(commands[-1] - commands[0]).max()
    assert travel > 0.5  # a real move, not one the limit never touches
    assert steps.max() <= 1.0 * 0.01 + 1e-9
