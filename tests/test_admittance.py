"""Admittance control (paper eq. 19–20, study §8): the virtual spring's steady state, dynamic stiffness, and the
tip force estimated from joint torques."""

from __future__ import annotations

import numpy as np
import pytest

from shc_cli.control.admittance import MAX_DELTA, AdmittanceController, tip_forces_from_efforts
from shc_cli.model.chains import Chains


def _controller(**kwargs: float | bool) -> AdmittanceController:
    base: dict[str, float | bool] = dict(mass=6.0, stiffness=20.0, damping_ratio=2.5, force_gain=0.02,
                                         step_time=0.06, swing_scaler=0.01, load_scaler=2.0, dynamic=True)
    base.update(kwargs)
    return AdmittanceController(6, **base)  # type: ignore[arg-type]


def test_a_loaded_leg_yields_force_over_stiffness() -> None:
    """Eq. 20 at rest: Δz = gain·F / k; no force, no offset; clamped at 0.2 m; pulling is ignored."""
    controller = _controller()
    forces = np.array([22.0, 0.0, 10.0, -5.0, 1e4, 22.0])
    for _ in range(2000):  # 2000 × 0.06 s of virtual time (ζ = 2.5: a slow mode)
        delta = controller.update(forces, np.full(6, -1.0), walking=False)
    np.testing.assert_allclose(delta, [0.022, 0.0, 0.01, 0.0, MAX_DELTA, 0.022], atol=1e-6)


def test_dynamic_stiffness_softens_the_swing_leg_and_stiffens_its_neighbours() -> None:
    """Study §8.3 with the reach r of the swing: swing leg k·(r·(0.01 − 1) + 1), neighbours + k·r·(2 − 1)."""
    controller = _controller()
    reach = np.array([0.5, -1.0, -1.0, -1.0, -1.0, -1.0])
    k = controller.stiffnesses(reach, walking=True)
    np.testing.assert_allclose(k, [20 * (0.5 * -0.99 + 1), 30.0, 20.0, 20.0, 20.0, 30.0])
    np.testing.assert_allclose(controller.stiffnesses(reach, walking=False), 20.0)
    np.testing.assert_allclose(_controller(dynamic=False).stiffnesses(reach, walking=True), 20.0)


@pytest.mark.slow  # simulated legs under load
def test_tip_force_from_joint_torques_inverts_the_jacobian_transpose(bullet) -> None:  # type: ignore[no-untyped-def]
    """Eq. 19 with τ = Jᵀ·F: J(JᵀJ + λ²I)⁻¹Jᵀ·F equals JJᵀ(JJᵀ + λ²I)⁻¹·F (push-through identity, an independent
    3×3 formula) for random joints; at the standing pose it is F within 2 % of |F| (the damping biases the
    leg's weakest direction)."""
    from shc_cli.model.ik import solve

    chains = Chains.from_robot(bullet)
    rng = np.random.default_rng(0)
    force = np.array([[1.0, -2.0, 20.0]] * chains.size)
    q = rng.uniform(chains.lower / 2, chains.upper / 2)
    jacobians = chains.jacobians(q)
    torques = np.einsum("lji,lj->li", jacobians, force)
    expected = [jj @ np.linalg.solve(jj + 0.02**2 * np.eye(3), f)
                for jj, f in zip(np.einsum("lij,lkj->lik", jacobians, jacobians), force, strict=True)]
    np.testing.assert_allclose(tip_forces_from_efforts(jacobians, torques), expected, rtol=1e-9, atol=1e-9)
    stance = np.array([[leg.stance.x, leg.stance.y, -bullet.walker.body_clearance] for leg in bullet.legs.values()])
    standing, _ = solve(chains, chains.default_joints(), stance)
    jacobians = chains.jacobians(standing)
    torques = np.einsum("lji,lj->li", jacobians, force)
    error = np.linalg.norm(tip_forces_from_efforts(jacobians, torques) - force, axis=1)
    assert (error < 0.02 * np.linalg.norm(force, axis=1)).all()


def test_the_offset_settles_without_overshoot_at_the_robot_files_damping() -> None:
    controller = _controller()
    history = [controller.update(np.full(6, 22.0), np.full(6, -1.0), walking=False)[0] for _ in range(600)]
    assert max(history) <= 0.022 + 1e-9
    assert history[-1] == pytest.approx(0.022, rel=1e-3)
