"""Cost of transport (paper eq. 22), the one place it and standard gravity are computed."""

from __future__ import annotations

GRAVITY = 9.81
"""Standard gravity [m/s²]."""
MIN_SPEED = 1e-3
"""Below this speed the robot did not travel and has no cost of transport [m/s]."""


def cost_of_transport(power_w: float, mass_kg: float, speed_mps: float) -> float | None:
    """Paper eq. 22: mean power / (m·g·v) [dimensionless]; ``None`` when the robot hardly moved."""
    return float(power_w / (mass_kg * GRAVITY * speed_mps)) if speed_mps > MIN_SPEED else None
