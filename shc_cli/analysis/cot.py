"""Cost of transport (paper eq. 22), the one place it is computed."""

from __future__ import annotations

from shc_cli.model.body import GRAVITY

MIN_SPEED = 1e-3
"""Below this speed the robot did not travel and has no cost of transport [m/s]."""


def cost_of_transport(power_w: float, mass_kg: float, speed_mps: float) -> float | None:
    """Paper eq. 22: mean power / (m·g·v) [dimensionless]; ``None`` when the robot hardly moved."""
    return float(power_w / (mass_kg * GRAVITY * speed_mps)) if speed_mps > MIN_SPEED else None
