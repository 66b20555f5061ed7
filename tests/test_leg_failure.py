"""Failed legs declared from the start (shc_cli/control/leg_failure.py, issue 39): the option, the held pose, the
re-planned gait and walking on the legs left."""

from __future__ import annotations

import csv
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control.leg_failure import FailedLeg, adapt, margin_at, parse_failures, retracted_pose
from shc_cli.errors import SpecError
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot

BULLET = load_robot("bullet").robot
LEGS = list(BULLET.legs)
CHAINS = Chains.from_robot(BULLET)


def test_a_failure_is_a_leg_and_a_mode_retracted_by_default() -> None:
    assert parse_failures(["AR", "BL:locked"], LEGS) == (FailedLeg("AR", "retracted"), FailedLeg("BL", "locked"))
    assert parse_failures(["AR,CL:retracted"], LEGS) == (FailedLeg("AR"), FailedLeg("CL"))


@pytest.mark.parametrize(("spec", "message"), [
    ("XX", "--fail-leg: 'XX': no leg 'XX' on this robot (give one of AR, BR, CR, CL, BL, AL)"),
    ("AR:limp", "--fail-leg: 'AR:limp': unknown mode 'limp' (give AR:retracted or AR:locked)"),
    ("AR,AR", "--fail-leg: 'AR': leg AR is failed twice (give each leg once)"),
    ("AR,BR,CR,CL", "2 leg(s) left (a statically stable gait needs at least three: fail fewer legs)"),
])
def test_a_bad_failure_is_one_line(spec: str, message: str) -> None:
    with pytest.raises(SpecError) as raised:
        parse_failures([spec], LEGS)
    assert str(raised.value).endswith(message) and "\n" not in str(raised.value)


@pytest.mark.parametrize("command", ["simulate", "plan"])
def test_the_command_line_refuses_a_bad_failure_in_one_line_with_exit_2(
        command: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    from shc_cli.cli import main

    monkeypatch.setattr(sys, "argv", ["shc", command, "--out", str(tmp_path / "run"), "--fail-leg", "AR:broken"])
    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 2 and err == "error: --fail-leg: 'AR:broken': unknown mode 'broken' (give " \
        "AR:retracted or AR:locked)\n", err
    assert not (tmp_path / "run").exists()


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 5), st.lists(st.floats(0.0, 1.0), min_size=5, max_size=5))
def test_the_retracted_pose_is_within_the_limits_and_lifts_the_tip_above_any_other_pose(
        leg: int, shares: list[float]) -> None:
    """Joint 0 at 0, every joint within its limits, and no pose with joint 0 at 0 puts the tip higher (beyond the
    grid's resolution: one grid step of the other joints moves the tip by at most a few cm)."""
    pose = retracted_pose(CHAINS, leg)
    lower, upper = CHAINS.lower[leg], CHAINS.upper[leg]
    assert pose[0] == pytest.approx(min(max(0.0, lower[0]), upper[0]))
    assert np.all(pose >= lower - 1e-12) and np.all(pose <= upper + 1e-12)
    other = lower + np.array(shares) * (upper - lower)
    other[0] = pose[0]
    chains = CHAINS.take(np.array([leg, leg], dtype=np.int64))
    tips = chains.tips(np.stack([pose, other]))
    assert tips[0, 2] >= tips[1, 2] - 0.03
    assert tips[0, 2] > chains.tips(np.stack([CHAINS.default_joints()[leg]] * 2))[0, 2]


def test_the_margin_at_the_planners_shift_is_the_planners_margin() -> None:
    """Two computations of one number: the planner's linear programme and convex hulls (SciPy's Qhull); one failed
    leg's body shift is one constant shift (a steadier walk than a sway) that keeps the margin."""
    adapted = adapt(BULLET, parse_failures(["BR"], LEGS))
    planned = adapted.planned
    assert margin_at(planned, planned.body_shift_m[0], adapted.stride_m) == pytest.approx(planned.margin_m, abs=1e-9)
    sway = adapted.failure.sway
    assert np.ptp(sway, axis=0).max() <= 1e-9
    assert margin_at(planned, sway[0], adapted.stride_m) >= 0.02 - 1e-6
    assert margin_at(planned, sway[0], 0.0) >= 0.02 - 1e-6  # the walker's stride ramps up from none


def test_the_body_follows_the_sway_at_the_walkers_phase() -> None:
    """S2 (AL, CR): the controller's body shift is the sway at the walker's phase once caught up (the phase read
    back from the walker's integers through the generated table's timing)."""
    from shc_cli.control import stepping
    from shc_cli.control.controller import Command, Controller, RobotState
    from shc_cli.control.gait_planner import sway_at
    from shc_cli.control.leg_failure import walk_phase

    adapted = adapt(BULLET, parse_failures(["AL,CR"], LEGS))
    sway = adapted.failure.sway
    assert np.ptp(sway, axis=0).max() > 0.02  # a sway, not a shift
    controller = Controller(adapted.robot, adapted.gait, failure=adapted.failure)
    groups = adapted.planned.groups
    swing = adapted.gait.swing_phase * len(groups) / adapted.gait.base_length
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    errors = []
    for cycle in range(3000):
        out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
        phase = walk_phase(controller.walker)
        if cycle > 1500 and phase is not None:
            errors.append(np.abs(adapted.failure.shift - sway_at(sway, phase)).max())
            t = phase * len(groups)  # the planner's time: group j lifts off at t = j, swings for `swing`
            for j, group in enumerate(groups):
                into = (t - j) % len(groups)
                if min(into, abs(into - swing), len(groups) - into) > 0.02:  # clear of the switching instants
                    walker = controller.walker
                    assert walker is not None
                    for leg in group:
                        state = walker.legs.integers[LEGS.index(leg), stepping.STATE]
                        assert (state == stepping.SWING) == (into < swing), (cycle, leg, t)
    assert out is not None and len(errors) > 1000
    assert max(errors) < 0.005


def test_one_failed_leg_gets_a_generated_gait_without_it_and_the_walking_legs_walkspace() -> None:
    adapted = adapt(BULLET, parse_failures(["BR"], LEGS))
    groups = adapted.planned.groups
    assert sorted(leg for group in groups for leg in group) == sorted(set(LEGS) - {"BR"})
    assert adapted.gait.name == "planned" and set(adapted.gait.offset_multiplier) == set(LEGS)
    assert adapted.planned.duty_factor == pytest.approx(0.6)  # the five-group wave (test_gait_planner: S1 β 0.6)
    planes = {leg: {0: 1.0} for leg in LEGS}
    assert set(adapted.failure.walking(planes)) == set(LEGS) - {"BR"}


def _commanded(run: Path, leg: str, after_cycle: int) -> np.ndarray:
    """A leg's commanded joints after ``after_cycle`` (``shc plan``'s joints.csv), ``(cycles, n)`` [rad]."""
    with (run / "joints.csv").open() as file:
        rows = list(csv.DictReader(file))
    names = [name for name in rows[0] if name.startswith(f"{leg}_")]
    return np.array([[float(row[name]) for name in names] for row in rows if int(row["cycle"]) > after_cycle])


@pytest.mark.parametrize("mode", ["retracted", "locked"])
def test_a_failed_legs_joints_are_still_once_walking_and_the_generated_gait_is_used(
        mode: str, tmp_path: Path) -> None:
    from shc_cli import api

    run = api.plan("bullet", duration=4.0, out=tmp_path / "run", plots=False, fail_leg=f"BR:{mode}")
    summary = json.loads((run.path / "summary.json").read_text())
    assert summary["gait"] == "planned"
    events = [json.loads(line) for line in (run.path / "events.log").read_text().splitlines()]
    running = next(e["cycle"] for e in events if e["message"].endswith("READY → RUNNING"))
    held = _commanded(run.path, "BR", running + 1)
    assert len(held) > 300 and np.ptp(held, axis=0).max() == 0.0
    walking = _commanded(run.path, "AR", running + 1)
    assert np.ptp(walking, axis=0).max() > 0.1  # the others walk
    if mode == "retracted":
        assert held[0] == pytest.approx(retracted_pose(CHAINS, LEGS.index("BR"))[:held.shape[1]])


@pytest.mark.slow
@pytest.mark.parametrize("leg", LEGS)
def test_one_retracted_leg_walks_on_without_a_fall_in_mujoco(leg: str, tmp_path: Path) -> None:
    from shc_cli import api

    run = api.simulate("bullet", duration=20.0, out=tmp_path / "run", plots=False, fail_leg=leg)
    summary = json.loads((run.path / "summary.json").read_text())
    assert not summary["fell"] and summary["max_tilt_rad"] < 0.6
    assert summary["forward_distance_m"] > 0.5  # intact: 3.4 m in 20 s
    assert math.isfinite(summary["displacement_speed_mps"])


@pytest.mark.slow
@pytest.mark.parametrize("legs", ["AL,CR", "BL,BR", "CL,AR"])
def test_two_opposite_retracted_legs_walk_on_a_swaying_crawl_without_a_fall(legs: str, tmp_path: Path) -> None:
    """S2: four legs left, no constant shift holds; the body sways through the crawl (measured 0.039–0.049 m/s
    forward on 20 s, tilt ≤ 0.31 rad)."""
    from shc_cli import api

    run = api.simulate("bullet", duration=20.0, out=tmp_path / "run", plots=False, fail_leg=legs)
    summary = json.loads((run.path / "summary.json").read_text())
    assert summary["duty_factor"] == pytest.approx(0.75)
    assert not summary["fell"] and summary["max_tilt_rad"] < 0.6
    assert summary["forward_distance_m"] > 0.5


@pytest.mark.slow
def test_two_failed_legs_on_one_side_are_refused_in_one_line() -> None:
    """S3 (AL and CL): the left side keeps BL alone; while it swings the robot stands on the three right feet in a
    line, which no stance move and sway within the legs' reach make an area of (the planner needs a 0.37 m
    shift: tests/test_gait_planner.py)."""
    with pytest.raises(SpecError) as raised:
        adapt(BULLET, parse_failures(["AL,CL"], LEGS))
    assert str(raised.value) == (
        "--fail-leg: 'AL:retracted,CL:retracted': no generated gait and body sway keep a 0.02 m static margin on "
        "legs AR, BR, CR, BL, down to 0.25 of their stride (fail fewer legs)")
