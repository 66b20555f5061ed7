"""How often a run's commanded joints sit at their limits: the controller clamping the IK to the joint range."""

from __future__ import annotations

import numpy as np

from shc_cli.record.runread import RunLog

TOLERANCE = 1e-3
"""[rad]: a commanded joint this close to a limit counts as clamped."""


def joint_limit_fraction(run: RunLog, rows: np.ndarray, tolerance: float = TOLERANCE) -> float | None:
    """Share of the cycles ``rows`` in which any commanded joint is within ``tolerance`` of its ``min`` or ``max``
    [ratio, 0–1]; ``None`` without commanded joints or rows. Joints of shorter legs (padding) are ignored."""
    if run.commanded is None or len(rows) == 0:
        return None
    width = run.commanded.shape[2]
    low = np.full((len(run.legs), width), -np.inf)
    high = np.full((len(run.legs), width), np.inf)
    for i, leg in enumerate(run.robot.legs.values()):
        for k, joint in enumerate(leg.joints.values()):
            low[i, k], high[i, k] = joint.min, joint.max
    commanded = run.commanded[rows]
    at_limit = (commanded <= low + tolerance) | (commanded >= high - tolerance)
    return float(np.any(at_limit & np.isfinite(commanded), axis=(1, 2)).mean())
