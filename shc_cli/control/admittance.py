"""Admittance control (OpenSHC paper eq. 19–20, study §8): each leg yields to the ground force like a virtual
mass–spring–damper, so the load spreads over the feet on uneven ground.

Per leg, on the vertical axis of the body (paper eq. 20): ``−F_z = m·Δz̈ + b·Δż + k·Δz`` with
``b = 2ζ·sqrt(m·k)``; the desired tip becomes ``z_d = z_r − Δz`` (a loaded leg shortens by about ``F/k``).
``F_z`` is the ground's upward force on the foot times ``force_gain`` (clipped at 0): from a foot force sensor,
or from the joint torques through the damped pseudo-inverse of the Jacobian transpose (eq. 19,
``F = J·(JᵀJ + λ²I)⁻¹·τ``, λ = 0.02). As in OpenSHC the virtual system advances ``integrator_step_time`` per
control cycle (RK4, 30 steps) and ``Δz`` is clamped to ±0.2 m.

Dynamic stiffness (study §8.3): while walking, a swinging leg's stiffness is ``k·(r·(swing_scaler − 1) + 1)`` and
each neighbour of a swinging leg gains ``k·r·(load_scaler − 1)``, ``r`` = swing height reached (0 at lift-off, 1 at
the apex). OpenSHC computes these and then integrates with the global ``k``; here they act (docs/deviations.md).

Deviations from OpenSHC's code, all towards the paper: the force gain is applied once (OpenSHC twice when it
estimates from joint efforts), each leg has its own state on the vertical axis only (OpenSHC runs x, y and z
through one shared state and projects the result onto the last link), and dynamic stiffness acts.
"""

from __future__ import annotations

import numpy as np

from shc_cli.model.jit import njit

MAX_DELTA = 0.2
"""Clamp of the admittance offset [m] (OpenSHC)."""
RK4_STEPS = 30
"""Integration steps per control cycle (OpenSHC)."""
DAMPING_LAMBDA = 0.02
"""Damping of the pseudo-inverse that turns joint torques into a tip force (study §8.2)."""


@njit(cache=True)
def _integrate(x: np.ndarray, v: np.ndarray, force: np.ndarray, mass: float, stiffness: np.ndarray,
               damping_ratio: float, duration: float) -> None:  # pragma: no cover - compiled
    h = duration / RK4_STEPS
    for leg in range(x.shape[0]):
        k = stiffness[leg]
        b = damping_ratio * 2.0 * np.sqrt(mass * k)
        u = force[leg]
        p, q = x[leg], v[leg]
        for _ in range(RK4_STEPS):
            a1 = (-u - b * q - k * p) / mass
            p2, q2 = p + 0.5 * h * q, q + 0.5 * h * a1
            a2 = (-u - b * q2 - k * p2) / mass
            p3, q3 = p + 0.5 * h * q2, q + 0.5 * h * a2
            a3 = (-u - b * q3 - k * p3) / mass
            p4, q4 = p + h * q3, q + h * a3
            a4 = (-u - b * q4 - k * p4) / mass
            p = p + h * (q + 2.0 * q2 + 2.0 * q3 + q4) / 6.0
            q = q + h * (a1 + 2.0 * a2 + 2.0 * a3 + a4) / 6.0
        x[leg], v[leg] = p, q


def tip_forces_from_efforts(jacobians: np.ndarray, efforts: np.ndarray) -> np.ndarray:
    """Force each tip applies to the world, in the leg frames ``(L, 3)`` [N], from joint torques ``(L, n)``
    (paper eq. 19: ``F = J·(JᵀJ + λ²I)⁻¹·τ``; τ = Jᵀ·F for a static leg)."""
    out = np.empty((len(efforts), 3))
    for leg, (jac, tau) in enumerate(zip(jacobians, efforts, strict=True)):
        n = jac.shape[1]
        out[leg] = jac @ np.linalg.solve(jac.T @ jac + DAMPING_LAMBDA**2 * np.eye(n), tau)
    return out


class AdmittanceController:
    """Per-leg virtual mass–spring–damper on the body's vertical axis.

    Args:
        legs: number of legs (neighbours are id ± 1 around the body, as OpenSHC).
        mass: virtual mass [kg].
        stiffness: virtual stiffness [N/m].
        damping_ratio: ζ.
        force_gain: multiplier on the measured force.
        step_time: virtual time advanced per control cycle [s].
        swing_scaler: stiffness factor of a swinging leg at its apex.
        load_scaler: stiffness factor added to the neighbours of a swinging leg at its apex.
        dynamic: whether dynamic stiffness acts.
    """

    def __init__(self, legs: int, mass: float, stiffness: float, damping_ratio: float, force_gain: float,
                 step_time: float, swing_scaler: float, load_scaler: float, dynamic: bool) -> None:
        self.legs = legs
        self.mass, self.stiffness, self.damping_ratio = mass, stiffness, damping_ratio
        self.force_gain, self.step_time = force_gain, step_time
        self.swing_scaler, self.load_scaler, self.dynamic = swing_scaler, load_scaler, dynamic
        self.x = np.zeros(legs)
        self.v = np.zeros(legs)
        self.leg_stiffness = np.full(legs, stiffness)
        self.delta = np.zeros(legs)

    def stiffnesses(self, swing_reach: np.ndarray, walking: bool) -> np.ndarray:
        """Per-leg stiffness [N/m]; ``swing_reach`` is 0..1 for swinging legs, negative otherwise."""
        k = np.full(self.legs, self.stiffness)
        if not (self.dynamic and walking):
            return k
        for leg in np.flatnonzero(swing_reach >= 0.0):
            reach = float(swing_reach[leg])
            k[leg] = self.stiffness * (reach * (self.swing_scaler - 1.0) + 1.0)
        for leg in np.flatnonzero(swing_reach >= 0.0):
            reach = float(swing_reach[leg])
            for neighbour in ((leg - 1) % self.legs, (leg + 1) % self.legs):
                if swing_reach[neighbour] < 0.0:
                    k[neighbour] += self.stiffness * reach * (self.load_scaler - 1.0)
        return k

    def update(self, force_z: np.ndarray, swing_reach: np.ndarray, walking: bool) -> np.ndarray:
        """Advance one control cycle with the ground's vertical force on each foot [N]; returns ``Δz`` per leg
        [m] (positive: the tip is raised towards the body)."""
        self.leg_stiffness = self.stiffnesses(swing_reach, walking)
        force = np.maximum(np.asarray(force_z, dtype=float) * self.force_gain, 0.0)
        _integrate(self.x, self.v, force, self.mass, self.leg_stiffness, self.damping_ratio, self.step_time)
        self.delta = np.clip(-self.x, -MAX_DELTA, MAX_DELTA)
        return self.delta
