"""The MuJoCo engine (:class:`~shc_cli.backends.engine.Engine`): robot, terrain, servos and sensors.

The model is MJCF built in code (:mod:`shc_cli.backends.mujoco_.mjcf`), the same bodies PyBullet loads. Servos
behave as PyBullet's (docs/physics-model.md):

* ``position`` control: PyBullet's POSITION_CONTROL motor asks each physics step for the joint speed
  ``v* = position_gain·(q* − q)/h + (1 − velocity_gain)·v`` (h the physics step) and reaches it within the stall
  torque. Here every physics step sets ``v*`` (clipped to ± the no-load speed) as the target of a velocity
  actuator of gain ``kv`` (:func:`~shc_cli.backends.mujoco_.mjcf.velocity_stiffness`, integrated implicitly)
  limited to ± the stall torque. The joints carry the gearbox's reflected rotor inertia
  (:func:`~shc_cli.backends.mujoco_.mjcf.armature`), which keeps light links stable when the torque limit
  clamps (MuJoCo integrates a clamped actuator explicitly).
* ``pd`` control: a position actuator ``τ = stiffness·(q* − q) − damping·q̇`` within ± the torque limit, with the
  gains of :meth:`~shc_cli.backends.servo.ServoModel.gains` (implicit in the damping, as PyBullet's stable PD); the
  servo's ``armature`` as joint armature.
* ``dynamixel`` control: a torque motor set every physics step to
  :meth:`~shc_cli.backends.servo.ServoModel.torque` of the state before the step (PWM limit, torque–speed line,
  current limit), exactly PyBullet's explicit law; the servo's ``armature`` as joint armature.

Torque and speed are averaged over each control period's physics steps and turned into electrical power by the
engine-independent :meth:`~shc_cli.backends.servo.ServoModel.power`, exactly as in PyBullet. A control period — the
servo law, ``mj_step`` and the sums of every physics step, then the means and the power — runs in one compiled
kernel (:mod:`~shc_cli.backends.mujoco_.substeps`: the same operations as the Python loop it replaced, which stays
for a MuJoCo library it cannot call). ``mujoco`` is imported
here only; it needs no GL to simulate.
"""

from __future__ import annotations

import logging
import time
from typing import Any

import numpy as np

from shc_cli.backends import servo_kernels
from shc_cli.backends.engine import EngineOptions, Reading, rpy_from_matrix, spawn_height
from shc_cli.backends.imu import Imu
from shc_cli.backends.mujoco_ import substeps as substeps_kernels
from shc_cli.backends.mujoco_.gl import import_for_physics
from shc_cli.backends.mujoco_.mjcf import RESTITUTION_THRESHOLD_MPS, Options, robot_mjcf, velocity_stiffness
from shc_cli.backends.servo import ServoModel
from shc_cli.backends.terrain import Terrain, robot_scale
from shc_cli.errors import BackendError
from shc_cli.events import NOTICE, event
from shc_cli.model.body import leg_names
from shc_cli.model.chains import JointSlots
from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

RAY_GROUPS = np.array([1, 0, 0, 0, 0, 0], dtype=np.uint8)
"""Geom groups the height ray sees: the terrain's (0), not the robot's."""
DOWN = np.array([0.0, 0.0, -1.0])
DOWN.flags.writeable = False
"""The height ray's direction."""


class MujocoWorld:
    """A MuJoCo model and data holding one robot on one terrain.

    Args:
        robot: the robot; its ``time_delta`` is the control period.
        options: terrain, physics steps per control period, fixed base (no free joint,
            :data:`~shc_cli.backends.engine.AIR_LIFT` above its standing height), PyBullet-style friction and
            restitution of feet and terrain (docs/physics-model.md), seed, IMU noise and the stand (spawn at standing
            height held by a weld, :meth:`release_stand`); ``gui`` is not used.
        initial_joints: joint positions to spawn with ``(L, n)`` [rad].
    """

    def __init__(self, robot: Robot, options: EngineOptions, initial_joints: np.ndarray) -> None:
        o = options
        terrain, control_period, substeps, fixed_base = o.terrain, robot.time_delta, o.substeps, o.fixed_base
        friction, restitution, seed, imu_noise, stand = o.friction, o.restitution, o.seed, o.imu_noise, o.stand
        mujoco = import_mujoco()
        WARNINGS.clear()
        self.mujoco = mujoco
        self.name = "mujoco"
        self.version = str(mujoco.__version__)
        self.robot = robot
        self.control_period = control_period
        self.substeps = substeps
        self.physics_time = 0.0
        """Wall time spent inside ``mj_step`` [s]."""
        self.terrain = Terrain(terrain, seed, diagonal="mujoco", scale=robot_scale(robot.walker.body_clearance))
        stand = stand and not fixed_base
        self.fixed_base = fixed_base
        height = spawn_height(robot, self.terrain, initial_joints, fixed_base, stand)
        timestep = control_period / substeps
        self.timestep = timestep
        """Physics step [s]."""
        if restitution > 0.0:
            event(log, NOTICE, "restitution", "note: MuJoCo applies no restitution (--restitution %g): PyBullet gives "
                  "none below %g m/s, where walking feet land; the contacts stay critically damped", restitution,
                  RESTITUTION_THRESHOLD_MPS)
        self.xml = robot_mjcf(robot, self.terrain, Options(timestep, height, fixed_base, stand, friction, restitution))
        self.model = model = mujoco.MjModel.from_xml_string(self.xml)
        self.data = data = mujoco.MjData(model)
        self.layout = JointSlots.of(robot)
        self.slot_rows, self.slot_cols = self.layout.rows, self.layout.cols
        joints = [name for names in leg_names(robot).values() for name in names.joints]
        ids = [model.joint(name).id for name in joints]
        self.qpos_index = np.array([model.jnt_qposadr[i] for i in ids], dtype=np.intp)
        self.qvel_index = np.array([model.jnt_dofadr[i] for i in ids], dtype=np.intp)
        self.touch_index = np.array([model.sensor_adr[model.sensor(names.foot.replace("_foot", "_touch")).id]
                                     for names in leg_names(robot).values()], dtype=np.intp)
        self.base = model.body("base_link").id
        self.com_offset = np.array(robot.body.com, dtype=float)
        flat = initial_joints[self.slot_rows, self.slot_cols].astype(float)
        data.qpos[self.qpos_index] = flat
        mujoco.mj_forward(model, data)
        self.stand: int | None = model.equality("stand").id if stand else None
        servo = robot.servo
        self.compliant = servo.control == "pd"
        """A position actuator of the servo model's stiffness and damping (no per-step servo loop in Python)."""
        self.servo_model = ServoModel(servo)
        """The servo's electrical model (power), built once."""
        self.explicit = self.servo_model if servo.control == "dynamixel" else None
        """The servo model whose torque (:meth:`ServoModel.torque`) drives a motor actuator every physics step."""
        self._gain = servo.position_gain / timestep
        self._keep = 1.0 - servo.velocity_gain
        self._speed = servo.no_load_speed
        self._kv = velocity_stiffness(robot)
        self._stall = servo.stall_torque
        self._goals = flat.copy()
        self._positions = flat.copy()
        self._mean_torque = np.zeros(len(joints))
        self._mean_power = np.full(len(joints), servo.idle_power)
        self.imu = Imu(control_period, imu_noise, seed, o.imu_yaw_bias)
        self._q = _view(data.qpos, self.qpos_index)
        """The servos' joint positions: a view into ``qpos`` (the hinges follow the free joint, legs in order)."""
        self._v = _view(data.qvel, self.qvel_index)
        self._ctrl = data.ctrl
        self._xmat, self._xquat, self._xpos = data.xmat, data.xquat, data.xpos
        self._qvel, self._sensordata = data.qvel, data.sensordata
        """Views into ``data`` the sensor read uses, fetched once (each attribute access builds a new view)."""
        self._mj_ray = mujoco.mj_ray
        """The actuators' controls, one per servo in servo order (a view into ``data``, fetched once)."""
        self._force = data.actuator_force
        """The actuators' forces after a step (a view into ``data``)."""
        entries = substeps_kernels.entries(mujoco)
        self._pointers = None if entries is None else np.array(
            [*entries, int(model._address), int(data._address)], dtype=np.int64)
        """``mj_step``, MuJoCo's log handler functions, ``mjModel*`` and ``mjData*`` for the compiled control period
        (None: the physics steps run from Python)."""
        self._firmware = np.array(self.servo_model.firmware_parameters, dtype=float)
        self._supply = np.array(self.servo_model.supply_parameters, dtype=float)
        self._motor = np.array([self._gain, self._keep, self._speed, self._kv, self._stall], dtype=float)
        self._work = np.zeros((4, len(joints)))
        self._guard = substeps_kernels.guard_buffer()
        self._ray_hit = np.zeros(1, dtype=np.int32)
        self.command(initial_joints)

    @property
    def warnings(self) -> list[str]:
        """MuJoCo's warnings since this world opened (distinct texts), e.g. an unstable simulation."""
        return list(WARNINGS)

    def release_stand(self) -> None:
        """Deactivate the stand's weld: the robot now carries itself."""
        if self.stand is not None:
            self.data.eq_active[self.stand] = 0
            self.stand = None

    def command(self, targets: np.ndarray) -> None:
        """Position targets of every servo ``(L, n)`` [rad]."""
        self._goals = self.layout.servo_order(targets).astype(float)  # (a new array)
        if self.compliant:
            self.data.ctrl[:] = self._goals

    def step(self) -> None:
        """Advance one control period; torque and speed averaged over its physics steps give the power."""
        if self._pointers is not None:
            self._step_compiled()
            return
        total = np.zeros(len(self._goals))
        self.physics_time += self._step_python(total)
        positions = np.array(self._q)
        # mj_step integrates q += v·h with the new v (semi-implicit Euler): the displacement is the mean speed.
        mean_speed = (positions - self._positions) / self.control_period
        self._positions = positions
        self._mean_torque = total / self.substeps
        self._mean_power = self.servo_model.power(self._mean_torque, mean_speed)

    def _step_compiled(self) -> None:
        """:meth:`step` in one kernel (:mod:`~shc_cli.backends.mujoco_.substeps`): the physics steps with the servo
        law, then the means and the power, the same operations in the same order as :meth:`_step_python` and
        :meth:`step`'s end."""
        kernels = substeps_kernels  # (short)
        n = len(self._goals)
        positions, torque, power = np.empty(n), np.empty(n), np.empty(n)
        common = (self._pointers, self._guard, kernels.CLOCK, self.substeps)
        if self.explicit is not None:
            integral = self.explicit.integral_for(self._goals)
            physics, failed = kernels.firmware_period(
                *common, self.timestep, self.control_period, self._goals, self._q, self._v,
                self._ctrl if integral is None else integral, self._firmware, self._ctrl, self._force, self._supply,
                self._work, self._positions, positions, torque, power)
        elif self.compliant:
            physics, failed = kernels.compliant_period(*common, self.control_period, self._q, self._force,
                                                       self._supply, self._work, self._positions, positions,
                                                       torque, power)
        else:
            physics, failed = kernels.velocity_period(*common, self.control_period, self._goals, self._q, self._v,
                                                      self._motor, self._ctrl, self._supply, self._work,
                                                      self._positions, positions, torque, power)
        self.physics_time += physics * 1e-9
        if failed:
            raise self.mujoco.FatalError(kernels.error_message(self._guard))
        self._positions, self._mean_torque, self._mean_power = positions, torque, power

    def _step_python(self, total: np.ndarray) -> float:
        """The control period's physics steps from Python (a MuJoCo library :func:`substeps.entries` cannot
        find); returns the time inside ``mj_step`` [s]."""
        mj_step, model, data = self.mujoco.mj_step, self.model, self.data
        q, v, ctrl, goals, force = self._q, self._v, self._ctrl, self._goals, self._force
        clock = time.perf_counter
        physics = 0.0
        explicit, step = self.explicit, self.timestep
        if explicit is not None:  # the servo model's torque from the state before the step, as in PyBullet
            torque_into = explicit.torque_into
            for _ in range(self.substeps):
                torque_into(goals, q, v, step, ctrl)
                started = clock()
                mj_step(model, data)
                physics += clock() - started
                total += force
        elif self.compliant:
            for _ in range(self.substeps):
                started = clock()
                mj_step(model, data)
                physics += clock() - started
                total += force
        else:  # PyBullet's velocity motor: the speed that closes position_gain of the error
            gain, keep, speed, kv, stall = self._gain, self._keep, self._speed, self._kv, self._stall
            motor, motor_force = servo_kernels.velocity_motor, servo_kernels.velocity_motor_force
            for _ in range(self.substeps):
                motor(goals, q, v, gain, keep, speed, ctrl)
                started = clock()
                mj_step(model, data)
                physics += clock() - started
                # the implicit step applied kv·(ctrl − v_new); a clamped one (explicit) the stall torque
                motor_force(ctrl, v, kv, stall, total)
        return physics

    def read(self) -> Reading:
        """Sensor readings now.

        Once a control cycle, so written for few allocations: the products with the rotation stay NumPy's (their
        rounding is BLAS's), every elementwise sum and difference is taken on Python floats (the same IEEE
        operations, the same bits)."""
        padded, base = self.layout.padded, self.base
        rotation = self._xmat[base].reshape(3, 3).copy()
        position = self._xpos[base].copy()
        if self.fixed_base:
            linear_origin, angular = [0.0, 0.0, 0.0], np.zeros(3)
        else:
            qvel = self._qvel
            linear_origin = qvel[0:3].tolist()
            angular = rotation @ qvel[3:6]  # a free joint's angular velocity is in the body frame
        r = (rotation @ self.com_offset).tolist()
        w = angular.tolist()
        velocity = np.array([linear_origin[0] + (w[1] * r[2] - w[2] * r[1]),  # of the centre of mass, as PyBullet
                             linear_origin[1] + (w[2] * r[0] - w[0] * r[2]),
                             linear_origin[2] + (w[0] * r[1] - w[1] * r[0])])
        specific_force, rate = self.imu.sense(rotation, velocity, angular)
        forces = self._sensordata[self.touch_index]  # (a copy: fancy indexing)
        qw, qx, qy, qz = self._xquat[base].tolist()
        return Reading(
            joints=padded(self._positions), joint_velocities=padded(self._v), joint_efforts=padded(self._mean_torque),
            servo_power=padded(self._mean_power), orientation=self.imu.orientation(np.array([qx, qy, qz, qw])),
            angular_rate=rate, linear_acceleration=specific_force, foot_forces=forces, foot_contact=forces > 0.0,
            body_height=self._ray_height(position), position=position, rpy=rpy_from_matrix(rotation),
            linear_velocity=velocity, angular_velocity=angular,
        )

    def _ray_height(self, position: np.ndarray) -> float:
        """Body-origin height above the terrain, from a ray cast down that sees only terrain geoms."""
        distance = self._mj_ray(self.model, self.data, position, DOWN, RAY_GROUPS, 1, -1, self._ray_hit)
        if distance < 0.0:
            return self.terrain.height_above(position)
        return float(distance)

    def cast_rays(self, origin: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
        """Distances [m] from ``origin`` along each unit direction ``(n, 3)`` to a terrain geom (group 0; ``nan``:
        nothing within ``reach``), in one ``mj_multiRay``."""
        n = len(directions)
        geoms, distances = np.empty(n, dtype=np.int32), np.empty(n)
        self.mujoco.mj_multiRay(self.model, self.data, np.asarray(origin, dtype=float),
                                np.ascontiguousarray(directions, dtype=float).ravel(), RAY_GROUPS, 1, -1, geoms,
                                distances, None, n, reach)
        distances[(geoms < 0) | (distances < 0.0) | (distances > reach)] = np.nan
        return distances

    def close(self) -> None:
        """Nothing to free but the references."""
        self.stand = None


def import_mujoco() -> Any:
    """``mujoco`` for the physics (:func:`~shc_cli.backends.mujoco_.gl.import_for_physics`: without OpenGL, which
    ``shc render`` and ``--video`` load when they render), its warnings kept in :data:`WARNINGS`."""
    mujoco = import_for_physics()
    if mujoco.get_mju_user_warning() is None:  # else MuJoCo appends its warnings to MUJOCO_LOG.TXT in the cwd
        mujoco.set_mju_user_warning(_warned)
    return mujoco


WARNINGS: list[str] = []
"""MuJoCo's warnings (e.g. "Nan, Inf or huge value in QACC … The simulation is unstable") since the newest world
opened; :attr:`World.warnings` reads them."""


def _warned(text: str) -> None:
    """MuJoCo's warning handler: keep each distinct warning once (at most 20), instead of MuJoCo's log file."""
    if text not in WARNINGS and len(WARNINGS) < 20:
        WARNINGS.append(text)


def _view(values: np.ndarray, index: np.ndarray) -> np.ndarray:
    """``values[index]`` as a view (a slice) when ``index`` is a contiguous run, which it is for the servos."""
    start = int(index[0])
    if np.array_equal(index, np.arange(start, start + len(index))):
        return values[start:start + len(index)]
    raise BackendError("MuJoCo model: the servo joints are not contiguous in qpos/qvel")
