"""Speed limits the legs can really walk (issue 42, point 1a; docs/deviations.md "Verified speed limits"): a robot
that sets ``walker.verify_speed_limits`` walks OpenSHC's limits scaled per bearing until trial walks stay off its
joint limits; at any throttle and gait its plan walk then never reaches a position limit and the speed guard never
acts. Robots that do not set it keep OpenSHC's limits to the bit."""

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
from shc_cli.analysis.workspace import analyse_workspace
from shc_cli.control import verified_limits
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.limits import generate_limits
from shc_cli.control.verified_limits import SpeedShares, verified_shares
from shc_cli.record.summary import RunSummary
from shc_cli.spec.loading import bundled, load_gait, load_robot

from .test_cli import run


def _keeps_verified_tables(name: str) -> bool:
    """The robot's file keeps speed-share tables made for it (a robot that extends one inherits tables made for
    another name: they do not apply)."""
    robot = load_robot(name).robot
    return any(verified_limits.stored_shares(robot, load_gait(gait).gait) != verified_limits.UNCHANGED
               for gait in robot.walker.speed_shares)


VERIFYING = [name for name in bundled("robots") if load_robot(name).robot.walker.verify_speed_limits
             or _keeps_verified_tables(name)]
"""The bundled robots that verify their speed limits (by trials at run time, or by the tables their file keeps)."""
HEXAPOD_GAITS = ("tripod", "wave", "ripple", "amble", "bipod")
WALK_CYCLES = 2500
"""25 s at bullet's 10 ms: its tripod drifted onto the roll limit after ≈ 15 s at 0.6 of OpenSHC's limit."""


@cache
def running(robot_name: str, gait_name: str) -> Controller:
    """A controller of the robot and gait through its start-up to RUNNING."""
    robot = load_robot(robot_name).robot
    controller = Controller(robot, load_gait(gait_name).gait, speed_shares=verified_limits.source_for(robot))
    for _ in range(5000):
        if controller.state == RobotState.RUNNING:
            return controller
        controller.step(Command(state_request=RobotState.RUNNING))
    raise AssertionError(f"{robot_name} / {gait_name}: no RUNNING")


def test_the_default_robot_walks_verified_limits_and_the_paper_robots_openshcs() -> None:
    """The default bullet keeps verified shares for every hexapod gait in its file, bullet_verified runs the trials;
    the paper's robots (which extend bullet under another name) and OpenSHC's own files walk OpenSHC's limits."""
    assert {"bullet", "bullet_verified"} <= set(VERIFYING)
    bullet = load_robot("bullet").robot
    assert set(bullet.walker.speed_shares) == set(HEXAPOD_GAITS)
    for gait in HEXAPOD_GAITS:
        assert verified_limits.source_for(bullet)(load_gait(gait).gait).reduced  # type: ignore[misc]
    for name in ("bullet_insectoid_a", "bullet_mammalian_a", "bullet_openshc", "bullet_mammalian", "openshc_default"):
        robot = load_robot(name).robot
        source = verified_limits.source_for(robot)
        assert source is None or all(source(load_gait(g).gait) == verified_limits.UNCHANGED for g in HEXAPOD_GAITS)


def test_the_default_robots_tables_were_verified_for_its_legs_and_gaits() -> None:
    """Each stored table's fingerprint is that of bullet's legs, IK and the gait file as they are now: an edit of
    either without new trials fails here (run docs/experiments/verify_speed_limits.py and paste its tables)."""
    bullet = load_robot("bullet").robot
    for gait, entry in bullet.walker.speed_shares.items():
        assert entry.fingerprint == verified_limits.fingerprint(bullet, load_gait(gait).gait), gait


def test_stored_shares_apply_only_to_the_robot_and_gait_they_were_verified_for() -> None:
    """A table whose fingerprint matches gives its shares (bearing 360 repeats 0); another fingerprint, another gait
    or a robot that extends it under another name: OpenSHC's limits."""
    from shc_cli.spec.robot import StoredShares

    bullet, tripod = load_robot("bullet").robot, load_gait("tripod").gait
    entry = StoredShares(linear={"0": 0.5, "90": 0.25}, turn=0.75,
                         fingerprint=verified_limits.fingerprint(bullet, tripod))
    robot = bullet.model_copy(update={"walker": bullet.walker.model_copy(update={"speed_shares": {"tripod": entry}})})
    assert verified_limits.stored_shares(robot, tripod) == SpeedShares({0: 0.5, 90: 0.25, 360: 0.5}, 0.75)
    assert verified_limits.stored_shares(robot, load_gait("wave").gait) == verified_limits.UNCHANGED
    renamed = robot.model_copy(update={"name": "my_bullet"})
    assert verified_limits.stored_shares(renamed, tripod) == verified_limits.UNCHANGED
    stale = entry.model_copy(update={"fingerprint": "0" * 16})
    robot = bullet.model_copy(update={"walker": bullet.walker.model_copy(update={"speed_shares": {"tripod": stale}})})
    assert verified_limits.stored_shares(robot, tripod) == verified_limits.UNCHANGED


@pytest.mark.slow
@pytest.mark.parametrize("gait", HEXAPOD_GAITS)
def test_the_default_robots_stored_shares_pass_the_trials(gait: str) -> None:
    """Every trial direction (three per walkspace bearing, turning both ways) walks 25 step cycles at bullet's stored
    shares without an IK miss, a clamp, a guarded joint speed or a joint within 5 % of its range of a limit."""
    bullet = load_robot("bullet").robot
    shares = verified_limits.stored_shares(bullet, load_gait(gait).gait)
    assert shares.reduced
    assert verified_limits.failing_directions(bullet, load_gait(gait).gait, shares) == []


@pytest.mark.slow
@settings(max_examples=12, deadline=None)
@given(robot=st.sampled_from(VERIFYING), gait=st.sampled_from(HEXAPOD_GAITS), vx=st.floats(-1.0, 1.0),
       vy=st.floats(-1.0, 1.0), wz=st.floats(-1.0, 1.0))
def test_a_verifying_robot_walks_clear_of_its_joint_limits_at_any_throttle(robot: str, gait: str, vx: float,
                                                                            vy: float, wz: float) -> None:
    """25 s at any throttle (vx, vy, wz ∈ −1..1) and gait: no joint comes within 1 % of its half range of a position
    limit (limit proximity > 0), the IK never misses or clamps and the speed guard never acts."""
    controller = copy.deepcopy(running(robot, gait))
    chains = controller.model.chains
    half = (chains.upper - chains.lower) / 2.0
    moving = half > 0.0
    closest = np.inf
    for _ in range(WALK_CYCLES):
        out = controller.step(Command(velocity=(vx, vy, wz)))
        assert (out.ik_deviations, out.ik_clamped, out.joint_speed_limited) == (0, 0, 0)
        near = np.minimum(out.joints - chains.lower, chains.upper - out.joints)
        closest = min(closest, float((near[moving] / half[moving]).min()))
    assert closest > 0.01


def test_openshcs_limits_drive_bullet_onto_its_roll_limit() -> None:
    """Why bullet verifies: with OpenSHC's limits (shares of 1) its tripod at full throttle ahead reaches the roll
    joint's limit (−1.396 rad) and the IK deviates within 15 s; with the verified ones it does not (the test above)."""
    robot = load_robot("bullet").robot
    controller = Controller(robot, load_gait("tripod").gait, speed_shares=lambda _: verified_limits.UNCHANGED)
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    deviations, lowest = 0, np.inf
    for _ in range(1500):
        out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
        deviations += out.ik_deviations
        lowest = min(lowest, float(out.joints[:, 1].min()))  # the roll (coxat) joints
    assert deviations > 0
    assert lowest == pytest.approx(-1.396, abs=1e-3)


def test_shares_scale_linear_limits_per_bearing_and_angular_limits_everywhere() -> None:
    """A hand-made share table on bullet's tripod limits: bearing 90° linear × 0.5, every angular × 0.25, the
    other linear limits unchanged."""
    report = analyse_workspace(load_robot("bullet_insectoid_a").robot, load_gait("tripod").gait)
    limits = generate_limits(report.walkspace, report.cycle, 0.01, report.limits.stance_radius)
    scaled = SpeedShares({90: 0.5}, 0.25).apply(limits)
    for bearing, lim in limits.bearings.items():
        new = scaled.bearings[bearing]
        share = 0.5 if bearing == 90 else 1.0
        assert (new.linear_speed, new.linear_acceleration) == (lim.linear_speed * share,
                                                               lim.linear_acceleration * share)
        assert (new.angular_speed, new.angular_acceleration) == (lim.angular_speed * 0.25,
                                                                 lim.angular_acceleration * 0.25)
        assert new.walkspace_radius == lim.walkspace_radius
    assert SpeedShares({90: 0.5, 360: 1.0}, 0.25).reduced == {"90": 0.5, "turn": 0.25}


def test_the_shares_are_cached_per_robot_and_gait(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The first call runs the trials and writes the cache file; a new process (an empty memo) reads it back; a
    changed robot is another key."""
    monkeypatch.setenv("SHC_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(verified_limits, "_memo", {})
    calls: list[str] = []
    fake = SpeedShares({0: 0.5, 360: 0.5}, 0.75)

    def trials(robot: object, gait: object) -> SpeedShares:
        calls.append("trial")
        return fake

    monkeypatch.setattr(verified_limits, "trial_shares", trials)
    robot, gait = load_robot("bullet").robot, load_gait("tripod").gait
    assert verified_shares(robot, gait) == fake
    files = list((tmp_path / "verified-limits").glob("*.json"))
    assert len(files) == 1 and json.loads(files[0].read_text()) == {"linear": {"0": 0.5, "360": 0.5},
                                                                    "angular": 0.75}
    monkeypatch.setattr(verified_limits, "_memo", {})
    assert verified_shares(robot, gait) == fake and calls == ["trial"]
    other = robot.model_copy(update={"walker": robot.walker.model_copy(update={"body_clearance": 0.19})})
    assert verified_shares(other, gait) == fake and calls == ["trial", "trial"]


def test_the_run_line_names_the_kept_share() -> None:
    assert speed_note(RunSummary(speed_limits_verified={})) == ""
    assert speed_note(RunSummary(speed_limits_verified={"90": 0.40625, "0": 0.5625})) == (
        ", speed limits verified (41–56 % of OpenSHC's)")
    assert speed_note(RunSummary(speed_limits_verified={"turn": 0.5})) == ", speed limits verified (50 % of OpenSHC's)"


def test_plan_at_full_throttle_walks_clean_and_records_the_shares(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """`shc plan bullet --duration 20` (the README's walk, full throttle ahead): IK deviations 0, clamped 0, no
    joint speed limited; summary.json records the shares below 1 (every bearing's, from bisection: k/32); the
    OpenSHC robot's summary has no such key."""
    out = tmp_path / "run"
    code, text, err = run(["plan", "bullet", "--duration", "20", "--out", str(out), "--no-plots"], capsys,
                          monkeypatch)
    assert code == 0, err
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    assert (summary["ik_deviation_count"], summary["ik_clamp_count"]) == (0, 0)
    assert summary["joint_speed_limited_cycles"] == 0
    shares = summary["speed_limits_verified"]
    assert set(shares) == {"0", "45", "90", "135", "180", "225", "270", "315", "turn"}
    assert all(0.0 < s < 1.0 and (s * 32).is_integer() for s in shares.values())
    assert "IK deviations 0, clamped 0, speed limits verified (" in text
    other = tmp_path / "openshc"
    code, _, err = run(["plan", "bullet_openshc", "--duration", "1", "--out", str(other), "--no-plots"], capsys,
                       monkeypatch)
    assert code == 0, err
    assert "speed_limits_verified" not in json.loads((other / "summary.json").read_text(encoding="utf-8"))


def test_workspace_shows_openshcs_and_the_verified_speeds(capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """`shc workspace bullet`: OpenSHC's max linear speed (0.2000 m/s ahead, the figure issue 42 quotes) and below
    it the verified one, each bearing's at its verified share of OpenSHC's (the table's rows; --json's numbers)."""
    code, text, err = run(["workspace", "bullet_verified"], capsys, monkeypatch)
    assert code == 0, err
    assert "verified linear speed m/s" in text and "verified angular speed rad/s" in text
    code, text, err = run(["workspace", "bullet_verified", "--json"], capsys, monkeypatch)
    assert code == 0, err
    document = json.loads(text)
    openshc, verified = document["max_linear_speed"], document["verified_max_linear_speed"]
    shares = verified_shares(load_robot("bullet_verified").robot, load_gait("tripod").gait).linear
    assert openshc["0"] == pytest.approx(0.2, abs=1e-4)
    for bearing in range(0, 360, 45):
        assert verified[str(bearing)] == pytest.approx(openshc[str(bearing)] * shares[bearing], rel=1e-12)
        assert verified[str(bearing)] < openshc[str(bearing)]
    code, text, err = run(["workspace", "bullet_openshc", "--json"], capsys, monkeypatch)
    assert code == 0, err
    assert json.loads(text)["verified_max_linear_speed"] is None
