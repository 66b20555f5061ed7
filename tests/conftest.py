"""Shared fixtures: the repository's folders and the bundled robots, loaded once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from shc_cli.spec.loading import load_gait, load_robot
from shc_cli.spec.robot import Robot

ROOT = Path(__file__).resolve().parents[1]
GOLDEN = ROOT / "golden"


@pytest.fixture(scope="session")
def bullet() -> Robot:
    robot = load_robot(ROOT / "robots" / "bullet.toml").robot
    assert robot is not None
    return robot


@pytest.fixture(scope="session")
def tripod():  # type: ignore[no-untyped-def]
    return load_gait("tripod").gait
