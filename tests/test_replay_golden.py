"""The controller against the real OpenSHC binary: the whole insectoid recording, cycle by cycle.

Recording (golden/openshc-runs/, from shared/reference/openshc-runs/): Bullet insectoid, tripod, all joints 0,
direct start-up (5 s), then throttle 0.5 and 1.0 forward, stop, turn at 0.5, stop — 7,939 cycles at 100 Hz.
Values are printed with 6 decimals (joints, tips, velocities) and 4 (progress), which bounds the agreement.
"""

from __future__ import annotations

import pytest

from shc_cli.analysis.recording import Comparison, Recording, replay, startup_cycles
from shc_cli.control.controller import RobotState
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot

from .conftest import GOLDEN


@pytest.fixture(scope="module")
def recording() -> Recording:
    return Recording.load(GOLDEN / "openshc-runs", "insectoid")


@pytest.fixture(scope="module")
def comparison(recording: Recording, bullet: Robot, tripod: Gait) -> Comparison:
    return replay(recording, bullet, tripod)


def test_the_recording_is_complete(recording: Recording) -> None:
    assert recording.cycles == 7939
    assert len(recording.joints.columns) == 2 + 30


def test_startup_requests_are_derived_from_the_recording(recording: Recording, bullet: Robot) -> None:
    assert startup_cycles(recording, bullet) == {0: RobotState.RUNNING, 9: RobotState.RUNNING,
                                                 509: RobotState.RUNNING}


def test_model_tips_match_within_a_tenth_of_a_millimetre(comparison: Comparison) -> None:
    assert comparison.worst["model_tip_m"] < 1e-4
    assert comparison.worst["model_tip_m"] < 1e-6  # in fact: the recording's print precision


def test_walker_and_poser_tips_match(comparison: Comparison) -> None:
    assert comparison.worst["walker_tip_m"] < 1e-6
    assert comparison.worst["poser_tip_m"] < 1e-6


def test_joint_targets_match_within_a_milliradian(comparison: Comparison) -> None:
    assert comparison.worst["joints_rad"] < 1e-3
    assert comparison.worst["joints_rad"] < 2e-6  # printed to 6 decimals


def test_body_velocity_matches_within_1e_6(comparison: Comparison) -> None:
    assert comparison.worst["velocity"] < 1e-6


def test_stance_and_swing_progress_match(comparison: Comparison) -> None:
    assert comparison.worst["progress"] < 1e-4  # printed to 4 decimals
