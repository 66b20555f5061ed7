"""Damped-least-squares inverse kinematics with joint-limit avoidance (paper eq. 10–15, study §2).

OpenSHC takes exactly **one** DLS step per control cycle and leg; the remaining error is carried
into the next cycle. :func:`ik_step` is that step, for many legs at once. :func:`solve` repeats it
until the tip is within a tolerance, for planning uses (stance reachability, start poses).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shc_cli.model import kernels
from shc_cli.model.chains import Chains, FloatArray

DLS_COEFFICIENT = kernels.DLS_COEFFICIENT
"""λ of the damped pseudo-inverse ``Jᵀ(JJᵀ + λ²I)⁻¹``."""
JOINT_LIMIT_COST_WEIGHT = kernels.JOINT_LIMIT_COST_WEIGHT
"""w, the weight of every joint in the limit-avoidance cost."""
POSITION_LIMIT_SHARE = kernels.POSITION_LIMIT_SHARE
"""Share of the position-limit gradient in the null-space motion (the rest is the velocity-limit gradient)."""
IK_TOLERANCE = kernels.IK_TOLERANCE
"""Largest per-axis tip error [m] before a step counts as failed."""


@dataclass(frozen=True)
class StepResult:
    """Outcome of one IK step for ``B`` legs.

    Attributes:
        q: new desired joint positions, ``(B, n)`` [rad].
        qd: new desired joint velocities ``Δq/dt`` (before position clamping), ``(B, n)`` [rad/s].
        tip: tip positions after the step (FK of ``q``) in base_link, ``(B, 3)`` [m].
        ok: ``True`` where every axis of the tip error is within :data:`IK_TOLERANCE`, ``(B,)``.
        proximity: limit proximity ρ ∈ [0, 1] (1 = all joints centred, 0 = a joint at a limit), ``(B,)``.
        position_clamped: ``True`` where a joint position was clamped, ``(B,)``.
        velocity_clamped: ``True`` where a joint velocity was clamped, ``(B,)``.
    """

    q: FloatArray
    qd: FloatArray
    tip: FloatArray
    ok: np.ndarray
    proximity: FloatArray
    position_clamped: np.ndarray
    velocity_clamped: np.ndarray

    @property
    def result(self) -> FloatArray:
        """OpenSHC's return value of ``applyIK``: ρ where the step succeeded, else 0."""
        return np.where(self.ok, self.proximity, 0.0)


def ik_step(
    chains: Chains,
    q: FloatArray,
    qd: FloatArray,
    current_tip: FloatArray,
    desired_tip: FloatArray,
    dt: float,
    *,
    clamp_positions: bool = True,
    clamp_velocities: bool = False,
    avoid_limits: bool = True,
    avoidance_cap: float = 0.0,
) -> StepResult:
    """One OpenSHC IK step for every chain (study §2.1–§2.2, position only).

    Args:
        chains: the legs.
        q: current desired joint positions, ``(B, n)`` [rad].
        qd: current desired joint velocities (from the previous step), ``(B, n)`` [rad/s].
        current_tip: model tip positions in base_link (FK of ``q``), ``(B, 3)`` [m].
        desired_tip: target tip positions in base_link, ``(B, 3)`` [m].
        dt: control period [s].
        clamp_positions: clamp to the joint limits.
        clamp_velocities: clamp ``|q̇|`` to ``max_vel`` (OpenSHC skips this in its "simulation" calls).
        avoid_limits: add OpenSHC's null-space limit avoidance (off only to polish planning solutions).
        avoidance_cap: 0 is OpenSHC; c > 0 limits each limit-avoidance term to c times what it corrects
            (``ik.limit_avoidance_cap`` of the robot file, docs/deviations.md).

    The general, allocating entry (any arrays in, a fresh :class:`StepResult` out), used by :func:`solve` and
    the start-up sequence's planning. The controller's per-cycle loop calls the same kernel through
    :meth:`shc_cli.control.controller.Model.step_ik` instead, which writes into its own arrays and skips the result
    object: ≈ 8 µs against ≈ 12 µs per 6-leg step here, a cost paid every control cycle, so neither wraps the other.
    """
    count, joints = chains.d.shape
    q_new = np.empty((count, joints))
    qd_new = np.empty((count, joints))
    tip = np.empty((count, 3))
    flags = np.empty(count, dtype=np.int64)
    near = np.empty(count)
    kernels.ik_step_kernel(
        chains.base, chains.d, chains.theta, chains.r, chains.alpha, chains.lower, chains.upper, chains.max_vel,
        np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float),
        np.ascontiguousarray(current_tip, dtype=float), np.ascontiguousarray(desired_tip, dtype=float),
        float(dt), clamp_positions, clamp_velocities, q_new, qd_new, tip, flags, near, 1.0 if avoid_limits else 0.0,
        float(avoidance_cap),
    )
    return StepResult(q_new, qd_new, tip, (flags & 1) != 0, near, (flags & 2) != 0, (flags & 4) != 0)


def proximity(chains: Chains, q: FloatArray) -> FloatArray:
    """Limit proximity ρ = min over joints of ``min(|q − min|, |q − max|) / (range/2)``; 1 for fixed joints."""
    half = (chains.upper - chains.lower) / 2.0
    moving = half != 0.0
    near = np.minimum(np.abs(q - chains.lower), np.abs(q - chains.upper))
    ratio = np.where(moving, near / np.where(moving, half, 1.0), 1.0)
    return np.asarray(ratio.min(axis=1))


def solve(
    chains: Chains,
    q0: FloatArray,
    targets: FloatArray,
    *,
    tolerance: float = 1e-6,
    max_steps: int = 500,
    dt: float = 0.01,
) -> tuple[FloatArray, FloatArray]:
    """Repeat clamped IK steps until every tip is within ``tolerance`` of its target.

    A planning tool (not OpenSHC's per-cycle behaviour): used to check that stance positions are
    reachable and to seed start poses.

    Args:
        chains: the legs.
        q0: start joint positions, ``(B, n)`` [rad].
        targets: tip targets in base_link, ``(B, 3)`` [m].
        tolerance: stop when every tip error norm is below this [m].
        max_steps: give up after this many steps.
        dt: nominal step period for the velocity term [s].

    Returns:
        ``(q, error)``: the joint positions reached and each chain's remaining tip error norm [m].
    """
    q = np.array(q0, dtype=float)
    qd = np.zeros_like(q)
    tip = chains.tips(q)
    error = np.linalg.norm(targets - tip, axis=1)
    for count in range(max_steps):
        if (error < tolerance).all():
            break
        # Limit avoidance keeps joints central on the way; the last steps polish without it.
        polish = count >= max_steps // 2 or bool((error < 1e-3).all())
        step = ik_step(chains, q, qd, tip, targets, dt, avoid_limits=not polish)
        q, tip = step.q, step.tip
        error = np.linalg.norm(targets - tip, axis=1)
    return q, error
