"""The physics engines by name (``--engine``): the one list of engine names and how each is opened.

Above :mod:`shc_cli.backends.engine` (the interface) and the engines that implement it, so the interface never
imports an engine (no import circle); ``pybullet`` and ``mujoco`` are imported only when one is opened.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Literal, get_args

from shc_cli.backends.engine import AIR_LIFT as AIR_LIFT
from shc_cli.backends.engine import Engine

if TYPE_CHECKING:
    import numpy as np

    from shc_cli.backends.terrain import TerrainSpec
    from shc_cli.spec.robot import Robot

EngineName = Literal["pybullet", "mujoco"]
"""A physics engine's name, as ``--engine`` takes it."""
ENGINES: tuple[EngineName, ...] = get_args(EngineName)
"""The physics engines ``--engine`` takes; the first is the default."""
DEFAULT_ENGINE: EngineName = ENGINES[0]

Opener = Callable[["Robot", "TerrainSpec", float, int, bool, "np.ndarray", float, float, int, float, bool, bool],
                  Engine]
"""Opens one engine: ``(robot, terrain, control_period, substeps, fixed_base, initial_joints, friction,
restitution, seed, imu_noise, gui, stand)`` (as :func:`open_engine`)."""


def _open_pybullet(robot: Robot, terrain: TerrainSpec, control_period: float, substeps: int, fixed_base: bool,
                   initial_joints: np.ndarray, friction: float, restitution: float, seed: int, imu_noise: float,
                   gui: bool, stand: bool) -> Engine:
    from shc_cli.backends.pybullet_.world import World

    return World(robot, terrain, control_period, substeps, fixed_base, initial_joints, friction, restitution, seed,
                 imu_noise, gui, stand)


def _open_mujoco(robot: Robot, terrain: TerrainSpec, control_period: float, substeps: int, fixed_base: bool,
                 initial_joints: np.ndarray, friction: float, restitution: float, seed: int, imu_noise: float,
                 gui: bool, stand: bool) -> Engine:
    from shc_cli.errors import BackendError

    if gui:
        raise BackendError("MuJoCo: the simulator has no viewer here; run without --gui or with --engine pybullet")
    from shc_cli.backends.mujoco_.world import MujocoWorld

    return MujocoWorld(robot, terrain, control_period, substeps, fixed_base, initial_joints, friction, restitution,
                       seed, imu_noise, stand)


OPENERS: dict[EngineName, Opener] = {"pybullet": _open_pybullet, "mujoco": _open_mujoco}
"""Engine name → the function that opens it (the same names as :data:`ENGINES`)."""
assert tuple(OPENERS) == ENGINES


def open_engine(name: str, robot: Robot, terrain: TerrainSpec, control_period: float, substeps: int,
                fixed_base: bool, initial_joints: np.ndarray, friction: float = 0.9, restitution: float = 0.0,
                seed: int = 0, imu_noise: float = 0.0, gui: bool = False, stand: bool = False) -> Engine:
    """Open physics engine ``name`` with the robot spawned on the terrain.

    Args:
        name: one of :data:`ENGINES`.
        robot: the robot.
        terrain: the terrain.
        control_period: the controller's period [s].
        substeps: physics steps per control period (physics rate = substeps / control_period).
        fixed_base: hold the body in the air, :data:`AIR_LIFT` above its standing height (scenarios SA, WA).
        initial_joints: joint positions to spawn with ``(L, n)`` [rad].
        friction: friction of feet and terrain, as PyBullet's ``lateralFriction`` of both: the coefficient
            between them is ``friction²`` in both engines (docs/physics-model.md).
        restitution: restitution of feet and terrain, as PyBullet's ``restitution`` of both (docs/physics-model.md).
        seed: seed of every random thing (terrain blocks, IMU noise).
        imu_noise: standard deviation of IMU noise (rad/s, m/s² alike); 0 = none.
        gui: open the engine's viewer (PyBullet only).
        stand: spawn the body at its standing height held by a removable support (:meth:`Engine.release_stand`)
            instead of on its feet just above the ground.

    Raises:
        BackendError: an unknown engine, or a GUI that cannot open.
    """
    from shc_cli.errors import BackendError

    if name not in ENGINES:
        raise BackendError(f"unknown physics engine '{name}'; use {' or '.join(ENGINES)}")
    return OPENERS[name](robot, terrain, control_period, substeps, fixed_base, initial_joints, friction,
                         restitution, seed, imu_noise, gui, stand)
