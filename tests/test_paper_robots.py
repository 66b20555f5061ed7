"""The OpenSHC paper's robots (robots/bullet_{insectoid,mammalian}_{a,b}.toml): Table I masses, Table III heights,
arrangements A (yaw-roll-pitch-pitch-pitch) and B (pitch-yaw-pitch-pitch-pitch), mirror legs, Table II's figure."""

from __future__ import annotations

import numpy as np
import pytest

from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Robot

from .conftest import ROOT

TABLE_I = {"bullet_insectoid_a": 10.07, "bullet_mammalian_a": 10.07, "bullet_insectoid_b": 11.13,
           "bullet_mammalian_b": 11.13}
"""Mass with battery [kg]."""
TABLE_III = {"bullet_mammalian_a": (0.12, 0.30), "bullet_mammalian_b": (0.08, 0.30), "bullet_insectoid_a": (0.15, 0.20),
             "bullet_insectoid_b": (0.10, 0.25)}
"""Stride height and body height [m]."""


def _robot(name: str) -> Robot:
    robot = load_robot(ROOT / "robots" / f"{name}.toml").robot
    return robot


@pytest.mark.parametrize("name", sorted(TABLE_I))
def test_table_i_mass_and_table_iii_heights(name: str) -> None:
    robot = _robot(name)
    assert robot.total_mass() == pytest.approx(TABLE_I[name], abs=1e-9)
    assert (robot.walker.swing_height.default, robot.walker.body_clearance) == TABLE_III[name]
    assert robot.walker.step_frequency.default == 1.0  # walk air at 1 Hz (§VIII)
    assert robot.servo.control == "dynamixel"


def _axes(robot: Robot) -> np.ndarray:
    """Joint axes (z of the frame each joint turns about) of the front right leg at joint angles 0, in base_link."""
    chains = Chains.from_robot(robot)
    frames = chains.frames_in_base(np.zeros((1, chains.size, chains.joints)))[0, 0]
    return np.asarray(frames[:-1, :3, 2])


def test_arrangement_a_is_yaw_roll_pitch_pitch_pitch_with_340_mm_legs() -> None:
    robot = _robot("bullet_insectoid_a")
    axes = np.abs(_axes(robot))
    assert np.allclose(axes[0], [0, 0, 1], atol=1e-3)  # coxa yaw: vertical
    assert np.allclose(axes[1], [0, 1, 0], atol=1e-3)  # coxa roll: along the leg (straight out, -y)
    for k in (2, 3, 4):  # femur, tibia, tarsus: pitch, parallel to x
        assert np.allclose(axes[k], [1, 0, 0], atol=1e-3)
    leg = robot.legs["AR"]
    length = sum(abs(j.d) + abs(j.r) for j in leg.joints.values())
    assert length == pytest.approx(0.340)


def test_arrangement_b_is_pitch_yaw_pitch_pitch_pitch() -> None:
    axes = np.abs(_axes(_robot("bullet_insectoid_b")))
    assert np.allclose(axes[0], [0, 1, 0], atol=1e-3)  # coxa pitch
    assert np.allclose(axes[1], [0, 0, 1], atol=1e-3)  # coxa yaw
    for k in (2, 3, 4):
        assert np.allclose(axes[k], [1, 0, 0], atol=1e-3)


@pytest.mark.parametrize("name", ["bullet_insectoid_a", "bullet_mammalian_a"])
def test_left_legs_mirror_the_right_legs(name: str) -> None:
    """At mirrored joint angles (coxa and coxat negated, the pitch joints keep their sense) a left tip is the right
    tip reflected through the x-z plane."""
    robot = _robot(name)
    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(3)
    q = rng.uniform(-0.05, 0.05, (chains.size, chains.joints)) + np.array([0.0, 0.0, 0.4, 0.6, 0.4])
    legs = list(robot.legs)
    for right, left in (("AR", "AL"), ("BR", "BL"), ("CR", "CL")):
        q[legs.index(left)] = q[legs.index(right)] * np.array([-1, -1, 1, 1, 1])
    tips = chains.tips(q)
    for right, left in (("AR", "AL"), ("BR", "BL"), ("CR", "CL")):
        reflected = tips[legs.index(right)] * np.array([1, -1, 1])
        assert np.allclose(tips[legs.index(left)], reflected, atol=1e-5)  # the files' DH angles have 4 decimals


def test_the_mammalian_a_legs_point_backwards_with_the_yaw_locked() -> None:
    robot = _robot("bullet_mammalian_a")
    axes = _axes(robot)
    assert np.allclose(axes[1], [-1, 0, 0], atol=1e-3)  # roll axis backwards
    for leg in robot.legs.values():
        assert leg.joints["coxa"].max - leg.joints["coxa"].min <= 0.2 + 1e-9


TABLE_II = {"bullet_insectoid_a": (0.046, 0.287), "bullet_insectoid_b": (0.060, 0.348),
            "bullet_mammalian_a": (0.049, 0.207), "bullet_mammalian_b": (0.063, 0.210)}
"""The paper's Table II: walkspace area [m²] and stride length [m] (docs/experiments/openshc-cot.md: our reading)."""


@pytest.mark.parametrize("name", sorted(TABLE_II))
def test_table_ii_rows_within_10_percent(name: str) -> None:
    from shc_cli.analysis.workspace import analyse_workspace
    from shc_cli.spec.loading import load_gait

    robot = _robot(name)
    gait = load_gait(robot.walker.gait).gait
    report = analyse_workspace(robot, gait)
    area, stride = TABLE_II[name]
    assert report.walkspace_area() == pytest.approx(area, rel=0.10)
    assert report.walkspace_stride() == pytest.approx(stride, rel=0.10)


def test_athena_paper_stands_in_the_papers_posture() -> None:
    """§5.1, eq. 12 (θ2 = 0, θ3 = 0, θ4 = −π/2): feet l2 + l3 = 0.144 m out from the TC joint, l4 = 0.104 m below it;
    the controller at 20 Hz."""
    robot = _robot("athena_paper")
    assert robot.time_delta == 0.05 and robot.walker.body_clearance == 0.104
    chains = Chains.from_robot(robot)
    q = np.tile([0.0, 0.0, -np.pi / 2], (chains.size, 1))
    tips = chains.tips(q)
    for i, leg in enumerate(robot.legs.values()):
        assert tips[i][:2] == pytest.approx([leg.stance.x, leg.stance.y], abs=2e-4)
        assert tips[i][2] == pytest.approx(-0.104, abs=1e-9)
