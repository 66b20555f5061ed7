"""MuJoCo's control period in one compiled kernel (:mod:`shc_cli.backends.mujoco_.substeps`): the same state, forces
and power as the Python loop over ``mj_step`` it replaced, to the last bit, for every ``[servo] control``; MuJoCo's
warnings still reach the world and an ``mju_error`` inside the kernel's ``mj_step`` is the binding's
``mujoco.FatalError`` (not MuJoCo's default: print, log file, exit)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shc_cli.backends.engine import EngineOptions
from shc_cli.backends.mujoco_.world import MujocoWorld
from shc_cli.backends.simulated import open_world
from shc_cli.backends.terrain import parse_terrain
from shc_cli.spec.loading import load_robot


def _world(name: str, control: str | None = None, python: bool = False):  # type: ignore[no-untyped-def]
    """A MuJoCo world of robot ``name`` standing on flat ground (``control`` overriding its servos'); ``python``:
    the physics steps from Python (the loop the kernel replaced)."""
    robot = load_robot(name).robot
    assert robot is not None
    if control is not None:
        robot = robot.model_copy(update={"servo": robot.servo.model_copy(update={"control": control})})
    world = open_world(robot, EngineOptions(parse_terrain("flat"), 4, False, engine="mujoco"))
    assert isinstance(world, MujocoWorld)
    assert world._pointers is not None  # this MuJoCo's library is callable: the kernel runs
    if python:
        world._pointers = None
    return world


@pytest.mark.parametrize(("name", "control"), [("bullet", None), ("bullet_insectoid_b", None), ("athena", None),
                                                ("bullet", "pd"), ("bullet", "position")])
def test_the_compiled_period_is_the_python_loop_to_the_last_bit(name: str, control: str | None) -> None:
    compiled, python = _world(name, control), _world(name, control, python=True)
    rng = np.random.default_rng(3)
    targets = compiled.read().joints
    try:
        for period in range(150):
            if period % 10 == 0:  # new goals: the servos work (torque limits, the I term, the velocity clamp)
                targets = targets + rng.normal(0.0, 0.15, targets.shape)
            for world in (compiled, python):
                world.command(targets)
                world.step()
            a, b = compiled.read(), python.read()
            for field in ("joints", "joint_velocities", "joint_efforts", "servo_power", "position", "foot_forces"):
                assert np.array_equal(getattr(a, field), getattr(b, field)), (period, field)
        assert np.array_equal(compiled.data.qpos, python.data.qpos)
        assert np.array_equal(compiled.data.ctrl, python.data.ctrl)
        assert compiled.physics_time > 0.0 and python.physics_time > 0.0
    finally:
        compiled.close()
        python.close()


def test_a_mujoco_warning_inside_the_kernel_reaches_the_world() -> None:
    texts = []
    for python in (False, True):
        world = _world("bullet", python=python)
        world.data.qvel[:] = 1e20  # MuJoCo: "Nan, Inf or huge value in QVEL … The simulation is unstable", reset
        world.step()
        texts.append(world.warnings)
        world.close()
    assert texts[0] == texts[1]
    assert len(texts[0]) == 1 and "QVEL" in texts[0][0] and "unstable" in texts[0][0]


def test_an_mju_error_inside_the_kernel_is_the_bindings_fatal_error(tmp_path: Path,
                                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """An invalid integrator makes ``mj_step`` call ``mju_error``: with the kernel's guard the process goes on
    (MuJoCo's own handler would print, append to MUJOCO_LOG.TXT and exit) with the binding's exception and text,
    and the next step of a repaired model runs."""
    import mujoco

    monkeypatch.chdir(tmp_path)
    messages = []
    for python in (False, True):
        world = _world("bullet", python=python)
        world.step()
        world.model.opt.integrator = 99
        with pytest.raises(mujoco.FatalError) as raised:
            world.step()
        messages.append(str(raised.value))
        world.model.opt.integrator = 0
        world.step()
        world.close()
    assert messages[0] == messages[1] == "mj_step: invalid integrator"
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_another_mujoco_release_steps_from_python() -> None:
    """The kernels read MuJoCo's ``mjLogMessage`` at fixed offsets and call its private log-handler entry points,
    checked on one release: any other steps from Python instead (never a struct read at a moved offset)."""
    import types

    import mujoco

    from shc_cli.backends.mujoco_ import substeps

    assert substeps.entries(mujoco) is not None  # the release installed here is the checked one
    assert mujoco.__version__.startswith(substeps.CHECKED_VERSION)
    for version in ("4.1.0", "3.3.7", "5.0.0", "40.0.1"):
        other = types.SimpleNamespace(__version__=version, __file__=mujoco.__file__)
        assert substeps.entries(other) is None, version
