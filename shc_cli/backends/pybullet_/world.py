"""The PyBullet engine (:class:`~shc_cli.backends.engine.Engine`): robot, terrain, servos and sensors.

Advanced one control period at a time: :meth:`World.command` sends the controller's joint targets
to position-controlled servos (torque limit and no-load speed passed explicitly: POSITION_CONTROL
ignores the URDF's limits), :meth:`World.step` runs the physics sub-steps of one control period and
:meth:`World.read` returns what the robot's sensors see. ``pybullet`` is imported here only.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from importlib import metadata
from typing import Any

import numpy as np

from shc_cli.backends.engine import EngineOptions, Reading, spawn_height, tilt
from shc_cli.backends.imu import Imu
from shc_cli.backends.pybullet_.quiet import quiet_stdout
from shc_cli.backends.pybullet_.terrain_bodies import build_terrain
from shc_cli.backends.pybullet_.urdf import robot_urdf
from shc_cli.backends.servo import ServoModel
from shc_cli.backends.terrain import robot_scale
from shc_cli.errors import BackendError
from shc_cli.model.body import GRAVITY
from shc_cli.model.chains import JointSlots
from shc_cli.spec.robot import Robot

__all__ = ["Reading", "World", "quiet_stdout", "tilt"]
SOLVER_ITERATIONS = 30
"""Constraint solver iterations. Measured on the Bullet tripod walk at 400 Hz (docs/physics-model.md): 30 instead
of 50 takes 21–29 % less physics time, lowers the walking body by 0.8 mm and changes speed by −1.3 % and power
by +5 %; 20 sags 1.9 mm."""
EXPLICIT_STABILITY_LIMIT = 0.8
"""Largest :func:`explicit_stability` figure run without a warning (1 is the theoretical edge; measured on
bullet_mammalian_b with smaller armatures: 0.69 walks as calibrated, 0.96 walks with its power doubled by
chatter, 1.29 and above fall)."""


def explicit_stability(step: float, stiffness: float, damping: float, inverse_inertia: float) -> float:
    """How close an explicitly applied spring–damper servo law is to making the integrator unstable (≥ 1: it is).

    Bullet integrates semi-implicitly (velocity first, then position with the new velocity); a joint of inertia I
    under ``τ = −K·x − c·ẋ`` evaluated at the step's start is stable only while ``2·h·c/I + h²·K/I < 4``.
    With many coupled joints the lightest mode counts: ``1/I`` is the largest eigenvalue of the joint block of
    the inverse mass matrix.

    Args:
        step: physics step h [s].
        stiffness: K [N·m/rad].
        damping: c [N·m·s/rad].
        inverse_inertia: 1/I [1/(kg·m²)].
    """
    return (2.0 * step * damping + step * step * stiffness) * inverse_inertia / 4.0


def stable_rate(control_period: float, stiffness: float, damping: float, inverse_inertia: float) -> float:
    """The lowest physics rate [Hz], a whole multiple of the control rate, at which :func:`explicit_stability`
    stays within :data:`EXPLICIT_STABILITY_LIMIT`."""
    a, b = stiffness * inverse_inertia, 2.0 * damping * inverse_inertia
    c = -4.0 * EXPLICIT_STABILITY_LIMIT
    step = -c / b if a == 0.0 else (-b + math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
    return math.ceil(control_period / step - 1e-9) / control_period


class World:
    """A PyBullet client holding one robot on one terrain: the PyBullet :class:`~shc_cli.backends.engine.Engine`.

    Args:
        robot: the robot; its ``time_delta`` is the control period.
        options: terrain, physics steps per control period, fixed base (held :data:`AIR_LIFT` above its standing
            height), friction and restitution of terrain and feet, seed, IMU noise, GUI, and the stand (spawn at
            standing height held by a removable support, :meth:`release_stand`, like the stand box of OpenSHC's
            Gazebo launch).
        initial_joints: joint positions to spawn with ``(L, n)`` [rad].
    """

    def __init__(self, robot: Robot, options: EngineOptions, initial_joints: np.ndarray) -> None:
        o = options
        terrain, control_period, substeps, fixed_base = o.terrain, robot.time_delta, o.substeps, o.fixed_base
        friction, restitution, seed, imu_noise, gui, stand = (o.friction, o.restitution, o.seed, o.imu_noise, o.gui,
                                                              o.stand)
        with quiet_stdout():  # importing pybullet prints its build time
            import pybullet

        self.p = pybullet
        self.name = "pybullet"
        self.version = metadata.version("pybullet")
        self.robot = robot
        self.control_period = control_period
        self.substeps = substeps
        self.timestep = control_period / substeps
        """Physics step [s]."""
        self.physics_time = 0.0
        """Wall time spent inside ``stepSimulation`` [s]."""
        self.imu = Imu(control_period, imu_noise, seed, o.imu_yaw_bias)
        with quiet_stdout():
            self.client = pybullet.connect(pybullet.GUI if gui else pybullet.DIRECT)
        if self.client < 0:
            raise BackendError("PyBullet: cannot open a GUI here (no display?); run without --gui")
        p, c = pybullet, self.client
        p.setGravity(0.0, 0.0, -GRAVITY, physicsClientId=c)
        p.setTimeStep(self.timestep, physicsClientId=c)
        p.setPhysicsEngineParameter(numSolverIterations=SOLVER_ITERATIONS, deterministicOverlappingPairs=1,
                                    physicsClientId=c)
        self.terrain = build_terrain(c, terrain, friction, restitution, seed,
                                     robot_scale(robot.walker.body_clearance))
        self.stand: int | None = None
        self._load_robot(fixed_base, initial_joints, friction, restitution, stand and not fixed_base)

    # -- set-up ------------------------------------------------------------------------------------------------

    def _load_robot(self, fixed_base: bool, joints: np.ndarray, friction: float, restitution: float,
                    stand: bool = False) -> None:
        p, c, robot = self.p, self.client, self.robot
        height = spawn_height(robot, self.terrain, joints, fixed_base, stand)
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as handle:
            handle.write(robot_urdf(robot))
            path = handle.name
        try:
            with quiet_stdout():
                self.body = p.loadURDF(path, [0.0, 0.0, height], [0.0, 0.0, 0.0, 1.0], useFixedBase=fixed_base,
                                       flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=c)
        finally:
            os.unlink(path)
        names = {p.getJointInfo(self.body, j, physicsClientId=c)[1].decode(): j
                 for j in range(p.getNumJoints(self.body, physicsClientId=c))}
        links = {p.getJointInfo(self.body, j, physicsClientId=c)[12].decode(): j
                 for j in range(p.getNumJoints(self.body, physicsClientId=c))}
        self.joint_index: list[list[int]] = []
        for leg_id, leg in robot.legs.items():
            self.joint_index.append([names[f"{leg_id}_{joint}_joint"] for joint in leg.joints])
        self.foot_links = [links[f"{leg_id}_foot"] for leg_id in robot.legs]
        self.flat_joints = [index for indices in self.joint_index for index in indices]
        self.layout = JointSlots.of(robot)
        """Where each servo sits in the padded ``(L, n)`` arrays: ``a[slot_rows, slot_cols]`` lists the real joints of
        ``a`` in servo (= log column) order."""
        self.slot_rows, self.slot_cols = self.layout.rows, self.layout.cols
        self.slots = list(zip(self.slot_rows.tolist(), self.slot_cols.tolist(), strict=True))
        self._states: Any = None
        """The joint states after the last physics step (``None`` until the first step)."""
        self.foot_leg = {link: leg for leg, link in enumerate(self.foot_links)}
        # PyBullet reports the base's centre of mass; the body frame (base_link) is offset from it.
        self.com_offset = np.array(p.getDynamicsInfo(self.body, -1, physicsClientId=c)[3])
        for j in range(p.getNumJoints(self.body, physicsClientId=c)):  # free joints: no default motors
            p.setJointMotorControl2(self.body, j, p.VELOCITY_CONTROL, force=0.0, physicsClientId=c)
        for link in [-1, *range(p.getNumJoints(self.body, physicsClientId=c))]:
            p.changeDynamics(self.body, link, lateralFriction=friction, restitution=restitution,
                             physicsClientId=c)
        servo = robot.servo
        self.servo_model = ServoModel(servo)
        self.gains = self.servo_model.gains()
        for index in self.flat_joints:  # the servo's no-load speed as the joint's speed limit
            p.changeDynamics(self.body, index, maxJointVelocity=servo.no_load_speed, physicsClientId=c)
        count = len(self.flat_joints)
        self._forces = [servo.stall_torque] * count
        self._position_gains = [servo.position_gain] * count
        self._velocity_gains = [servo.velocity_gain] * count
        self._mean_torque = np.zeros(count)
        self._mean_power = np.full(count, servo.idle_power)
        self.compliant = servo.control == "pd"
        self.explicit = servo.control == "dynamixel"
        """The servo model's torque (:meth:`ServoModel.torque`) applied with TORQUE_CONTROL every physics step."""
        self._warnings: list[str] = []
        self._goals = np.zeros(count)
        for row, indices in enumerate(self.joint_index):
            for k, index in enumerate(indices):
                p.resetJointState(self.body, index, float(joints[row, k]), 0.0, physicsClientId=c)
        self._positions = joints[self.slot_rows, self.slot_cols].astype(float)
        self.command(joints)
        if self.explicit:
            self._check_explicit_stability()
        if stand:
            base = p.getBasePositionAndOrientation(self.body, physicsClientId=c)
            self.stand = p.createConstraint(self.body, -1, -1, -1, p.JOINT_FIXED, [0, 0, 0], [0, 0, 0], base[0],
                                            physicsClientId=c)

    @property
    def warnings(self) -> list[str]:
        """Warnings about this world: an explicit servo law beyond the integrator's stability (checked at spawn);
        PyBullet's own C warnings are not collected (it prints them, silenced by ``quiet_stdout``)."""
        return list(self._warnings)

    def _check_explicit_stability(self) -> None:
        """Warn when the ``dynamixel`` servo law, applied as a torque at each physics step's start, is too stiff
        or too damped for the lightest joint mode of the spawn posture (:func:`explicit_stability`)."""
        p, c = self.p, self.client
        movable = [j for j in range(p.getNumJoints(self.body, physicsClientId=c))
                   if p.getJointInfo(self.body, j, physicsClientId=c)[2] != p.JOINT_FIXED]
        positions = [p.getJointState(self.body, j, physicsClientId=c)[0] for j in movable]
        mass = np.array(p.calculateMassMatrix(self.body, positions, physicsClientId=c))
        base = mass.shape[0] - len(movable)  # 6 base coordinates first for a free base, none for a fixed one
        rows = [base + movable.index(j) for j in self.flat_joints]
        inverse = float(np.linalg.eigvalsh(np.linalg.inv(mass)[np.ix_(rows, rows)]).max())
        step = self.timestep
        gains = self.gains
        figure = explicit_stability(step, gains.stiffness, gains.damping, inverse)
        if figure > EXPLICIT_STABILITY_LIMIT:
            rate = stable_rate(self.control_period, gains.stiffness, gains.damping, inverse)
            self._warnings.append(
                f"the 'dynamixel' servo law, applied explicitly, is too stiff for {1.0 / step:g} Hz physics (stability "
                f"figure {figure:.2f}, over {EXPLICIT_STABILITY_LIMIT}: damping {gains.damping:.3g} N·m·s/rad and "
                f"stiffness {gains.stiffness:.3g} N·m/rad on a joint mode of {1.0 / inverse:.2g} kg·m²); use "
                f"--physics-rate {rate:g} or more, a larger [servo] armature, or --engine mujoco")

    def release_stand(self) -> None:
        """Take the stand away: the robot now carries itself."""
        if self.stand is not None:
            self.p.removeConstraint(self.stand, physicsClientId=self.client)
            self.stand = None

    # -- the loop ----------------------------------------------------------------------------------------------

    def command(self, targets: np.ndarray) -> None:
        """Position targets for every servo ``(L, n)`` [rad], at most the servo's stall torque; the no-load
        speed is the joints' velocity limit (set once with ``maxJointVelocity``, since POSITION_CONTROL
        ignores the URDF's limits)."""
        p = self.p
        if self.compliant or self.explicit:  # set before every physics step (step): it does not persist
            self._goals = targets[self.slot_rows, self.slot_cols].astype(float)
            return
        p.setJointMotorControlArray(self.body, self.flat_joints, p.POSITION_CONTROL,
                                    targetPositions=[float(targets[leg, k]) for leg, k in self.slots],
                                    forces=self._forces, positionGains=self._position_gains,
                                    velocityGains=self._velocity_gains, physicsClientId=self.client)

    def step(self) -> None:
        """Advance one control period (``substeps`` physics steps); adds the time spent to ``physics_time``.

        Motor torque (sampled after every physics step) and joint speed are averaged over the sub-steps and
        the electrical power is computed from those means: a position-controlled joint's torque chatters from
        physics step to physics step, faster than a servo's current can follow (motor inductance, PWM and gearbox
        compliance filter it), and squaring the chatter would make the copper loss depend on the physics rate.
        """
        p, c, body, joints, count = self.p, self.client, self.body, self.flat_joints, len(self.flat_joints)
        clock = time.perf_counter
        step = self.timestep
        samples = []
        pd = self._stable_pd() if self.compliant else None
        applied = []
        state = self._states
        if self.explicit and state is None:  # the explicit servo law needs the state before the first step
            state = p.getJointStates(body, joints, physicsClientId=c)
        for _ in range(self.substeps):
            if pd is not None:
                p.setJointMotorControlMultiDofArray(body, joints, p.STABLE_PD_CONTROL, **pd, physicsClientId=c)
            elif self.explicit:
                q = np.fromiter([s[0] for s in state], float, count)
                qd = np.fromiter([s[1] for s in state], float, count)
                torque = self.servo_model.torque(self._goals, q, qd, step)
                applied.append(torque)
                p.setJointMotorControlArray(body, joints, p.TORQUE_CONTROL, forces=torque.tolist(), physicsClientId=c)
            started = clock()
            p.stepSimulation(physicsClientId=c)
            self.physics_time += clock() - started
            state = p.getJointStates(body, joints, physicsClientId=c)
            samples.append(state)
        states = samples[-1]
        self._states = states
        positions = np.fromiter([state[0] for state in states], float, count)
        # Bullet integrates q += v·h with the new v (semi-implicit Euler), so the mean of the sub-steps'
        # speeds is exactly the displacement over the period: no per-step speed sampling needed.
        mean_speed = (positions - self._positions) / self.control_period
        self._positions = positions
        if self.explicit:
            self._mean_torque = np.mean(applied, axis=0)
        elif self.compliant:  # stable PD reports no motor torque: the PD law at each sub-step's end state
            g = self.gains
            values = np.array([[state[0], state[1]] for sample in samples for state in sample]).reshape(
                self.substeps, count, 2)
            torques = np.clip(g.stiffness * (self._goals - values[:, :, 0]) - g.damping * values[:, :, 1],
                              -g.torque_limit, g.torque_limit)
            self._mean_torque = torques.mean(axis=0)
        else:
            torques = np.fromiter([state[3] for sample in samples for state in sample], float,
                                  self.substeps * count)
            self._mean_torque = torques.reshape(self.substeps, count).mean(axis=0)
        self._mean_power = self.servo_model.power(self._mean_torque, mean_speed)

    def _stable_pd(self) -> dict[str, Any]:
        """Arguments of PyBullet's stable (implicit) PD motor for this period's goals: the servo model's stiffness
        and damping (:meth:`ServoModel.gains`), at most its torque limit. PyBullet has no joint armature, so the
        rotor inertia is not simulated here; gearbox friction enters the electrical model only."""
        g, count = self.gains, len(self.flat_joints)
        return {"targetPositions": [[goal] for goal in self._goals.tolist()], "targetVelocities": [[0.0]] * count,
                "positionGains": [g.stiffness] * count, "velocityGains": [g.damping] * count,
                "forces": [[g.torque_limit]] * count}

    def read(self) -> Reading:
        """Sensor readings now."""
        p, c, padded = self.p, self.client, self.layout.padded
        states = self._states if self._states is not None else p.getJointStates(self.body, self.flat_joints,
                                                                                  physicsClientId=c)
        velocities = np.fromiter([state[1] for state in states], float, len(states))
        com, orientation = p.getBasePositionAndOrientation(self.body, physicsClientId=c)
        linear, angular = p.getBaseVelocity(self.body, physicsClientId=c)
        rotation = np.array(p.getMatrixFromQuaternion(orientation)).reshape(3, 3)
        position = np.array(com) - rotation @ self.com_offset  # the base_link frame's origin
        linear_v, angular_v = np.array(linear), np.array(angular)
        specific_force, rate = self.imu.sense(rotation, linear_v, angular_v)
        forces = np.zeros(len(self.joint_index))
        for point in p.getContactPoints(bodyA=self.body, physicsClientId=c):
            foot = self.foot_leg.get(point[3])
            if foot is not None and point[2] != self.body:
                forces[foot] += point[9]
        return Reading(
            joints=padded(self._positions), joint_velocities=padded(velocities),
            joint_efforts=padded(self._mean_torque), servo_power=padded(self._mean_power),
            orientation=self.imu.orientation(np.array(orientation)), angular_rate=rate,
            linear_acceleration=specific_force,
            foot_forces=forces, foot_contact=forces > 0.0, body_height=self._ray_height(position),
            position=position, rpy=np.array(p.getEulerFromQuaternion(orientation)),
            linear_velocity=linear_v, angular_velocity=angular_v,
        )

    def _ray_height(self, position: np.ndarray | tuple[float, float, float]) -> float:
        """Body-origin height above the terrain, from a ray cast down that passes through the robot itself."""
        x, y, z = position
        start = z - 0.001
        for _ in range(8):
            hit = self.p.rayTest([x, y, start], [x, y, z - 10.0], physicsClientId=self.client)[0]
            if hit[0] < 0:
                break
            if hit[0] != self.body:
                return float(z - hit[3][2])
            start = hit[3][2] - 0.001
        return self.terrain.height_above(position)

    def cast_rays(self, origin: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
        """Distances [m] from ``origin`` along each unit direction ``(n, 3)`` to the terrain (``nan``: nothing
        within ``reach``), in one ``rayTestBatch``; a ray that hits the robot is cast again from just beyond the hit
        (up to 7 times), so the rays see only the terrain, as :meth:`_ray_height` does, and the physics is untouched."""
        p, c = self.p, self.client
        directions = np.asarray(directions, dtype=float)
        start = np.array(np.broadcast_to(np.asarray(origin, dtype=float), directions.shape))
        travelled = np.zeros(len(directions))
        result = np.full(len(directions), np.nan)
        todo = np.arange(len(directions))
        for _ in range(8):
            left = reach - travelled[todo]
            ends = start[todo] + directions[todo] * left[:, None]
            hits = p.rayTestBatch(start[todo].tolist(), ends.tolist(), physicsClientId=c)
            body = np.array([hit[0] for hit in hits])
            fraction = np.array([hit[2] for hit in hits], dtype=float)
            terrain = (body >= 0) & (body != self.body)
            result[todo[terrain]] = travelled[todo[terrain]] + fraction[terrain] * left[terrain]
            robot = body == self.body
            if not robot.any():
                break
            again = todo[robot]
            step = fraction[robot] * left[robot] + 0.001
            travelled[again] += step
            start[again] += directions[again] * step[:, None]
            todo = again
        return result

    def close(self) -> None:
        self.p.disconnect(physicsClientId=self.client)

