"""Bézier curves and the smooth step, written in OpenSHC's operation order (study §1.5, §5).

The controller integrates or evaluates these every cycle; the expressions keep the original
order of multiplications so results match the reference recordings bit for bit where possible.
"""

from __future__ import annotations

import numpy as np


def smooth_step(x: float) -> float:
    """``6x⁵ − 15x⁴ + 10x³``: 0 → 1 with zero slope and curvature at both ends."""
    return 6.0 * x**5 - 15.0 * x**4 + 10.0 * x**3


def quartic(points: np.ndarray, t: float) -> np.ndarray:
    """Point of the quartic Bézier with control points ``points`` (5, …) at ``t`` ∈ [0, 1]."""
    s = 1.0 - t
    return np.asarray(
        points[0] * (s * s * s * s) + points[1] * (4.0 * t * s * s * s) + points[2] * (6.0 * t * t * s * s)
        + points[3] * (4.0 * t * t * t * s) + points[4] * (t * t * t * t)
    )


def cubic(points: np.ndarray, t: float) -> np.ndarray:
    """Point of the cubic Bézier with control points ``points`` (4, …) at ``t`` ∈ [0, 1]."""
    s = 1.0 - t
    return np.asarray(points[0] * (s * s * s) + points[1] * (3.0 * t * s * s) + points[2] * (3.0 * t * t * s)
                      + points[3] * (t * t * t))
