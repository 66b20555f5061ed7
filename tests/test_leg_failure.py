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
    """Two computations of one number: the planner's linear programme and convex hulls (SciPy's Qhull)."""
    adapted = adapt(BULLET, parse_failures(["BR"], LEGS))
    planned = adapted.planned
    assert margin_at(planned, planned.body_shift_m[0], adapted.stride_m) == pytest.approx(planned.margin_m, abs=1e-9)
    assert margin_at(planned, adapted.failure.shift, adapted.stride_m) >= 0.02 - 1e-6
    assert np.linalg.norm(adapted.failure.shift) <= np.linalg.norm(planned.body_shift_m[0]) + 1e-12


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
def test_two_opposite_failed_legs_are_refused_in_one_line_until_the_body_sways() -> None:
    """S2 (AL and CR): four legs left, no table keeps the margin with one constant shift (a crawl needs sway)."""
    with pytest.raises(SpecError) as raised:
        adapt(BULLET, parse_failures(["AL,CR"], LEGS))
    assert str(raised.value) == (
        "--fail-leg: 'AL:retracted,CR:retracted': no generated gait keeps a 0.02 m static margin on legs AR, BR, CL, "
        "BL with one constant body shift, down to 0.25 of their stride (fail fewer legs: a body swaying through the "
        "cycle is not applied yet)")
