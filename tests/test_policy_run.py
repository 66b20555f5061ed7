"""A policy file (``shc_cli.loop.policy.file``) run by ``shc simulate --policy`` and ``shc run-hw --policy``: the
same joint targets as the policy in ``shc/Walk-v0``, the controller alone before RUNNING, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from shc_cli.gym.policy import play
from shc_cli.loop.policy.file import Policy, PolicyFileError
from shc_cli.loop.policy.observe import observation_names
from shc_cli.record.runread import read_run
from shc_cli.spec.loading import load_robot

SHC = [sys.executable, "-m", "shc_cli.cli"]


def _names() -> list[str]:
    return observation_names(load_robot("bullet").robot)


def _simulate(tmp_path: Path, name: str, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*SHC, "simulate", "--velocity", "0.5,0,0", "--duration", "1", "--no-plots", "--out",
                           str(tmp_path / name), *args], capture_output=True, text=True, timeout=300)


def test_a_two_layer_tanh_policy_with_normalisation_gives_the_hand_computed_action(tmp_path: Path) -> None:
    w0, b0 = np.array([[1.0, -1.0], [0.5, 0.0], [0.0, 2.0]]), np.array([0.0, 0.1, -0.2])
    w1, b1 = np.array([[1.0, 1.0, 1.0], [-2.0, 0.0, 0.0]]), np.array([0.0, 0.5])
    policy = Policy("gait", ((w0, b0), (w1, b1)), "tanh", np.array([1.0, 2.0]), np.array([2.0, 4.0]), 0.5)
    policy.save(tmp_path / "p.npz")
    loaded = Policy.load(tmp_path / "p.npz")
    # o = (5, 2): normalised (2, 0) clipped to (0.5, 0); hidden tanh(0.5, 0.35, -0.2); out (sum, -2·tanh(0.5) + 0.5)
    h = [np.tanh(0.5), np.tanh(0.35), np.tanh(-0.2)]
    expected = [min(sum(h), 1.0), -2.0 * h[0] + 0.5]
    assert loaded(np.array([5.0, 2.0])).tolist() == pytest.approx(expected, abs=1e-6)
    assert loaded.activation == "tanh" and loaded.obs_clip == 0.5 and loaded.actions == 2


def test_the_first_linear_form_is_read_and_bad_files_are_one_line(tmp_path: Path) -> None:
    with (tmp_path / "old.npz").open("wb") as handle:
        np.savez(handle, weights=np.zeros((4, 3)), bias=np.array([0.5, 0.0, 2.0, -0.1]), action=np.array("gait"))
    assert Policy.load(tmp_path / "old.npz")(np.ones(3)).tolist() == pytest.approx([0.5, 0.0, 1.0, -0.1])
    (tmp_path / "junk.npz").write_text("not a zip")
    with pytest.raises(PolicyFileError, match=r"junk\.npz: not a policy file"):
        Policy.load(tmp_path / "junk.npz")
    with (tmp_path / "bad.npz").open("wb") as handle:
        np.savez(handle, format=np.array("shc-policy-1"), action=np.array("gait"), layers=np.array(2),
                 w0=np.zeros((3, 2)), b0=np.zeros(3), w1=np.zeros((4, 2)), b1=np.zeros(4))
    with pytest.raises(PolicyFileError, match=r"layer 1: weights \(4, 2\) and bias \(4,\) do not chain"):
        Policy.load(tmp_path / "bad.npz")


def test_simulate_with_a_policy_applies_the_joint_targets_of_the_environment(tmp_path: Path) -> None:
    """A linear residual policy (the action depends on the observation) through ``shc simulate --policy`` and through
    ``shc/Walk-v0`` (:func:`play`): the same joint targets bit for bit, and not those of the controller alone."""
    names = _names()
    weights = np.random.default_rng(0).normal(0.0, 0.01, (18, len(names)))
    Policy("residual", ((weights, np.full(18, 0.3)),), "identity", names=tuple(names)).save(tmp_path / "res.npz")
    episode = play(Policy.load(tmp_path / "res.npz"), tmp_path / "play", command="0.5,0,0", duration=1.0)
    result = _simulate(tmp_path, "sim", "--policy", str(tmp_path / "res.npz"))
    assert result.returncode == 0, result.stderr
    alone = _simulate(tmp_path, "alone")
    assert alone.returncode == 0, alone.stderr
    played, driven, controller = (read_run(path).commanded for path in (episode, tmp_path / "sim",
                                                                         tmp_path / "alone"))
    assert played is not None and driven is not None and controller is not None
    assert played.shape == driven.shape == controller.shape
    assert np.array_equal(played, driven)
    running = read_run(tmp_path / "sim").running
    first = int(np.argmax(running))  # the start-up is the controller's alone; the first RUNNING cycle too
    assert np.array_equal(driven[: first + 1], controller[: first + 1])
    assert np.abs(driven[first + 1:] - controller[first + 1:]).max() > 1e-3


def test_simulate_with_a_gait_policy_walks_at_its_step_frequency(tmp_path: Path) -> None:
    names = _names()
    Policy.constant("gait", np.array([0.5, 0.0, 0.0, 0.0]), len(names)).save(tmp_path / "gait.npz")
    result = _simulate(tmp_path, "sim", "--policy", str(tmp_path / "gait.npz"))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "sim" / "summary.json").read_text())
    frequency = load_robot("bullet").robot.walker.step_frequency
    assert summary["step_frequency_hz"] == pytest.approx(frequency.default + 0.5 * (frequency.max - frequency.default))


@pytest.mark.parametrize(("content", "message"), [
    ("junk", "not a policy file"),
    ("quadruped", "the policy takes 50 observations, bullet gives 94"),
    ("missing", "missing.npz: no such file"),
])
def test_a_bad_or_unfitting_policy_is_one_line_and_exit_2(content: str, message: str, tmp_path: Path) -> None:
    file = tmp_path / ("missing.npz" if content == "missing" else "p.npz")
    if content == "missing":
        pass
    elif content == "junk":
        file.write_text("junk")
    else:
        names = observation_names(load_robot(content).robot)
        Policy.constant("gait", np.zeros(4), len(names)).save(file)
    result = _simulate(tmp_path, "sim", "--policy", str(file))
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "--policy" in lines[0] and "Traceback" not in result.stderr
    assert not (tmp_path / "sim").exists()  # refused before anything is written


JOINTS = [f"{leg}_{joint}" for leg in ("AR", "BR", "CR", "CL", "BL", "AL") for joint in ("coxa", "femur", "tibia")]


def _bus_robot(folder: Path) -> Path:
    lines = ['extends = "openshc_default"', 'name = "hexapod_bus"', "[start_up]", "time_to_start = 1.5", "[hardware]",
             'model = "XM430-W350"', "return_delay_us = 0", "[hardware.servos]",
             *(f"{key} = {{ id = {k + 1} }}" for k, key in enumerate(JOINTS))]
    path = folder / "hexapod_bus.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def _run_hw(tmp_path: Path, name: str, policy: Path | None) -> tuple[dict[str, object], np.ndarray]:
    """run-hw's domain on 18 emulated servos on a virtual clock: the summary and the commanded joints."""
    from shc_cli.domain.hardware import HardwareConfig, run_hardware
    from shc_cli.hardware.emulator import BusEmulator, VirtualClock

    clock = VirtualClock()
    with BusEmulator({k + 1: "XM430-W350" for k in range(18)}, clock=clock) as bus:
        clock.bus = bus
        result = run_hardware(HardwareConfig(robot=str(_bus_robot(tmp_path)), ports=[bus.port], velocity="1,0,0",
                                             duration=1.5, out=tmp_path / name, stop_state="running",
                                             policy=policy), clock=clock, sleep=clock.sleep)
    commanded = read_run(tmp_path / name).commanded
    assert commanded is not None
    return result.summary.model_dump(), commanded


def test_run_hw_with_a_residual_policy_keeps_its_start_up_stop_and_limits(tmp_path: Path) -> None:
    """On emulated servos a residual policy moves the walking targets, not the start-up's; the run ends by its
    controlled stop as without it, every target within the joint limits."""
    from shc_cli.model.chains import Chains, JointSlots

    robot = load_robot(str(_bus_robot(tmp_path))).robot
    names = observation_names(robot)
    Policy.constant("residual", np.full(18, 1.0), len(names)).save(tmp_path / "res.npz")
    alone, plain = _run_hw(tmp_path, "alone", None)
    driven, moved = _run_hw(tmp_path, "driven", tmp_path / "res.npz")
    for summary in (alone, driven):
        assert summary["fault"] is None and summary["stopped_by_request"] and summary["final_state"] == "RUNNING"
    running = read_run(tmp_path / "driven").running
    first = int(np.argmax(running))
    assert np.array_equal(moved[: first + 1], plain[: first + 1])
    assert np.abs(moved[first + 1:] - plain[first + 1:]).max() > 1e-3
    chains, slots = Chains.from_robot(robot), JointSlots.of(robot)
    low, high = chains.lower[slots.rows, slots.cols], chains.upper[slots.rows, slots.cols]
    flat = moved.reshape(len(moved), -1)[:, : len(low)] if moved.ndim == 3 else moved
    assert (flat >= low - 1e-9).all() and (flat <= high + 1e-9).all()


def test_run_hw_refuses_a_joints_policy_before_the_bus_opens(tmp_path: Path) -> None:
    from shc_cli.domain.hardware import HardwareConfig, run_hardware
    from shc_cli.errors import SpecError

    robot = load_robot(str(_bus_robot(tmp_path))).robot
    Policy.constant("joints", np.zeros(18), len(observation_names(robot))).save(tmp_path / "joints.npz")
    with pytest.raises(SpecError, match="a 'joints' policy replaces the controller's targets"):
        run_hardware(HardwareConfig(robot=str(_bus_robot(tmp_path)), ports=["/dev/null-no-bus"],
                                    policy=tmp_path / "joints.npz"))
