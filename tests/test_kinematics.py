"""DH forward kinematics, Jacobians and the OpenSHC IK step (paper eq. 1–15, study §1–§2)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.model.chains import Chains, dh_matrix
from shc_cli.model.ik import IK_TOLERANCE, ik_step, solve
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Robot

ROBOTS = ["bullet", "bullet_mammalian", "openshc_default", "athena", "quadruped", "octopod"]
CHAINS = {name: Chains.from_robot(load_robot(name).robot) for name in ROBOTS}


def test_bullet_tips_at_zero_joints_match_the_study(bullet: Robot) -> None:
    """Study §11.3: right legs' tip at q = 0 is (x_b − 0.047, −0.631, −0.009); left legs mirror it."""
    tips = Chains.from_robot(bullet).tips(np.zeros((6, 5)))
    x_b = {"AR": 0.25, "BR": 0.0, "CR": -0.25, "CL": -0.25, "BL": 0.0, "AL": 0.25}
    for i, leg in enumerate(bullet.legs):
        side = -1.0 if leg.endswith("R") else 1.0
        np.testing.assert_allclose(tips[i], [x_b[leg] - 0.047, side * 0.631, -0.009], atol=1e-3)


def test_bullet_unpacked_tip_matches_the_study(bullet: Robot) -> None:
    """Study §11.3: the unpacked tip of a right leg is at (x_b − 0.047, −0.500, −0.006)."""
    chains = Chains.from_robot(bullet)
    q = np.array([[j.unpacked for j in leg.joints.values()] for leg in bullet.legs.values()])
    tips = chains.tips(q)
    np.testing.assert_allclose(tips[0], [0.25 - 0.047, -0.500, -0.006], atol=1.5e-3)


def test_dh_matrix_is_the_classical_convention() -> None:
    d, theta, r, alpha = 0.1, 0.3, 0.2, -0.7
    rot_z = np.array([[np.cos(theta), -np.sin(theta), 0, 0], [np.sin(theta), np.cos(theta), 0, 0],
                      [0, 0, 1, 0], [0, 0, 0, 1]])
    trans = np.eye(4)
    trans[2, 3], trans[0, 3] = d, r
    rot_x = np.array([[1, 0, 0, 0], [0, np.cos(alpha), -np.sin(alpha), 0], [0, np.sin(alpha), np.cos(alpha), 0],
                      [0, 0, 0, 1]])
    np.testing.assert_allclose(dh_matrix(np.array(d), np.array(theta), np.array(r), np.array(alpha)),
                               rot_z @ trans @ rot_x, atol=1e-15)


def test_compiled_tips_equal_numpy_frames() -> None:
    chains = CHAINS["bullet"]
    q = np.random.default_rng(1).uniform(chains.lower, chains.upper)
    via_frames = chains.tip_transforms(q)[:, :3, 3]
    np.testing.assert_allclose(chains.tips(q), via_frames, atol=1e-14)


joint_fraction = st.lists(st.floats(0.0, 1.0), min_size=6 * 8, max_size=6 * 8)


def _within_limits(chains: Chains, fractions: list[float]) -> np.ndarray:
    f = np.array(fractions[: chains.size * chains.joints]).reshape(chains.size, chains.joints)
    return chains.lower + f * (chains.upper - chains.lower)


@pytest.mark.parametrize("name", ROBOTS)
@settings(max_examples=25, deadline=None)
@given(fractions=joint_fraction)
def test_jacobian_matches_finite_differences(name: str, fractions: list[float]) -> None:
    chains = CHAINS[name]
    q = _within_limits(chains, fractions)
    jac = chains.jacobians(q)
    eps = 1e-7
    rot = chains.base[:, :3, :3]
    for k in range(chains.joints):
        dq = np.zeros_like(q)
        dq[:, k] = eps
        numeric = (chains.tips(q + dq) - chains.tips(q - dq)) / (2 * eps)
        leg_frame = np.einsum("bji,bj->bi", rot, numeric)
        np.testing.assert_allclose(jac[:, :, k], leg_frame, atol=1e-6)


@pytest.mark.parametrize("name", ROBOTS)
@settings(max_examples=20, deadline=None)
@given(fractions=joint_fraction)
def test_ik_recovers_any_reachable_tip(name: str, fractions: list[float]) -> None:
    """FK → IK round trip: a tip produced by joints inside the limits is found again (to 0.1 mm)."""
    chains = CHAINS[name]
    margin = 0.15 * (chains.upper - chains.lower)
    q_true = chains.lower + margin + np.array(fractions[: chains.size * chains.joints]).reshape(
        chains.size, chains.joints) * (chains.upper - chains.lower - 2 * margin)
    targets = chains.tips(q_true)
    start = np.clip(q_true + 0.2, chains.lower, chains.upper)
    q, error = solve(chains, start, targets, tolerance=1e-6, max_steps=600)
    assert np.all(np.isfinite(q))
    assert error.max() < 1e-4
    np.testing.assert_allclose(chains.tips(q), targets, atol=1e-4)


@pytest.mark.parametrize("name", ROBOTS)
@settings(max_examples=30, deadline=None)
@given(fractions=joint_fraction, reach=st.floats(0.0, 3.0), seed=st.integers(0, 2**16))
def test_ik_step_stays_finite_and_within_limits(name: str, fractions: list[float], reach: float, seed: int) -> None:
    """Any target, however far or degenerate, gives finite joints inside the limits."""
    chains = CHAINS[name]
    q = _within_limits(chains, fractions)
    rng = np.random.default_rng(seed)
    target = chains.tips(q) + rng.normal(size=(chains.size, 3)) * reach
    qd = rng.normal(size=q.shape)
    step = ik_step(chains, q, qd, chains.tips(q), target, 0.01, clamp_velocities=True)
    assert np.all(np.isfinite(step.q)) and np.all(np.isfinite(step.tip))
    assert np.all(step.q >= chains.lower) and np.all(step.q <= chains.upper)
    assert np.all(np.abs(step.qd) <= chains.max_vel + 1e-12)
    assert np.all((step.proximity >= 0.0) & (step.proximity <= 1.0))


def test_singular_pose_gives_no_nan() -> None:
    """A fully stretched leg (all pitch joints 0) is singular along the leg; the damped step stays finite."""
    chains = CHAINS["openshc_default"]
    q = np.zeros((chains.size, chains.joints))
    q[:, 2] = chains.upper[:, 2]
    tip = chains.tips(q)
    step = ik_step(chains, q, np.zeros_like(q), tip, tip * 3.0, 0.02)
    assert np.all(np.isfinite(step.q))
    assert not step.ok.any()


def test_clamping_is_reported_and_zeroes_the_proximity() -> None:
    chains = CHAINS["openshc_default"]
    q = chains.upper - 1e-6
    tip = chains.tips(q)
    step = ik_step(chains, q, np.zeros_like(q), tip, tip + np.array([0.0, 0.0, 0.5]), 0.02)
    assert step.position_clamped.any()
    assert np.all(step.q <= chains.upper)
    assert np.all(step.proximity[step.position_clamped] == 0.0)
    assert np.all(step.result[step.position_clamped] == 0.0)


def test_velocity_clamp_limits_joint_speed() -> None:
    chains = CHAINS["openshc_default"]
    q = (chains.lower + chains.upper) / 2
    tip = chains.tips(q)
    step = ik_step(chains, q, np.zeros_like(q), tip, tip + 0.05, 0.02, clamp_velocities=True)
    assert step.velocity_clamped.all()
    assert np.abs(step.qd).max() == pytest.approx(5.0)


def test_deviation_beyond_five_millimetres_fails_the_step() -> None:
    chains = CHAINS["bullet"]
    q = (chains.lower + chains.upper) / 2
    tip = chains.tips(q)
    near = ik_step(chains, q, np.zeros_like(q), tip, tip + 0.001, 0.01)
    far = ik_step(chains, q, np.zeros_like(q), tip, tip + 0.2, 0.01)
    assert near.ok.all()
    assert not far.ok.any()
    assert IK_TOLERANCE == 0.005


def test_padding_short_legs_changes_nothing() -> None:
    """A 3-DOF leg padded to 5 joints (as in a mixed robot) moves exactly as the unpadded leg."""
    robot: Robot = load_robot("openshc_default").robot
    plain = Chains.from_robot(robot)
    def pad(values: np.ndarray) -> np.ndarray:
        return np.pad(values, ((0, 0), (0, 2)))

    padded = Chains(
        plain.names, plain.base, d=pad(plain.d), theta=pad(plain.theta), r=pad(plain.r), alpha=pad(plain.alpha),
        lower=pad(plain.lower), upper=pad(plain.upper),
        max_vel=np.pad(plain.max_vel, ((0, 0), (0, 2)), constant_values=1.0), joint_count=plain.joint_count,
    )
    q = (plain.lower + plain.upper) / 2 + 0.05
    tip = plain.tips(q)
    target = tip + np.array([0.01, -0.02, 0.005])
    a = ik_step(plain, q, np.ones_like(q) * 0.3, tip, target, 0.02)
    b = ik_step(padded, np.pad(q, ((0, 0), (0, 2))), np.pad(np.ones_like(q) * 0.3, ((0, 0), (0, 2))), tip, target,
                0.02)
    np.testing.assert_array_equal(a.q, b.q[:, :3])
    np.testing.assert_array_equal(b.q[:, 3:], 0.0)
    np.testing.assert_array_equal(a.tip, b.tip)


@pytest.mark.parametrize("name", ROBOTS)
@settings(max_examples=10, deadline=None)
@given(fractions=joint_fraction, seed=st.integers(0, 2**16))
def test_ik_steps_from_kept_frames_equal_the_plain_steps_bit_for_bit(name: str, fractions: list[float],
                                                                     seed: int) -> None:
    """The controller's IK step keeps each leg's frames of its result and starts the next step from them
    (ik_step_frames_kernel): over steps towards moving targets — and after some legs' joints were set from outside,
    one of them to −0.0 — joints, speeds, tips, flags and proximity equal the plain kernel's bit for bit."""
    from shc_cli.model.kernels import ik_step_frames_kernel, ik_step_kernel

    c = CHAINS[name]
    q = _within_limits(c, fractions)
    rng = np.random.default_rng(seed)
    plain = [q.copy(), np.zeros_like(q), c.tips(q)]
    kept = [q.copy(), np.zeros_like(q), c.tips(q)]
    frames, frames_q = np.empty((c.size, c.d.shape[1] + 1, 4, 4)), np.full(c.d.shape, np.nan)
    for step in range(12):
        if step in (4, 8):  # joints set from outside (a pack, a direct move): those legs' frames are stale
            legs = rng.random(c.size) < 0.5
            moved = _within_limits(c, list(rng.random(len(fractions))))
            moved[0, 0] = -0.0 if step == 8 else moved[0, 0]
            for arrays in (plain, kept):
                arrays[0] = np.where(legs[:, None], moved, arrays[0])
                arrays[2] = c.tips(arrays[0])
        target = plain[2] + rng.normal(size=(c.size, 3)) * 0.01
        outputs = []
        for arrays, keep in ((plain, False), (kept, True)):
            q_out, qd_out, tip_out = np.empty_like(q), np.empty_like(q), np.empty((c.size, 3))
            flags, proximity = np.zeros(c.size, dtype=np.int64), np.ones(c.size)
            common = (c.base, c.d, c.theta, c.r, c.alpha, c.lower, c.upper, c.max_vel, arrays[0], arrays[1],
                      arrays[2], target, 0.01, True, True, q_out, qd_out, tip_out, flags, proximity)
            if keep:
                ik_step_frames_kernel(*common, frames, frames_q, np.zeros(c.size), 1.0)
            else:
                ik_step_kernel(*common, 1.0)
            arrays[:] = [q_out, qd_out, tip_out]
            outputs.append((q_out, qd_out, tip_out, flags, proximity))
        for a, b in zip(*outputs, strict=True):
            assert a.tobytes() == b.tobytes()
