"""The plan summary's paper eq. 16 speed is a prediction, not the walker's own velocity read back: the stride comes
from the walkspace-derived limit of the commanded direction and the throttle, f and β from the gait."""

from __future__ import annotations

from pathlib import Path

import pytest

from shc_cli.domain.plan import plan


def test_eq16_predicts_the_stance_feet_speed_at_half_throttle(tmp_path: Path) -> None:
    summary = plan("bullet_openshc", "tripod", "0.5,0,0", 6.0, None, tmp_path / "half", False).summary
    # v = l_s·f/β with l_s = 2·r·throttle: half of the full-throttle speed 0.231884058 m/s (tests/test_plan.py)
    assert summary.eq16_speed_mps == pytest.approx(0.5 * 0.231884058, rel=1e-6)
    assert summary.achieved_mean_speed_mps == pytest.approx(summary.eq16_speed_mps, rel=0.01)


def test_eq16_can_disagree_with_the_walk(tmp_path: Path) -> None:
    """Turning while walking: the stance feet do not move at the straight-line eq. 16 speed (the old check, the
    walker's velocity divided and multiplied by f/β, agreed with itself whatever happened)."""
    summary = plan("bullet_openshc", "tripod", "0.5,0,0.5", 6.0, None, tmp_path / "turn", False).summary
    assert summary.eq16_speed_mps == pytest.approx(0.5 * 0.231884058, rel=1e-6)
    assert summary.achieved_mean_speed_mps is not None and summary.eq16_speed_mps is not None
    assert abs(summary.achieved_mean_speed_mps / summary.eq16_speed_mps - 1.0) > 0.05
