"""Cost of transport over the distance walked (issue 38): a path back to its start has one; the displacement's
CoT is kept beside it (shc_cli/analysis/metrics.py walk_figures)."""

from __future__ import annotations

import itertools
import json
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from shc_cli.analysis.metrics import walk_figures
from shc_cli.model.body import GRAVITY, body_mass
from shc_cli.spec.loading import load_robot

ROOT = Path(__file__).resolve().parents[1]


def _run(position: np.ndarray, power_w: float) -> SimpleNamespace:
    robot = load_robot("bullet").robot
    n = len(position)
    return SimpleNamespace(dt=0.01, robot=robot, desired=np.zeros((n, 3)), power=np.full(n, power_w),
                           position=np.column_stack([position, np.zeros(n)]))


def _square(side: float, per_side: int) -> np.ndarray:
    corners = np.array([[0, 0], [side, 0], [side, side], [0, side], [0, 0]], dtype=float)
    legs = [np.linspace(a, b, per_side, endpoint=False) for a, b in itertools.pairwise(corners)]
    return np.vstack([*legs, corners[-1:]])


def test_a_closed_square_gets_the_cot_of_its_perimeter_and_no_displacement_cot() -> None:
    position = _square(2.0, 400)  # 1601 rows at 10 ms: 8 m in 16.01 s
    run = _run(position, 100.0)
    rows = np.arange(1, len(position))  # the window's path starts at row 0's position: the samples hit the corners
    figures = walk_figures(run, rows, walking=True, period=100)  # type: ignore[arg-type]
    span = len(rows) * 0.01
    mass = body_mass(run.robot)
    assert figures.walked_m == pytest.approx(8.0, rel=1e-9)
    assert figures.cot == pytest.approx(100.0 / (mass * GRAVITY * 8.0 / span), rel=1e-9)
    assert figures.cot_displacement is None


def test_the_sway_within_a_step_is_not_distance_walked() -> None:
    """A straight walk with a lateral sway of one period per gait cycle: the distance walked is the straight line,
    and both CoTs agree."""
    t = np.arange(1001) * 0.01
    position = np.column_stack([0.1 * t, 0.02 * np.sin(2 * np.pi * t)])  # one sway a second, 100 cycles
    rows = np.arange(1, len(t))
    figures = walk_figures(_run(position, 80.0), rows, walking=True, period=100)  # type: ignore[arg-type]
    assert figures.walked_m == pytest.approx(1.0, rel=1e-6)
    assert figures.path_speed_mps * figures.span_s > 1.05  # the sway lengthens the raw path
    assert figures.cot == pytest.approx(figures.cot_displacement, rel=2e-3)


@pytest.mark.slow
def test_the_bundled_square_prints_a_cot(tmp_path: Path) -> None:
    out = tmp_path / "square"
    shc = str(Path(sys.executable).parent / "shc")
    result = subprocess.run([shc, "simulate", "--path", "paths/square_2m.csv", "--out", str(out), "--no-plots"],
                            cwd=ROOT, capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr
    assert "CoT " in result.stdout and "CoT:" not in result.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["walked_m"] > 7.5 and summary["cot"] is not None
    assert summary["cot_displacement"] is None or summary["cot_displacement"] > 10 * summary["cot"]
