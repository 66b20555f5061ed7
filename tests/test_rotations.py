"""Roll/pitch/yaw ↔ rotation matrix (the one conversion, on scipy): Rz(yaw)·Ry(pitch)·Rx(roll), body → world."""

from __future__ import annotations

import numpy as np

from shc_cli.analysis.metrics import rotation_rpy, rpy_of


def _elementary(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out = np.eye(3)
    out[i, i] = out[j, j] = c
    out[i, j], out[j, i] = -s, s
    return out


def test_rotation_is_z_y_x_and_round_trips() -> None:
    rng = np.random.default_rng(3)
    rpy = rng.uniform([-3.0, -1.5, -3.1], [3.0, 1.5, 3.1], (200, 3))
    expected = np.array([_elementary(2, y) @ _elementary(1, p) @ _elementary(0, r) for r, p, y in rpy])
    np.testing.assert_allclose(rotation_rpy(rpy), expected, atol=1e-12)
    np.testing.assert_allclose(rpy_of(expected), rpy, atol=1e-9)
    # a body pitched nose-down by +0.3 rad: its x axis points down in the world
    assert rotation_rpy(np.array([[0.0, 0.3, 0.0]]))[0, 2, 0] == np.sin(-0.3)
