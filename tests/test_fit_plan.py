"""The excitation plan of ``shc fit --plan`` (:mod:`shc_cli.domain.excitation`): a plan script the run commands
accept, inside the robot's ranges, ending where it started, and moving the joints in every phase."""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from shc_cli.domain.excitation import excitation_plan, write_plan
from shc_cli.spec.loading import load_robot
from shc_cli.spec.timeline import load_timeline


def _timeline(tmp_path: Path, robot: str = "openshc_default") -> tuple[Path, list[tuple[float, dict[str, Any]]]]:
    path = write_plan(robot, tmp_path / "plan.toml")
    dt = load_robot(robot).robot.time_delta
    return path, [(cycle * dt, change) for cycle, change in load_timeline(path, dt).changes]


def test_the_plan_is_a_plan_script_with_every_phase(tmp_path: Path) -> None:
    path, changes = _timeline(tmp_path)
    text = path.read_text()
    assert text.startswith("# shc fit excitation for openshc_default")
    frequencies = [change["parameters"]["step_frequency"] for _, change in changes
                   if "parameters" in change]
    assert frequencies == [0.5, 1.0, 1.5, 1.0]  # 0.5, 1 and 1.5 × the default 1 Hz, then the default again
    posed = {int(np.flatnonzero(change["pose_velocity"])[0]) for _, change in changes
             if any(change.get("pose_velocity", (0,)))}
    assert posed == set(range(6))  # every body axis swayed
    assert changes[0] == (0.0, {"velocity": (0.0, 0.0, 0.0)})  # stands first
    assert changes[-1][1] == {"velocity": (0.0, 0.0, 0.0)} and changes[-2][1]["velocity"] == (0.0, 0.0, 0.0)


def test_walking_and_swaying_return_to_the_start(tmp_path: Path) -> None:
    """Every walking input is undone by its opposite for as long (the robot on the ground ends where it began) and
    every sway input likewise (the body ends in its neutral pose, before the reset)."""
    _, changes = _timeline(tmp_path)
    travel, posed = np.zeros(3), np.zeros(6)
    held: dict[str, np.ndarray] = {"velocity": np.zeros(3), "pose_velocity": np.zeros(6)}
    for (t, change), (t_next, _) in itertools.pairwise(changes):
        for key in held:
            if key in change:
                held[key] = np.array(change[key], dtype=float)
        travel += held["velocity"] * (t_next - t)
        posed += held["pose_velocity"] * (t_next - t)
    assert np.abs(travel).max() < 1e-9 and np.abs(posed).max() < 1e-9


def test_step_frequencies_and_inputs_follow_the_robot_file(tmp_path: Path) -> None:
    """A robot whose step frequency cannot exceed 1.2 Hz gets 1.2 Hz instead of 1.5; real velocity inputs are
    given in m/s and rad/s."""
    robot = tmp_path / "slow.toml"
    robot.write_text('extends = "openshc_default"\nname = "slow"\n[walker]\nvelocity_input_mode = "real"\n'
                     "step_frequency = { default = 1.0, min = 0.001, max = 1.2, step = 0.1 }\n")
    text = excitation_plan(load_robot(robot).robot)
    assert "step_frequency = 1.2 }" in text and "step_frequency = 1.5" not in text
    assert "velocity = [0.05, 0, 0]" in text and "velocity = [0, 0, 0.2]" in text


def test_refuses_an_unknown_robot_without_writing(tmp_path: Path) -> None:
    from shc_cli.errors import ShcError

    with pytest.raises(ShcError):
        write_plan(str(tmp_path / "missing.toml"), tmp_path / "plan.toml")
    assert not (tmp_path / "plan.toml").exists()


@pytest.mark.slow  # 75 s of the kinematic run (≈ 5 s)
def test_every_phase_moves_the_joints(tmp_path: Path) -> None:
    """In ``shc plan``: the joints hold still while standing, swing through tenths of a radian while swaying and
    walking, and the walker walks at each frequency."""
    from shc_cli.api import plan

    path, changes = _timeline(tmp_path)
    run = plan("openshc_default", commands=path, out=tmp_path / "run", plots=False)
    from shc_cli.record.runread import read_run

    log = read_run(run.path)
    t = log.t - log.t[log.running][0]
    walk_from = next(at for at, change in changes if "parameters" in change)
    joints = log.joints.reshape(len(t), -1)
    for start, end, least in ((0.5, 3.5, 0.0), (4.0, walk_from, 0.2), (walk_from, t[-1], 0.3)):
        span = np.ptp(joints[(t >= start) & (t < end)], axis=0)
        assert span.min() >= least and (least > 0 or span.max() < 0.01), (start, end, span)
    blocks = [at for at, change in changes if "parameters" in change]
    for start, end in itertools.pairwise(blocks):  # each step frequency walks a good part of its block
        assert (log.walk_state[(t >= start) & (t < end)] == "MOVING").mean() > 0.3


def test_shc_fit_plan_writes_the_plan_and_refuses_to_overwrite_or_fit(tmp_path: Path) -> None:
    """End to end: ``shc fit --plan`` writes a plan script that ``shc validate`` and the run commands accept, says
    how to record it, and refuses (one line, exit 2) an existing file without --overwrite and run directories."""
    import subprocess
    import sys

    shc = [sys.executable, "-m", "shc_cli.cli"]
    out = tmp_path / "fit-plan.toml"
    made = subprocess.run([*shc, "fit", "--plan", "--robot", "openshc_default", "--out", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert made.returncode == 0, made.stderr
    assert f"shc run-hw openshc_default --commands {out}" in made.stdout
    assert load_timeline(out, 0.02).changes[0] == (0, {"velocity": (0.0, 0.0, 0.0)})
    again = subprocess.run([*shc, "fit", "--plan", "--robot", "openshc_default", "--out", str(out)],
                           capture_output=True, text=True, timeout=120)
    assert again.returncode == 2 and "already exists" in again.stderr and len(again.stderr.splitlines()) == 1
    mixed = subprocess.run([*shc, "fit", str(tmp_path), "--plan", "--out", str(tmp_path / "other.toml")],
                           capture_output=True, text=True, timeout=120)
    assert mixed.returncode == 2 and "--plan" in mixed.stderr and not (tmp_path / "other.toml").exists()
