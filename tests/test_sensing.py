"""Sensor-driven posing: IMU PID (study §7.4), inclination (§7.5), ATHENA plane and posture corrections."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control.pose import Pose, euler_from_matrix, rot_x, rot_y
from shc_cli.control.sensing import (
    ImuPoser,
    PostureController,
    inclination_pose,
    plane_normal,
    quaternion_matrix,
    support_centroid_pose,
)


def _quaternion(roll: float, pitch: float, yaw: float = 0.0) -> np.ndarray:
    """(x, y, z, w) of Rz(yaw)·Ry(pitch)·Rx(roll) (the ROS/PyBullet convention)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return np.array([sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
                     cr * cp * cy + sr * sp * sy])


@settings(max_examples=50, deadline=None)
@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(-3, 3))
def test_quaternion_matrix_round_trips_euler(roll: float, pitch: float, yaw: float) -> None:
    assert euler_from_matrix(quaternion_matrix(_quaternion(roll, pitch, yaw))) == pytest.approx((roll, pitch, yaw),
                                                                                             abs=1e-9)


def test_imu_posing_is_a_pid_on_roll_and_pitch() -> None:
    """One step from rest: c = −(k_d·0.15·(−ω) + k_p·e + k_i·e·dt), roll/pitch clamped, yaw = manual yaw."""
    poser = ImuPoser((1.0, 0.01, -0.05), (0.5, 0.5), 0.01)
    pose = poser.update(_quaternion(0.1, -0.2, 0.7), np.array([0.3, -0.4, 0.0]), Pose())
    roll, pitch, yaw = pose.euler()
    expected_roll = -(-0.05 * 0.15 * -0.3 + 1.0 * 0.1 + 0.01 * 0.1 * 0.01)
    expected_pitch = -(-0.05 * 0.15 * 0.4 + 1.0 * -0.2 + 0.01 * -0.2 * 0.01)
    assert (roll, pitch, yaw) == pytest.approx((expected_roll, expected_pitch, 0.0), abs=1e-12)
    big = ImuPoser((10.0, 0.0, 0.0), (0.5, 0.25), 0.01).update(_quaternion(0.3, 0.3), np.zeros(3), Pose())
    assert big.euler()[:2] == pytest.approx((-0.5, -0.25))


def test_inclination_shifts_the_body_uphill() -> None:
    """Study §7.5: x = −h·tan(pitch), y = h·tan(roll), clamped; manual tilt is intended, not corrected."""
    pose = inclination_pose(_quaternion(0.05, 0.1), Pose(), 0.25, (0.5, 0.5))
    np.testing.assert_allclose(pose.position, [-0.25 * math.tan(0.1), 0.25 * math.tan(0.05), 0.0], atol=1e-12)
    manual = Pose(np.zeros(3), rot_y(0.1))
    assert np.abs(inclination_pose(_quaternion(0.0, 0.1), manual, 0.25, (0.5, 0.5)).position).max() < 1e-12
    assert inclination_pose(_quaternion(0.0, 0.6), Pose(), 0.25, (0.05, 0.05)).position[0] == -0.05


def test_support_centroid_puts_the_projected_com_on_the_stance_centroid() -> None:
    tips = np.array([[0.3, -0.2, 0.0], [0.3, 0.2, 0.0], [-0.1, 0.0, 0.0]])
    pose = support_centroid_pose(_quaternion(0.0, 0.0), tips, np.zeros(3), 0.25, (1.0, 1.0))
    np.testing.assert_allclose(pose.position[:2], tips[:, :2].mean(axis=0))
    tilted = support_centroid_pose(_quaternion(0.0, 0.1), tips, np.zeros(3), 0.25, (1.0, 1.0))
    assert tilted.position[0] == pytest.approx(tips[:, 0].mean() - 0.25 * math.tan(0.1))


@settings(max_examples=100, deadline=None)
@given(st.floats(-0.4, 0.4), st.floats(-0.4, 0.4), st.floats(-0.3, 0.3))
def test_plane_normal_of_three_and_of_many_points(a: float, b: float, c: float) -> None:
    """Points on z = a·x + b·y + c: the normal is (−a, −b, 1)/|…| from three and from six (least squares)."""
    xy = np.array([[0.3, -0.3], [0.3, 0.3], [-0.3, 0.0], [0.0, 0.35], [-0.3, -0.3], [0.1, 0.0]])
    points = np.column_stack([xy, a * xy[:, 0] + b * xy[:, 1] + c])
    expected = np.array([-a, -b, 1.0]) / math.sqrt(a * a + b * b + 1.0)
    np.testing.assert_allclose(plane_normal(points[[0, 2, 1]]), expected, atol=1e-12)  # either winding
    np.testing.assert_allclose(plane_normal(points), expected, atol=1e-9)


def _feet(pitch: float = 0.0, roll: float = 0.0, z: float = -0.25) -> np.ndarray:
    """Six feet on a plane tilted by (roll, pitch) seen from the body."""
    xy = np.array([[0.3, -0.3], [0.0, -0.35], [-0.3, -0.3], [-0.3, 0.3], [0.0, 0.35], [0.3, 0.3]])
    flat = np.column_stack([xy, np.full(6, z)])
    return np.asarray(flat @ (rot_y(pitch) @ rot_x(roll)).T)


def test_posture_estimate_is_eq_25_26_and_the_height_error() -> None:
    controller = PostureController(0.8, 0.6, 0.4, 0.25, 100)
    feet = _feet(pitch=0.1, roll=0.05)
    estimate = controller.estimate(feet, np.array([True, False, True, False, True, False]), 0.2)
    assert estimate is not None and estimate.feet == 3
    normal = rot_y(0.1) @ rot_x(0.05) @ np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(estimate.normal, normal, atol=1e-12)
    assert estimate.pitch == pytest.approx(math.atan2(normal[0], normal[2]))
    assert estimate.roll == pytest.approx(math.atan2(normal[1], normal[2]))
    assert estimate.height == pytest.approx(-0.05)
    assert controller.estimate(feet, np.array([True, True, False, False, False, False]), 0.2) is None


def test_random_three_is_seeded_and_least_squares_uses_every_foot() -> None:
    feet = _feet() + np.array([0, 0, 0.01]) * np.arange(6)[:, None] ** 2 / 25  # not coplanar
    contact = np.ones(6, dtype=bool)
    first = [PostureController(1, 1, 1, 0.25, 100, seed=4).estimate(feet, contact, None) for _ in range(2)]
    assert first[0] is not None and first[1] is not None
    np.testing.assert_array_equal(first[0].normal, first[1].normal)
    squares = PostureController(1, 1, 1, 0.25, 100, plane="least_squares").estimate(feet, contact, None)
    assert squares is not None and squares.feet == 6
    np.testing.assert_allclose(squares.normal, plane_normal(feet))


def test_posture_corrections_accumulate_per_cycle_and_blend_over_half_a_cycle() -> None:
    """A sagging body (height 0.2 for 0.25) and a support plane pitched 0.1: after one cycle the targets are
    z += k_z·0.05 and pitch += k_α·0.1, taken in linearly over half a cycle (eq. 31)."""
    period = 10
    controller = PostureController(0.8, 0.6, 0.0, 0.25, period)
    contact = np.array([True, False, True, False, True, False])
    poses = [controller.update(True, _feet(pitch=0.1), contact, 0.2) for _ in range(period + period // 2)]
    assert poses[period - 2].position[2] == 0.0  # nothing before the first whole cycle
    halfway = poses[period - 1 + period // 4]
    assert 0.0 < halfway.position[2] < 0.8 * 0.05
    final = poses[-1]
    assert final.position[2] == pytest.approx(0.8 * 0.05)
    assert final.euler()[1] == pytest.approx(0.6 * math.atan2(*(rot_y(0.1) @ [0, 0, 1.0])[[0, 2]]))
    assert final.euler()[0] == pytest.approx(0.0)
    still = PostureController(0.8, 0.6, 0.0, 0.25, period)
    assert all(still.update(False, _feet(pitch=0.1), contact, 0.2).position[2] == 0.0 for _ in range(3 * period))


def test_touchdown_and_liftoff_have_hysteresis() -> None:
    """Study §8.4: down above the touchdown threshold, up again only below the lift-off threshold."""
    from shc_cli.control.sensing import ContactDetector

    detector = ContactDetector(1, touchdown=0.9, liftoff=0.1)
    states = [bool(detector.update(np.array([force]))[0]) for force in (0.0, 0.5, 0.95, 0.5, 0.1, 0.05, 0.5, 1.0)]
    assert states == [False, False, True, True, True, False, False, True]


def test_quaternion_roll_pitch_is_euler_of_the_matrix_to_the_bit() -> None:
    """The odometry's shortcut gives exactly the roll and pitch of the full matrix (random, near-vertical and
    unnormalised quaternions)."""
    from shc_cli.control.pose import euler_from_matrix
    from shc_cli.control.sensing import quaternion_matrix, quaternion_roll_pitch

    rng = np.random.default_rng(7)
    quaternions = list(rng.normal(size=(5000, 4)))
    quaternions += [q / np.linalg.norm(q) for q in rng.normal(size=(5000, 4))]
    quaternions += [np.array([0.0, np.sin(a / 2), 0.0, np.cos(a / 2)]) for a in np.linspace(-np.pi, np.pi, 101)]
    for q in quaternions:
        roll, pitch, _ = euler_from_matrix(quaternion_matrix(q))
        assert quaternion_roll_pitch(q) == (roll, pitch) or (np.isnan(roll) and np.isnan(pitch))
