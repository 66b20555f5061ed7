"""Opening a physics engine by name (``--engine``): above :mod:`shc_cli.backends.engine` (the interface) and the
engines that implement it, so the interface never imports an engine (no import circle).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from shc_cli.backends.engine import AIR_LIFT as AIR_LIFT
from shc_cli.backends.engine import ENGINES, Engine

if TYPE_CHECKING:
    import numpy as np

    from shc_cli.backends.terrain import TerrainSpec
    from shc_cli.spec.robot import Robot


def open_engine(name: str, robot: Robot, terrain: TerrainSpec, control_period: float, substeps: int,
                fixed_base: bool, initial_joints: np.ndarray, friction: float = 0.9, restitution: float = 0.0,
                seed: int = 0, imu_noise: float = 0.0, gui: bool = False, stand: bool = False) -> Engine:
    """Open physics engine ``name`` with the robot spawned on the terrain.

    Args:
        name: ``"pybullet"`` or ``"mujoco"`` (:data:`ENGINES`).
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

    if name == "pybullet":
        from shc_cli.backends.pybullet_.world import World

        return World(robot, terrain, control_period, substeps, fixed_base, initial_joints, friction, restitution,
                     seed, imu_noise, gui, stand)
    if name == "mujoco":
        if gui:
            raise BackendError("MuJoCo: the simulator has no viewer here; run without --gui or with --engine "
                               "pybullet")
        from shc_cli.backends.mujoco_.world import MujocoWorld

        return MujocoWorld(robot, terrain, control_period, substeps, fixed_base, initial_joints, friction,
                           restitution, seed, imu_noise, stand)
    raise BackendError(f"unknown physics engine '{name}'; use {' or '.join(ENGINES)}")
