"""SimulationConfig: every ``shc simulate`` option validated once, with the command line's one-line errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from shc_cli.backends.engine_registry import ENGINES, OPENERS
from shc_cli.domain.config import SimulationConfig, SimulationOptions
from shc_cli.errors import SpecError


def test_defaults_are_the_command_lines() -> None:
    config = SimulationConfig()
    assert (config.robot, config.velocity, config.terrain, config.scenario, config.physics_rate, config.engine) == (
        "bullet", "1,0,0", "flat", "WG", 400.0, "mujoco")
    assert config.walking and not config.airborne


def test_from_options_takes_a_sweep_points_values() -> None:
    config = SimulationConfig.from_options({"robot": "bullet", "gait": "", "scenario": "sa", "stand": None,
                                            "duration": 3, "engine": "mujoco"}, out="x")
    assert config.gait is None and config.scenario == "SA" and config.airborne and not config.walking
    assert config.duration == 3.0 and config.out == Path("x") and config.engine == "mujoco"


def test_replace_validates_again_and_keeps_the_rest() -> None:
    config = SimulationConfig(seed=4, velocity=(0.5, 0, 0))
    assert config.velocity == "0.5,0.0,0.0"
    assert config.replace(friction=0.5).seed == 4
    with pytest.raises(SpecError, match="--start: 'sideways' is not a start pose"):
        config.replace(start="sideways")


@pytest.mark.parametrize(("options", "message"), [
    ({"engine": "ode"}, "--engine: 'ode' is not a physics engine (use mujoco or pybullet)"),
    ({"scenario": "xx"}, "--scenario: 'XX' is not a scenario"),
    ({"inclination": "up"}, "--inclination: 'up' is not a mode"),
    ({"posture": "kz=2"}, "--posture: kz='2' is not a gain in [0, 1]"),
    ({"terrain": "lava"}, "unknown terrain 'lava'"),
    ({"seed": 1.5}, "--seed: 1.5"),
    ({"speed": 1}, "speed: 'speed' is not an option of simulate"),
])
def test_a_bad_option_is_one_line(options: dict[str, object], message: str) -> None:
    with pytest.raises(SpecError) as raised:
        SimulationConfig.from_options(options)
    assert message in str(raised.value) and "\n" not in str(raised.value)


def test_the_physics_rate_must_be_a_multiple_of_the_control_rate() -> None:
    from shc_cli.api import load_robot

    robot = load_robot("bullet")
    assert SimulationConfig().substeps(robot) == round(400 * robot.time_delta)
    with pytest.raises(SpecError, match="--physics-rate: 333 Hz is not a whole multiple"):
        SimulationConfig(physics_rate=333).substeps(robot)


def test_the_typed_keywords_are_the_configs_fields() -> None:
    assert set(SimulationOptions.__annotations__) | {"robot"} == set(SimulationConfig.model_fields)


def test_one_engine_registry() -> None:
    assert tuple(OPENERS) == ENGINES
    assert SimulationConfig.model_fields["engine"].default == ENGINES[0]
