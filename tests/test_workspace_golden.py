"""Start-up configuration, workspaces, walkspace and limits against the real OpenSHC binary.

Golden data: ``golden/openshc/insectoid_startup_limits.txt`` (the binary's start-up print) and rows of
``insectoid_startup_joints.csv`` (its joint outputs during the direct start-up), Bullet insectoid, tripod.
"""

from __future__ import annotations

import csv
import re

import numpy as np
import pytest

from shc_cli.analysis.workspace import WorkspaceReport, analyse_workspace
from shc_cli.control.startup import joint_transition, plan_direct_startup
from shc_cli.model.chains import Chains
from shc_cli.spec.robot import Robot

from .conftest import GOLDEN

LIMITS_FILE = GOLDEN / "openshc" / "insectoid_startup_limits.txt"


def _fields(line: str) -> dict[str, str]:
    return dict(re.findall(r"(\w+)=(\S+)", line))


def _golden_workspace() -> dict[str, dict[int, float]]:
    out = {}
    for line in LIMITS_FILE.read_text().splitlines():
        if line.startswith("[INSTR_WORKSPACE]"):
            parts = line.split()
            leg = parts[1].split("=")[1]
            out[leg] = {int(b): float(r) for b, r in (p.split(":") for p in parts[3:])}
    return out


def _golden_limits() -> dict[int, dict[str, float]]:
    out = {}
    for line in LIMITS_FILE.read_text().splitlines():
        if line.startswith("[INSTR_LIMITS]"):
            fields = _fields(line)
            out[int(fields["bearing"])] = {k: float(v) for k, v in fields.items() if k != "bearing"}
    return out


def _golden_joints() -> dict[int, np.ndarray]:
    with (GOLDEN / "openshc" / "insectoid_startup_joints.csv").open() as handle:
        rows = list(csv.reader(handle))
    return {int(row[0]): np.array([float(v) for v in row[2:]]).reshape(6, 5) for row in rows[1:]}


@pytest.fixture(scope="module")
def report(bullet: Robot, tripod) -> WorkspaceReport:  # type: ignore[no-untyped-def]
    return analyse_workspace(bullet, tripod)


def test_direct_startup_plan_lands_on_the_recorded_stance_configuration(bullet: Robot) -> None:
    chains = Chains.from_robot(bullet)
    planned = plan_direct_startup(bullet, chains, chains.default_joints())
    np.testing.assert_allclose(planned, _golden_joints()[508], atol=1e-6)  # the recording prints 6 decimals


def test_joint_transition_reproduces_the_recorded_cycles(bullet: Robot) -> None:
    """Cycle 9 is the first transition output (τ = 1/500), cycle 508 the last (τ = 1, exactly the target)."""
    chains = Chains.from_robot(bullet)
    start = chains.default_joints()
    target = plan_direct_startup(bullet, chains, start)
    path = joint_transition(start, target, bullet.start_up.time_to_start, bullet.time_delta)
    golden = _golden_joints()
    assert len(path) == 500
    for cycle in (9, 10, 258, 507, 508):
        np.testing.assert_allclose(path[cycle - 9], golden[cycle], atol=1e-6, err_msg=f"cycle {cycle}")
    np.testing.assert_array_equal(path[-1], target)
    np.testing.assert_array_equal(golden[8], 0.0)


def test_leg_workspaces_match_openshc_within_a_tenth_of_a_millimetre(report: WorkspaceReport) -> None:
    golden = _golden_workspace()
    assert set(golden) == set(report.planes)
    for leg, plane in golden.items():
        for bearing, radius in plane.items():
            assert report.planes[leg][bearing] == pytest.approx(radius, abs=1e-4), f"{leg} {bearing}"
    worst = max(abs(report.planes[leg][b] - r) for leg, plane in golden.items() for b, r in plane.items())
    assert worst < 1e-7  # in fact the search reproduces the binary to its 9 printed decimals


def test_walkspace_and_limits_match_openshc(report: WorkspaceReport) -> None:
    golden = _golden_limits()
    for bearing, expected in golden.items():
        assert report.walkspace[bearing] == pytest.approx(expected["walkspace_radius"], abs=1e-4)
        limit = report.limits.bearings[bearing]
        for ours, theirs in [
            (limit.scaled_radius, "scaled_radius"),
            (limit.linear_speed, "max_linear_speed"),
            (limit.linear_acceleration, "max_linear_acc"),
            (limit.angular_speed, "max_angular_speed"),
            (limit.angular_acceleration, "max_angular_acc"),
        ]:
            assert ours == pytest.approx(expected[theirs], rel=1e-3), f"{bearing} {theirs}"
        assert limit.stance_overshoot == pytest.approx(expected["stance_overshoot"], abs=1e-6)
        assert limit.swing_overshoot == pytest.approx(expected["swing_overshoot"], rel=1e-3)
        assert report.limits.stance_radius == pytest.approx(expected["stance_radius"], rel=1e-9)


def test_step_cycle_matches_openshc(report: WorkspaceReport) -> None:
    line = next(text for text in LIMITS_FILE.read_text().splitlines() if text.startswith("[INSTR_STEP]"))
    fields = _fields(line)
    cycle = report.cycle
    assert cycle.period == int(fields["period"])
    assert (cycle.swing_start, cycle.swing_end) == (int(fields["swing_start"]), int(fields["swing_end"]))
    assert (cycle.swing_period, cycle.stance_period) == (int(fields["swing_period"]), int(fields["stance_period"]))
    assert cycle.frequency == pytest.approx(float(fields["frequency"]), rel=1e-9)
    assert report.limits.time_to_max_stride == pytest.approx(float(fields["time_to_max_stride"]), rel=1e-12)
    assert report.limits.max_stance_extension == int(fields["max_stance_extension"])


def test_every_bundled_robot_has_a_nonempty_symmetric_walkspace() -> None:
    from shc_cli.spec.loading import load_gait, load_robot

    for name in ("bullet_mammalian", "openshc_default", "athena", "quadruped", "octopod"):
        robot = load_robot(name).robot
        gait = load_gait(robot.walker.gait).gait
        result = analyse_workspace(robot, gait)
        assert all(r > 0.0 for r in result.walkspace.values()), name
        assert result.walkspace[360] == result.walkspace[0]
        assert result.limits.bearings[0].linear_speed > 0.0


def test_volumetric_mode_contains_the_flat_plane(bullet: Robot, tripod) -> None:  # type: ignore[no-untyped-def]
    result = analyse_workspace(bullet, tripod, volumetric=True)
    assert result.layers is not None
    for leg, stack in result.layers.items():
        heights = sorted(stack)
        assert heights[0] < 0.0 < heights[-1]
        assert all(r == 0.0 for r in stack[heights[0]].values()) and all(r == 0.0 for r in stack[heights[-1]].values())
        assert len(heights) >= 10
        # The middle layer (height ≈ 0) is the simple-mode plane.
        flat = min(heights, key=abs)
        assert abs(flat) < 1e-9
        for bearing, radius in stack[flat].items():
            assert radius == pytest.approx(result.planes[leg][bearing], abs=1e-6), leg


# openshc-study.md §14A (values printed to 3 decimals; the insectoid rows equal the binary's print).
STUDY_RADII = {
    ("bullet_mammalian", "AR"): (0.298, 0.280, 0.301, 0.353, 0.409, 0.363, 0.313, 0.292),
    ("bullet_mammalian", "BR"): (0.323, 0.432, 0.525, 0.438, 0.284, 0.187, 0.165, 0.207),
    ("bullet_mammalian", "CR"): (0.448, 0.437, 0.364, 0.296, 0.258, 0.260, 0.304, 0.387),
}
STUDY_FORWARD_LIMITS = [  # robot, gait, r, v_max, a_max, ω_max at bearing 0
    ("bullet_mammalian", "bipod", 0.196, 0.445, 0.225, 1.126),
    ("bullet_mammalian", "tripod", 0.196, 0.284, 0.123, 0.718),
    ("openshc_default", "tripod", 0.060, 0.077, 0.030, 0.513),
    ("bullet_openshc", "wave", 0.160, 0.054, 0.009, 0.117),
    ("bullet_openshc", "ripple", 0.160, 0.125, 0.039, 0.271),
    ("bullet_openshc", "amble", 0.160, 0.125, 0.046, 0.272),
    ("bullet_openshc", "bipod", 0.160, 0.364, 0.184, 0.789),
]


@pytest.mark.parametrize(("robot_name", "leg"), list(STUDY_RADII))
def test_mammalian_workspace_matches_the_study(robot_name: str, leg: str) -> None:
    from shc_cli.spec.loading import load_gait, load_robot

    robot = load_robot(robot_name).robot
    gait = load_gait("bipod").gait
    plane = analyse_workspace(robot, gait).planes[leg]
    for bearing, expected in zip(range(0, 360, 45), STUDY_RADII[(robot_name, leg)], strict=True):
        assert plane[bearing] == pytest.approx(expected, abs=6e-4), bearing


@pytest.mark.parametrize(("robot_name", "gait_name", "radius", "speed", "acceleration", "angular"),
                         STUDY_FORWARD_LIMITS)
def test_forward_limits_match_the_study(robot_name: str, gait_name: str, radius: float, speed: float,
                                        acceleration: float, angular: float) -> None:
    from shc_cli.spec.loading import load_gait, load_robot

    robot = load_robot(robot_name).robot
    gait = load_gait(gait_name).gait
    limit = analyse_workspace(robot, gait).limits.bearings[0]
    assert limit.walkspace_radius == pytest.approx(radius, abs=6e-4)
    assert limit.linear_speed == pytest.approx(speed, abs=6e-4)
    assert limit.linear_acceleration == pytest.approx(acceleration, abs=6e-4)
    assert limit.angular_speed == pytest.approx(angular, abs=6e-4)
