"""Compile shc's numba kernels into numba's cache ahead of the first real command (``shc warmup``).

The kinematics (:mod:`shc_cli.model.kernels`), the walk (:mod:`shc_cli.control.stepping`), the leg odometry
(:mod:`shc_cli.control.odometry_kernels`) and admittance control (:mod:`shc_cli.control.admittance`) are compiled
by numba on first use and cached beside their sources (the editable install's ``__pycache__``); later processes
load them in milliseconds. Compiling takes ≈ 10 s on a 2-core
machine (≈ 5× a short simulation; docs/performance.md), so the README's set-up command runs this once: the first
``shc simulate`` of a new install then starts as fast as the second.

The kernels are compiled by running what calls them, with the types the commands pass (numba compiles one version
per argument-type signature): the servo laws of every ``[servo] control`` and MuJoCo's compiled control period
(:mod:`shc_cli.backends.mujoco_.substeps`) of each, then a short simulation — start-up, the
workspace search, walking — with and without admittance control, into a throwaway run directory.
A robot that verifies its speed limits (``bullet_verified``, :mod:`shc_cli.control.verified_limits`) pays its trial
walks at its first run of each gait instead (cached).
"""

from __future__ import annotations

import logging
import tempfile
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


def warm_up() -> float:
    """Compile (or load) every kernel; returns the seconds it took."""
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.simulate import simulate

    started = time.perf_counter()
    _servo_laws()
    with tempfile.TemporaryDirectory(prefix="shc-warmup-") as folder:
        for admittance in (False, True):
            out = Path(folder) / f"admittance-{admittance}"
            simulate(SimulationConfig(duration=0.2, out=out, plots=False, admittance=admittance))
            log.debug("warm-up run %s done", out.name)
    return time.perf_counter() - started


def _servo_laws() -> None:
    """The servo kernels of every ``[servo] control`` (the default robot's simulation uses one of them)."""
    import numpy as np

    from shc_cli.backends import servo_kernels
    from shc_cli.backends.servo import ServoModel
    from shc_cli.spec.loading import load_robot

    robot = load_robot("bullet").robot
    assert robot is not None
    zeros = np.zeros(len(robot.legs) * 3)
    for control in ("position", "pd", "dynamixel"):
        model = ServoModel(robot.servo.model_copy(update={"control": control}))
        model.torque(zeros, zeros, zeros, 0.001)
        model.power(zeros, zeros)
    servo_kernels.velocity_motor(zeros, zeros, zeros, 1.0, 0.5, 1.0, zeros.copy())
    servo_kernels.velocity_motor_force(zeros, zeros, 1.0, 1.0, zeros.copy())
    _mujoco_periods(robot)


def _mujoco_periods(robot: Robot) -> None:
    """MuJoCo's control period kernel of every ``[servo] control``: one period of the robot held in the air."""
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.engine_registry import open_engine
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.model.chains import Chains

    joints = Chains.from_robot(robot).default_joints()
    for control in ("position", "pd", "dynamixel"):
        servo = robot.servo.model_copy(update={"control": control})
        world = open_engine(robot.model_copy(update={"servo": servo}),
                            EngineOptions(parse_terrain("flat"), 4, True, engine="mujoco"), joints)
        try:
            world.step()
        finally:
            world.close()
