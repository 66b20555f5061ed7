"""shc_cli.gym: the Gymnasium environment over the one controller and run loop (issue 41)."""

from __future__ import annotations

import csv
import functools
from collections.abc import Callable
from pathlib import Path
from typing import cast

import gymnasium
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import given, settings
from hypothesis import strategies as st

import shc_cli.gym
from shc_cli.backends.engine import Reading
from shc_cli.backends.simulated import SimulatedBackend, open_world
from shc_cli.control.controller import Command, Controller, CycleOutput
from shc_cli.control.states import RobotState
from shc_cli.control.verified_limits import source_for
from shc_cli.control.walk import WalkState
from shc_cli.domain.config import SimulationConfig
from shc_cli.gym.env import WalkEnv
from shc_cli.loop.policy.actions import GAIT_PARAMETERS, around
from shc_cli.loop.policy.observe import TERMS, observation_names, support_margin
from shc_cli.loop.run_inputs import load_inputs
from shc_cli.loop.run_loop import RunLoop, StartUp
from shc_cli.spec.robot import Robot

STEPS = 60
"""Environment steps of the comparisons (0.6 s of walking at 100 Hz)."""


@functools.cache
def _bullet() -> Robot:
    from shc_cli.spec.loading import load_robot

    return load_robot("bullet").robot


def _env(action: str, **kwargs: float | str | tuple[float, float, float] | dict[str, float]) -> WalkEnv:
    make = cast(Callable[..., gymnasium.Env[np.ndarray, np.ndarray]], gymnasium.make)  # (its own keywords typed)
    env = make(shc_cli.gym.ENV_ID, action=action, duration=STEPS * 0.01, **kwargs)
    inner = env.unwrapped
    assert isinstance(inner, WalkEnv)
    return inner


@pytest.mark.parametrize("action", [pytest.param("gait", marks=pytest.mark.slow), "residual",
                                    pytest.param("joints", marks=pytest.mark.slow)])  # each 6–12 s on 2 busy cores
def test_check_env_passes_for_every_action_space(action: str) -> None:
    env = _env(action)
    check_env(env, skip_render_check=True)
    assert env.observation_space.shape == (len(observation_names(env.robot)),)
    env.close()


class _Capture:
    """A recorder keeping the applied joint targets of every cycle."""

    def __init__(self) -> None:
        self.applied: list[np.ndarray] = []

    def record(self, cycle: int, command: Command, out: CycleOutput, applied: np.ndarray, reading: Reading) -> None:
        self.applied.append(np.array(applied))

    def flush(self) -> None:
        """Nothing to flush."""


def _simulated_targets(velocity: str, seed: int) -> list[np.ndarray]:
    """Every cycle's joint targets of ``shc simulate bullet --velocity V --duration STEPS·dt --seed S`` as the
    domain builds it (the same robot, world, controller and loop), captured instead of logged."""
    config = SimulationConfig(robot="bullet", velocity=velocity, duration=STEPS * 0.01, seed=seed)
    inputs = load_inputs(config.robot, config.gait, config.velocity, config.duration, None, default_s=20.0,
                         walking=config.walking, robot_change=config.apply_switches)
    world = open_world(inputs.robot, config.engine_options(inputs.robot))
    capture = _Capture()
    with SimulatedBackend(inputs.robot, world) as backend:
        controller = Controller(inputs.robot, inputs.gait, joints=backend.start(), pose_sets=inputs.pose_sets,
                                speed_shares=source_for(inputs.robot))  # as the domain makes it
        RunLoop(controller, backend, inputs.source(controller), capture, StartUp.of(inputs.robot)).run()
    return capture.applied


def _episode(env: WalkEnv, seed: int, action: np.ndarray, options: dict[str, float] | None = None
             ) -> tuple[int, list[np.ndarray], list[np.ndarray]]:
    """(start-up cycles, each step's applied joint targets, each observation) of one episode."""
    obs, info = env.reset(seed=seed, options=options)
    joints, observations = [], [obs]
    for _ in range(STEPS):
        obs, _, terminated, truncated, info = env.step(action)
        joints.append(np.array(info["joints"]))
        observations.append(obs)
        if terminated or truncated:
            break
    return int(info.get("start_up_cycles", 0) or 0), joints, observations


@pytest.mark.parametrize("action", ["residual", "gait"])
def test_zero_actions_give_the_joint_targets_of_shc_simulate(action: str) -> None:
    reference = _simulated_targets("0.6,0,0.2", seed=3)
    env = _env(action, command=(0.6, 0.0, 0.2))
    _, info = env.reset(seed=3)
    start_up = info["start_up_cycles"] + 1
    zero = np.zeros(env.action_size, dtype=np.float32)
    joints = []
    truncated = False
    while not truncated:
        _, _, terminated, truncated, step_info = env.step(zero)
        assert not terminated
        joints.append(step_info["joints"])
    env.close()
    assert len(reference) == start_up + STEPS == start_up + len(joints)
    for mine, theirs in zip(joints, reference[start_up:], strict=True):
        np.testing.assert_array_equal(mine, theirs)  # bit for bit


def test_zero_residual_matches_the_log_of_the_simulate_command(tmp_path: Path) -> None:
    """Against ``log.csv`` of the command itself (6 significant digits there)."""
    from shc_cli.api import simulate

    run = simulate("bullet", velocity="0.6,0,0.2", duration=STEPS * 0.01, seed=3, out=tmp_path / "run", plots=False)
    with (run.path / "log.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    env = _env("residual", command="0.6,0,0.2")
    _, joints, _ = _episode(env, 3, np.zeros(env.action_size, dtype=np.float32))
    names = [f"{leg}_{joint}_cmd" for leg, spec in env.robot.legs.items() for joint in spec.joints]
    slots = env._slots
    logged = np.array([[float(row[name]) for name in names] for row in rows[-STEPS:]])
    mine = np.array([slots.servo_order(j) for j in joints])
    np.testing.assert_allclose(mine, logged, rtol=1e-5, atol=1e-6)
    env.close()


def test_a_residual_moves_the_tips_by_its_offset() -> None:
    """A 1 cm offset along x on every leg moves every tip (FK of the applied joints) by about 1 cm along x."""
    from shc_cli.model.chains import Chains

    env = _env("residual", command=(0.0, 0.0, 0.0), residual_limit=0.01)
    env.reset(seed=0)
    legs = len(env.robot.legs)
    _, _, _, _, plain = env.step(np.zeros(3 * legs, dtype=np.float32))
    chains = Chains.from_robot(env.robot)
    before = chains.tips(plain["joints"])
    action = np.tile(np.array([1.0, 0.0, 0.0], dtype=np.float32), legs)
    _, _, _, _, moved = env.step(action)
    shift = chains.tips(moved["joints"]) - before
    env.close()
    np.testing.assert_allclose(shift[:, 0], 0.01, atol=2e-3)  # standing still: the controller's tips stay put
    np.testing.assert_allclose(shift[:, 1:], 0.0, atol=2e-3)


def test_reset_with_a_seed_is_deterministic_and_options_change_the_episode() -> None:
    env = _env("gait")
    action = np.array([0.5, -0.5, 0.0, 0.0], dtype=np.float32)
    _, first, obs_first = _episode(env, 7, action)
    _, again, obs_again = _episode(env, 7, action)
    np.testing.assert_array_equal(np.array(first), np.array(again))
    np.testing.assert_array_equal(np.array(obs_first), np.array(obs_again))
    _, _, obs_heavy = _episode(env, 7, action, {"mass_scale": 1.5, "friction": 0.5})
    assert np.any(np.array(obs_heavy) != np.array(obs_first))
    with pytest.raises(ValueError, match="no option 'gravity'"):
        env.reset(options={"gravity": 1.0})
    env.close()


def test_the_gait_action_stays_within_the_dynamic_parameter_ranges() -> None:
    env = _env("gait", command=(0.5, 0.0, 0.0))
    env.reset(seed=0)
    for _ in range(STEPS):
        env.step(np.ones(4, dtype=np.float32))
    parameters = env._loop.controller.parameters if env._loop is not None else {}
    for name in GAIT_PARAMETERS:
        spec = getattr(env.robot.walker, name)
        assert spec.min <= parameters[name] <= spec.max
    assert parameters["step_frequency"] == pytest.approx(env.robot.walker.step_frequency.max)
    env.close()


def test_around_maps_zero_to_the_default_and_the_ends_to_the_range() -> None:
    assert around(0.0, 0.1, 0.5, 2.0) == 0.5
    assert around(-1.0, 0.1, 0.5, 2.0) == pytest.approx(0.1)
    assert around(1.0, 0.1, 0.5, 2.0) == pytest.approx(2.0)
    assert around(7.0, 0.1, 0.5, 2.0) == pytest.approx(2.0)


def test_support_margin_of_a_square_and_outside_it() -> None:
    square = np.array([[0.1, 0.1], [-0.1, 0.1], [-0.1, -0.1], [0.1, -0.1]])
    assert support_margin(square) == pytest.approx(0.1)
    assert support_margin(square + np.array([0.15, 0.0])) == pytest.approx(-0.05)
    assert support_margin(square[:2]) == -0.1


def test_reward_terms_are_named_and_an_unknown_one_is_refused() -> None:
    env = _env("gait", reward={"stability": 1.0})
    env.reset(seed=0)
    _, reward, _, _, info = env.step(np.zeros(4, dtype=np.float32))
    assert set(info["terms"]) == set(TERMS)
    assert info["terms"]["stability"] > 0  # standing on six feet, the body over them
    assert reward == pytest.approx(sum(env.rewards.weights[k] * v for k, v in info["terms"].items()))
    env.close()
    with pytest.raises(ValueError, match="no term 'speed'"):
        WalkEnv(reward={"speed": 1.0})


def test_the_example_of_docs_gym_runs(capsys: pytest.CaptureFixture[str]) -> None:
    import re

    from .conftest import ROOT

    page = (ROOT / "docs" / "gym.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", page, flags=re.S)
    assert len(blocks) == 1
    exec(compile(blocks[0], "docs/gym.md", "exec"), {})
    assert capsys.readouterr().out.strip() == "(94,) ['cot', 'fall', 'joint_limits', 'stability', 'tracking']"


def test_out_writes_each_episode_as_the_run_directory_of_shc_simulate(tmp_path: Path) -> None:
    """With ``out=DIR`` and zero residuals an episode's log.csv is byte for byte that of ``shc simulate``."""
    from shc_cli.api import simulate

    run = simulate("bullet", velocity="0.6,0,0.2", duration=STEPS * 0.01, seed=3, out=tmp_path / "run", plots=False)
    env = _env("residual", command="0.6,0,0.2", out=str(tmp_path / "episodes"))
    _episode(env, 3, np.zeros(env.action_size, dtype=np.float32))
    env.close()
    assert [p.name for p in env.written] == ["episode-0001"]
    episode = env.written[0]
    assert (episode / "log.csv").read_bytes() == (run.path / "log.csv").read_bytes()
    assert (episode / "robot.toml").read_bytes() == (run.path / "robot.toml").read_bytes()
    import json

    mine, theirs = (json.loads((p / "summary.json").read_text()) for p in (episode, run.path))
    for key in ("sim_time_s", "distance_m", "cot", "fell", "stop_reason", "complete", "mean_power_w", "seed"):
        assert mine[key] == theirs[key], key


@pytest.mark.slow
def test_the_gait_search_example_lowers_the_cost_of_transport_at_equal_speed() -> None:
    """docs/experiments/gym_gait_search.py (seeded, 2 iterations of 6): a gait found through the environment walks
    at the defaults' speed (within 5 %) for less than the defaults' CoT."""
    import re
    import subprocess
    import sys

    from .conftest import ROOT

    done = subprocess.run([sys.executable, str(ROOT / "docs" / "experiments" / "gym_gait_search.py"),
                           "--iterations", "2"], capture_output=True, text=True, timeout=600, check=True)
    base = re.search(r"defaults: CoT ([\d.]+) at ([\d.]+) m/s", done.stdout)
    found = re.search(r"found: CoT ([\d.]+) against [\d.]+ of the defaults .* at ([\d.]+) m/s", done.stdout)
    assert base is not None and found is not None, done.stdout
    assert float(found[1]) < float(base[1])
    assert abs(float(found[2]) / float(base[2]) - 1.0) <= 0.05


def test_the_observation_holds_the_reading_in_the_documented_order() -> None:
    env = _env("residual")
    env.reset(seed=0)
    obs, _, _, _, _ = env.step(np.zeros(env.action_size, dtype=np.float32))
    assert env._backend is not None and env._backend.reading is not None and env._loop is not None
    reading = env._backend.reading
    named = dict(zip(env.names, obs.tolist(), strict=True))
    leg, joint = next(iter(env.robot.legs.items()))
    first = f"{leg}.{next(iter(joint.joints))}"
    assert named[f"q.{first}"] == pytest.approx(float(reading.joints[0, 0]), abs=1e-6)
    assert named[f"dq.{first}"] == pytest.approx(float(reading.joint_velocities[0, 0]), abs=1e-4)
    quaternion = [named[k] for k in ("qx", "qy", "qz", "qw")]
    np.testing.assert_allclose(quaternion, reading.orientation, atol=1e-6)
    assert np.linalg.norm(quaternion) == pytest.approx(1.0, abs=1e-5)
    legs = list(env.robot.legs)
    np.testing.assert_array_equal([named[f"contact.{leg}"] for leg in legs], reading.foot_contact.astype(float))
    np.testing.assert_allclose([named[f"force.{leg}"] for leg in legs], reading.foot_forces, rtol=1e-6)
    assert named["cmd.vx"] > 0 and named["cmd.vy"] == 0.0  # walking forward, as commanded
    assert all(-1.0 <= named[f"{kind}.{leg}"] <= 1.0 for kind in ("stance", "swing") for leg in legs)
    env.close()


_UNIT = st.floats(-1.0, 1.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(st.lists(_UNIT, min_size=4, max_size=4), st.tuples(_UNIT, _UNIT, _UNIT))
def test_any_gait_action_stays_in_the_ranges_and_the_throttle(action: list[float],
                                                              velocity: tuple[float, float, float]) -> None:
    from shc_cli.loop.policy.actions import VELOCITY_SCALE, GaitAction

    robot = _bullet()
    gait = GaitAction(robot)
    gait.set(np.array(action))
    defaults = {name: getattr(robot.walker, name).default for name in GAIT_PARAMETERS}
    command = gait.command(Command(velocity=velocity), defaults, new_step_cycle=True)
    for name, value in command.parameters.items():
        spec = getattr(robot.walker, name)
        assert spec.min <= value <= spec.max
    assert VELOCITY_SCALE[0] <= gait.scale <= VELOCITY_SCALE[1]
    assert all(abs(v) <= 1.0 for v in command.velocity)
    unchanged = gait.command(Command(velocity=velocity), dict(gait.values), new_step_cycle=True)
    assert unchanged.parameters == {}  # nothing to send when the controller already has the values


@settings(max_examples=40, deadline=None)
@given(st.lists(_UNIT, min_size=18, max_size=18))
def test_any_residual_keeps_the_joint_targets_within_the_limits(action: list[float]) -> None:
    from shc_cli.loop.policy.actions import ResidualAction
    from shc_cli.model.chains import Chains

    robot = _bullet()
    residual = ResidualAction(robot, limit=0.05)
    chains = Chains.from_robot(robot)
    joints = (chains.lower + chains.upper) / 2
    legs = joints.shape[0]
    out = CycleOutput(joints, np.zeros_like(joints), np.zeros((legs, 3)), np.zeros((legs, 3)), np.zeros((legs, 3)),
                      np.full(legs, -1.0), np.full(legs, -1.0), (0.0, 0.0, 0.0), (0.0,) * 6,
                      RobotState.RUNNING, WalkState.STOPPED)
    residual.set(np.array(action))
    moved = residual.adjust(out).joints
    assert np.all(moved >= chains.lower) and np.all(moved <= chains.upper)
    if not any(action):
        assert moved is joints


def test_a_servo_option_changes_the_power_and_an_unknown_number_is_refused() -> None:
    env = _env("gait")
    power = {}
    for factor in (1.0, 2.0):
        env.reset(seed=0, options={"servo": {"winding_resistance": factor}})
        _, _, _, _, info = env.step(np.zeros(env.action_size, dtype=np.float32))
        power[factor] = info["power_w"]
    assert power[2.0] > power[1.0]  # twice the copper loss
    with pytest.raises(ValueError, match="servo has no number 'colour'"):
        env.reset(options={"servo": {"colour": 1.0}})
    env.close()


def test_a_policy_file_plays_into_a_run_directory(tmp_path: Path) -> None:
    import json

    from shc_cli.gym.policy import Policy, play

    names = observation_names(_bullet())
    file = tmp_path / "gait.npz"
    Policy.constant("gait", np.array([0.5, 0.0, 0.0, 0.0]), len(names)).save(file)
    policy = Policy.load(file)
    assert policy.action == "gait" and policy(np.ones(len(names), dtype=np.float32)).tolist() == [0.5, 0.0, 0.0, 0.0]
    path = play(policy, tmp_path / "runs", command="0.5,0,0", duration=0.5)
    summary = json.loads((path / "summary.json").read_text())
    assert summary["complete"] and not summary["fell"]
    frequency = _bullet().walker.step_frequency
    assert summary["step_frequency_hz"] == pytest.approx(frequency.default + 0.5 * (frequency.max - frequency.default))
    with pytest.raises(ValueError, match=r"do not fit this robot's \(4, 50\)"):
        play(policy, tmp_path / "quad", robot="quadruped", duration=0.1)
