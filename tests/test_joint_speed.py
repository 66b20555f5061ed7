"""No control cycle commands a joint faster than its ``max_vel`` (issue 42, point 1): the IK's velocity clamp as
OpenSHC's ``clamp_joint_velocities`` and shc's per-cycle guard behind it (docs/deviations.md), for every bundled
robot, gait and throttle, start-up included; how often it had to limit, in summary.json and the printed line."""

from __future__ import annotations

import copy
import json
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.analysis.run_line import speed_note
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.speed_guard import SpeedGuard
from shc_cli.control.verified_limits import source_for
from shc_cli.model.chains import Chains
from shc_cli.record.summary import RunSummary
from shc_cli.spec.loading import bundled, load_gait, load_robot
from shc_cli.spec.robot import Robot

from .conftest import ROOT
from .test_cli import run

ROBOTS = bundled("robots")
GAITS = {4: ("quad_wave", "trot", "amble"), 6: ("tripod", "wave", "ripple", "amble", "bipod"),
         8: ("octo_alternating", "octo_wave")}
"""The gaits tried per leg count."""
WALK_CYCLES = 300
TOLERANCE = 1e-9
"""Rounding allowed above max_vel·dt [rad] (the guard's own is 1e-12)."""


def speed_limits(robot: Robot) -> np.ndarray:
    """Each joint's max_vel·dt [rad], ``(L, n)``, read from the robot file's joints (padded with inf)."""
    legs = list(robot.legs.values())
    width = max(len(leg.joints) for leg in legs)
    out = np.full((len(legs), width), np.inf)
    for i, leg in enumerate(legs):
        for k, joint in enumerate(leg.joints.values()):
            out[i, k] = joint.max_vel * robot.time_delta
    return out


def fastest(steps: list[np.ndarray], bound: np.ndarray) -> float:
    """The largest per-cycle joint motion as a share of its max_vel·dt over consecutive commands."""
    q = np.stack(steps)
    return float((np.abs(np.diff(q, axis=0)) / bound).max())


@cache
def started(robot_name: str, gait_name: str) -> tuple[Controller, float]:
    """A controller through its start-up to RUNNING, and the start-up's fastest joint motion (share of the limit)."""
    robot = load_robot(robot_name).robot
    controller = Controller(robot, load_gait(gait_name).gait, speed_shares=source_for(robot))
    commands = [controller.model.joints.copy()]
    while controller.state != RobotState.RUNNING:
        commands.append(controller.step(Command(state_request=RobotState.RUNNING)).joints.copy())
        assert len(commands) < 5000, "no RUNNING"
    return controller, fastest(commands, speed_limits(robot))


@settings(max_examples=40, deadline=None)
@given(robot=st.sampled_from(ROBOTS), pick=st.integers(0, 4), vx=st.floats(-1.0, 1.0), vy=st.floats(-1.0, 1.0),
       wz=st.floats(-1.0, 1.0))
def test_no_cycle_commands_a_joint_beyond_its_speed_limit(robot: str, pick: int, vx: float, vy: float,
                                                          wz: float) -> None:
    """Every bundled robot, a gait for its legs, any throttle: start-up and walk, no commanded joint moves faster
    than its max_vel (from the robot file) in any cycle."""
    legs = len(load_robot(robot).robot.legs)
    gait = GAITS[legs][pick % len(GAITS[legs])]
    ready, startup = started(robot, gait)
    assert startup <= 1.0 + TOLERANCE, f"{robot} start-up: {startup:.3f} × max_vel"
    controller = copy.deepcopy(ready)
    bound = speed_limits(controller.robot)
    commands = [controller.model.joints.copy()]
    for _ in range(WALK_CYCLES):
        commands.append(controller.step(Command(velocity=(vx, vy, wz))).joints.copy())
    assert fastest(commands, bound) <= 1.0 + TOLERANCE


def test_a_short_time_to_start_takes_longer_rather_than_faster_than_the_servos() -> None:
    """OpenSHC's direct start-up moves the joints in time_to_start whatever the distance; with 0.2 s the cubic
    transition (10 cycles of 20 ms) would move openshc_default's fastest joint at 2.14 × max_vel. shc
    stretches it to the cycles the servos need (1.5·|Δq|/(max_vel·dt), docs/deviations.md)."""
    robot = load_robot(ROOT / "robots" / "openshc_default.toml").robot
    quick = robot.model_copy(update={"start_up": robot.start_up.model_copy(update={"time_to_start": 0.2})})
    controller = Controller(quick, load_gait("tripod").gait)
    commands = [controller.model.joints.copy()]
    while controller.state != RobotState.READY:
        commands.append(controller.step(Command(state_request=RobotState.READY)).joints.copy())
    bound = speed_limits(quick)
    travel = np.abs(commands[-1] - commands[0])
    needed = int(np.ceil((1.5 * travel / bound).max()))
    assert needed == 22  # 1.5 × 1.4285 rad / (5 rad/s × 0.02 s) = 21.4; OpenSHC's 10 cycles would be too fast
    assert len(commands) - 2 == needed  # the UNKNOWN → PACKED cycle, then the transition
    assert fastest(commands, bound) <= 1.0 + TOLERANCE
    assert controller.joint_speed_limited_cycles == 0  # planned within the limit, never cut by the guard


def test_the_guard_stops_a_joint_at_max_vel_dt_and_moves_the_tips_with_it() -> None:
    """A command 1 rad away is cut to max_vel·dt with velocity max_vel (hand-computed: 5 rad/s × 0.01 s = 0.05 rad);
    the tips are the FK of the limited joints; a command within the bound passes unchanged."""
    robot = load_robot(ROOT / "robots" / "bullet_openshc.toml").robot
    chains = Chains.from_robot(robot)
    guard = SpeedGuard(chains, 0.01)
    before = chains.default_joints()
    wanted = before.copy()
    wanted[1, 2] += 1.0
    wanted[4, 0] -= 0.03
    limited = guard.apply(before, wanted, np.zeros_like(wanted))
    assert limited is not None
    joints, velocities, tips = limited
    assert joints[1, 2] == pytest.approx(before[1, 2] + 0.05, abs=1e-15)
    assert velocities[1, 2] == pytest.approx(5.0)
    assert joints[4, 0] == wanted[4, 0]  # 0.03 rad: within 0.05
    np.testing.assert_allclose(tips, chains.tips(joints))
    assert guard.limited.tolist() == [0, 1, 0, 0, 0, 0]
    assert guard.apply(before, before + 0.04, np.zeros_like(before)) is None


def test_speed_note_names_the_limited_cycles_and_their_share() -> None:
    assert speed_note(RunSummary(joint_speed_limited_cycles=0, joint_speed_limited_share=0.0)) == ""
    assert speed_note(RunSummary()) == ""
    note = speed_note(RunSummary(joint_speed_limited_cycles=257, joint_speed_limited_share=257 / 2502))
    assert note == ", joint speed limited in 257 cycles (10.3 %)"


def test_plan_reports_the_limited_cycles_in_summary_and_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """quadruped at full throttle ahead (5 rad/s joints): the IK's velocity clamp holds joints in some cycles; the
    summary counts them and the printed line says so."""
    out = tmp_path / "run"
    code, text, err = run(["plan", "quadruped", "--velocity", "1,0,0", "--duration", "4", "--out", str(out),
                           "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    cycles = summary["joint_speed_limited_cycles"]
    assert 0 < cycles < summary["cycles"]
    assert summary["joint_speed_limited_share"] == pytest.approx(cycles / summary["cycles"])
    assert f"joint speed limited in {cycles} cycles" in text


@pytest.mark.parametrize(("gait", "velocity"), [("tripod", (1.0, 0.0, 0.0)), ("tripod", (0.0, 0.0, 1.0)),
                                                ("bipod", (1.0, 0.0, 0.0)), ("wave", (1.0, 0.0, 0.0)),
                                                ("amble", (1.0, 0.0, 0.0))])
def test_the_verified_bullet_walks_clear_of_its_joint_limits_at_full_throttle(
        gait: str, velocity: tuple[float, float, float]) -> None:
    """bullet_verified (the default bullet, arrangement A, walking its verified limits), 15 s at full throttle: no
    joint reaches its position limit, the IK never misses its target by 5 mm and no joint's speed is limited. With
    OpenSHC's limits bullet's folded legs' roll joints drift onto −1.396 rad above ≈ 0.6 throttle (tripod)
    (tests/test_verified_limits.py, docs/deviations.md)."""
    ready, _ = started("bullet_verified", gait)
    controller = copy.deepcopy(ready)
    lower, upper = controller.model.chains.lower, controller.model.chains.upper
    margin = np.inf
    for _ in range(1500):
        out = controller.step(Command(velocity=velocity))
        assert out.ik_deviations == 0 and out.ik_clamped == 0 and out.joint_speed_limited == 0
        margin = min(margin, float(np.minimum(out.joints - lower, upper - out.joints).min()))
    assert margin > 0.1  # rad: the closest any joint came to a limit


def test_simulate_commands_every_joint_within_its_speed_limit(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """The README's walk in MuJoCo (bullet, full throttle; 3 s after start-up): log.csv's commanded joints never move
    faster than max_vel (5 rad/s, robots/bullet.toml) (before issue 42: BR_coxat_cmd jumped −1.396 → −0.584 rad in
    one 10 ms cycle, 257 of 2501 cycles above 5 rad/s in 20 s)."""
    import csv

    out = tmp_path / "walk"
    code, text, err = run(["simulate", "--duration", "3", "--out", str(out), "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    with (out / "log.csv").open(encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    columns = [c for c in rows[0] if c.endswith("_cmd")]
    assert len(columns) == 30
    q = np.array([[float(row[c]) for c in columns] for row in rows])
    assert len(q) > 700
    assert np.abs(np.diff(q, axis=0)).max() <= 5.0 * 0.01 + 1e-5  # log.csv keeps 6 significant digits: ±5e-6 rad
    limited = summary["joint_speed_limited_cycles"]
    assert summary["joint_speed_limited_share"] == pytest.approx(limited / len(rows))
    assert ("joint speed limited in" in text) == (limited > 0)
