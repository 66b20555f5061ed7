"""``shc fit`` replays a simulated run from where it started: a run on the stand of a robot whose file starts on the
ground (``simulate --stand``, as the Table IV sweep runs) records the stand in its ``robot.toml``
(``start_up.simulation``), the fit accepts it as a run of that robot and its replay gives the run's joints back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest


@pytest.mark.slow  # a 1 s stance after the 5 s start-up in MuJoCo, then its replay (≈ 10 s)
def test_a_stand_start_is_recorded_and_replayed(tmp_path: Path) -> None:
    from shc_cli.api import load_robot, simulate
    from shc_cli.domain.fit.recording import load_recording
    from shc_cli.domain.fit.rollout import replay

    robot = load_robot("bullet_insectoid_a")
    assert robot.start_up.simulation == "ground"
    run = simulate("bullet_insectoid_a", scenario="SG", stand=True, duration=1.0, out=tmp_path / "run",
                   plots=False)
    assert load_robot(run.path / "robot.toml").start_up.simulation == "stand"
    recording = load_recording(run.path, robot)  # the stand is no other robot
    trace = replay(recording, recording.robot.servo)
    assert np.abs(trace.position - recording.position).max() < 1e-3  # [rad] (was 0.084 from the ground spawn)
