"""Shared fixtures: the repository's folders and the bundled robots, loaded once per session."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from shc_cli.spec.loading import load_gait, load_robot
from shc_cli.spec.robot import Robot

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "golden"
EXPERIMENTS = ROOT / "docs" / "experiments"
sys.path.insert(0, str(EXPERIMENTS))  # the experiment scripts (a folder, not a package) import as modules in tests


@pytest.fixture(scope="session")
def bullet() -> Robot:
    robot = load_robot(ROOT / "robots" / "bullet.toml").robot
    assert robot is not None
    return robot


@pytest.fixture(scope="session")
def tripod():  # type: ignore[no-untyped-def]
    return load_gait("tripod").gait


@pytest.fixture
def field_csv(tmp_path: Path) -> Path:
    """A 12 × 8 field (8 lines along y, 12 columns along x), 0..0.2 m, with a 0.3 m spike at (+x end, +y edge)."""
    grid = np.random.default_rng(7).uniform(0.0, 0.2, size=(8, 12))
    grid[0, -1] = 0.3
    path = tmp_path / "field.csv"
    np.savetxt(path, grid, delimiter=",", fmt="%.6f")
    return path
