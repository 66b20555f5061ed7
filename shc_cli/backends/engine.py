"""The physics-engine interface of the simulator: what the simulation loop needs from PyBullet or MuJoCo.

An :class:`Engine` holds one robot on one terrain in one scenario (on the ground, held in the air, or started on a
stand) and is advanced one control period at a time: :meth:`Engine.command` takes the controller's joint targets for
the servos, :meth:`Engine.step` runs the physics steps of one control period and :meth:`Engine.read` returns what
the robot's sensors see (:class:`Reading`). :func:`shc_cli.backends.engine_registry.open_engine` opens one by name. What
does not depend on the engine lives beside this module and is used by both: the terrain geometry
(:mod:`shc_cli.backends.terrain`), the IMU model and its noise (:mod:`shc_cli.backends.imu`), the servos' electrical
power (:mod:`shc_cli.backends.power`) and the spawn height (:func:`spawn_height`). Fall detection, logging and the
run directory belong to the loop, which sees only this interface.

Nothing here imports an engine: ``pybullet`` and ``mujoco`` are imported by
:func:`shc_cli.backends.engine_registry.open_engine` when asked for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal, Protocol

import numpy as np

if TYPE_CHECKING:
    from shc_cli.backends.terrain import Terrain, TerrainSpec
    from shc_cli.spec.robot import Robot

EngineName = Literal["mujoco", "pybullet"]
"""A physics engine's name, as ``--engine`` takes it (the list and the openers: :mod:`.engine_registry`)."""

SPAWN_GAP = 0.01
"""Height of the lowest foot above the ground when the robot is spawned [m]."""
AIR_LIFT = 0.3
"""In the air scenarios the body is held this far above its standing height, so no foot reaches the ground [m]."""


@dataclass(frozen=True)
class EngineOptions:
    """How a physics world is built: the engine, the terrain, the physics step and the spawn (``shc simulate``'s
    physics options, made by :meth:`shc_cli.domain.config.SimulationConfig.engine_options`).

    Attributes:
        terrain: the terrain (:func:`shc_cli.backends.terrain.parse_terrain`).
        substeps: physics steps per control period (physics rate = substeps / the robot's ``time_delta``).
        fixed_base: hold the body in the air, :data:`AIR_LIFT` above its standing height (scenarios SA, WA).
        friction: friction of feet and terrain, as PyBullet's ``lateralFriction`` of both: the coefficient
            between them is ``friction²`` in both engines (docs/physics-model.md).
        restitution: restitution of feet and terrain, as PyBullet's ``restitution`` of both (docs/physics-model.md).
        seed: seed of every random thing (terrain blocks, IMU noise).
        imu_noise: standard deviation of IMU noise (rad/s, m/s² alike); 0 = none.
        imu_yaw_bias: the IMU gyro's yaw-rate bias [rad/s]; 0 = none (:class:`shc_cli.backends.imu.Imu`).
        start_pose: spawn pose, ``"unpacked"`` or ``"packed"`` (:func:`shc_cli.backends.simulated.open_world`).
        gui: open the engine's viewer (PyBullet only).
        stand: spawn the body at its standing height held by a removable support (:meth:`Engine.release_stand`)
            instead of on its feet just above the ground (ignored with ``fixed_base``).
        engine: the physics engine (:data:`shc_cli.backends.engine_registry.ENGINES`).
    """

    terrain: TerrainSpec
    substeps: int
    fixed_base: bool = False
    friction: float = 0.9
    restitution: float = 0.0
    seed: int = 0
    imu_noise: float = 0.0
    start_pose: str = "unpacked"
    gui: bool = False
    stand: bool = False
    engine: EngineName = "mujoco"  # the default engine (engine_registry.DEFAULT_ENGINE)
    imu_yaw_bias: float = 0.0


@dataclass(slots=True)
class Reading:
    """What the robot's sensors report after a control period (legs in id order, joints leg by leg).

    Made once a control cycle, so not a frozen dataclass (whose ``__init__`` sets each of the 14 fields through
    ``object.__setattr__``: 1.2 µs more a cycle); nothing changes a reading once made.

    Attributes:
        joints: joint positions ``(L, n)`` [rad] (0 where a leg has fewer joints).
        joint_velocities: ``(L, n)`` [rad/s].
        joint_efforts: motor torques averaged over the control period's physics steps ``(L, n)`` [N·m].
        servo_power: electrical power of each servo averaged over the same steps ``(L, n)`` [W].
        orientation: IMU orientation quaternion (x, y, z, w), world → body.
        angular_rate: IMU angular velocity in the body frame [rad/s].
        linear_acceleration: IMU specific force in the body frame (gravity included, at rest +9.81 z) [m/s²].
        foot_forces: contact normal force on each foot ``(L,)`` [N].
        foot_contact: whether each foot touches anything ``(L,)``.
        body_height: height of the body origin above the terrain below it (ray) [m].
        position: ground-truth body position [m].
        rpy: ground-truth roll, pitch, yaw [rad].
        linear_velocity: ground-truth body velocity in the world frame [m/s].
        angular_velocity: ground-truth body angular velocity in the world frame [rad/s].
    """

    joints: np.ndarray
    joint_velocities: np.ndarray
    joint_efforts: np.ndarray
    servo_power: np.ndarray
    orientation: np.ndarray
    angular_rate: np.ndarray
    linear_acceleration: np.ndarray
    foot_forces: np.ndarray
    foot_contact: np.ndarray
    body_height: float
    position: np.ndarray
    rpy: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray


class Engine(Protocol):
    """One robot on one terrain in a physics engine, advanced one control period at a time.

    Attributes:
        name: the engine's name (one of :data:`shc_cli.backends.engine_registry.ENGINES`).
        version: the engine's version, e.g. ``"3.2.7"``.
        robot: the simulated robot.
        terrain: the built terrain (its analytic ground height).
        control_period: the controller's period [s].
        substeps: physics steps per control period.
        physics_time: wall time spent inside the engine's physics steps so far [s].
        stand: the support holding the body at standing height (``--stand`` start), ``None`` once released or
            if there is none.
        slot_rows, slot_cols: row (leg) and column (joint) of each servo in the padded ``(L, n)`` arrays, so that
            ``a[slot_rows, slot_cols]`` lists the real joints of ``a`` in servo (= log column) order.
    """

    name: str
    version: str
    robot: Robot
    terrain: Terrain
    control_period: float
    substeps: int
    physics_time: float
    slot_rows: np.ndarray
    slot_cols: np.ndarray

    @property
    def stand(self) -> object | None:
        """The support holding the body, ``None`` once released or if there is none."""

    @property
    def warnings(self) -> list[str]:
        """The engine's own warnings since it opened (distinct texts), e.g. an unstable simulation."""

    def command(self, targets: np.ndarray) -> None:
        """Position targets of every servo ``(L, n)`` [rad] for the next control period."""

    def step(self) -> None:
        """Advance one control period (``substeps`` physics steps)."""

    def read(self) -> Reading:
        """The sensors after the last step."""

    def release_stand(self) -> None:
        """Take the stand away (nothing if there is none): the robot now carries itself."""

    def close(self) -> None:
        """Free the engine's resources."""


def spawn_height(robot: Robot, terrain: Terrain, joints: np.ndarray, fixed_base: bool, stand: bool) -> float:
    """Height of the body frame (``base_link``) at spawn [m], the same in every engine.

    In the air: :data:`AIR_LIFT` above the standing height; on a stand: the standing height (the feet's centres
    ``body_clearance`` below the body, on the walk plane); else the lowest foot :data:`SPAWN_GAP` above the
    ground at the origin.
    """
    from shc_cli.model.body import foot_radius
    from shc_cli.model.chains import Chains

    tips = Chains.from_robot(robot).tips(joints)
    feet = [foot_radius(leg) for leg in robot.legs.values()]
    ground = terrain.height_at(0.0, 0.0)
    if fixed_base:
        return ground + robot.walker.body_clearance + AIR_LIFT
    if stand:
        return ground + robot.walker.body_clearance + max(feet)
    return ground + SPAWN_GAP + max(-float(tips[i, 2]) + feet[i] for i in range(len(feet)))


def tilt(rpy: np.ndarray) -> float:
    """Angle between the body's z axis and the vertical [rad]."""
    roll, pitch = float(rpy[0]), float(rpy[1])
    return math.acos(max(-1.0, min(1.0, math.cos(roll) * math.cos(pitch))))


def rpy_from_matrix(rotation: np.ndarray) -> np.ndarray:
    """Roll, pitch, yaw [rad] of a rotation ``R = Rz(yaw)·Ry(pitch)·Rx(roll)`` (as PyBullet's Euler angles).

    One matrix per engine step, so plain ``math`` rather than the batched scipy
    :func:`shc_cli.analysis.metrics.rpy_of` (same convention), whose per-call overhead (≈ 50 µs against ≈ 1.3 µs
    here) would land on every step."""
    r = np.asarray(rotation, dtype=float).tolist()  # the same floats as float(r[i, j]), in one call
    pitch = math.asin(max(-1.0, min(1.0, -r[2][0])))
    return np.array([math.atan2(r[2][1], r[2][2]), pitch, math.atan2(r[1][0], r[0][0])])
