"""Load-free servo joints: the servo model of :mod:`shc_cli.backends.servo` driving nothing but its own rotor.

A servo on a bench (or an emulated one, :mod:`shc_cli.hardware.emulator`) turns an output shaft that carries only
the rotor's inertia reflected through the gearbox (``armature``). Its motion follows from the robot file's
``[servo]`` table alone, so it is the one place where the table's parameters can be checked against a servo's own
logs without a model of the robot around it::

    inertia · dω/dt = k_t · I − viscous_friction · ω − coulomb_friction · sign(ω)

with the motor current ``I`` of the firmware's position control (P, I and D terms, PWM limit, the motor's
torque–speed line, the current limit: :meth:`~shc_cli.backends.servo.ServoModel.torque`'s law, the same compiled
function), integrated in steps of the ``firmware_period`` (1 ms): back-EMF and viscous damping implicitly, so any
inertia is stable, and Coulomb friction as an impulse that can stop the joint (a still joint stays still until the
motor overcomes it — the position error a real servo is left with). With the torque off the motor gives no current
and the shaft coasts against the gearbox's friction.

What the table's other fields mean here: ``holding_ratio``, ``static_speed``, ``idle_power`` and
``regenerative_efficiency`` belong to the electrical power model (:meth:`ServoModel.electrical`) and change no motion
or motor current, so a load-free joint says nothing about them; ``stall_torque`` and ``no_load_speed`` enter
through the torque–speed line (``no_load_speed`` sets the back-EMF) and the torque limit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shc_cli.backends.servo import ServoModel
from shc_cli.spec.robot import Servo

ARMATURE_PER_NM = 0.00025
"""Reflected rotor inertia per N·m of stall torque [kg·m²/(N·m)] where the ``[servo]`` table gives no
``armature`` (the MuJoCo model's default, :data:`shc_cli.backends.mujoco_.mjcf.ARMATURE_PER_NM`)."""


def joint_inertia(servo: Servo) -> float:
    """The load-free joint's inertia [kg·m²]: ``armature``, or :data:`ARMATURE_PER_NM` × stall torque if it is 0."""
    return float(servo.armature) if servo.armature > 0.0 else ARMATURE_PER_NM * float(servo.stall_torque)


class FreeJoints:
    """``count`` load-free joints of one servo model, their state in output-shaft units.

    Args:
        servo: the ``[servo]`` table (``control`` is ignored: the joints are always the firmware's position control,
            the ``dynamixel`` law).
        count: how many joints.
        position: the starting angle of every joint [rad].
    """

    def __init__(self, servo: Servo, count: int = 1, position: float | np.ndarray = 0.0) -> None:
        self.servo = servo
        self.model = ServoModel(servo)
        self.inertia = joint_inertia(servo)
        self.position = np.zeros(count) + position
        """Angle [rad]."""
        self.speed = np.zeros(count)
        """Speed [rad/s]."""
        self.current = np.zeros(count)
        """Motor current at the end of the last advance [A]."""
        self.integral = np.zeros(count)
        """The I term's integrated error [rad·s]."""
        from shc_cli.backends import servo_kernels

        s, m = servo, self.model
        self._kernel = servo_kernels.free_joints
        self._constants = (float(s.firmware_period), m.volts_per_rad, m.volts_per_rad_s, m.volts_per_rad_per_s,
                           m.max_voltage, m.back_emf, float(s.winding_resistance), float(s.current_limit),
                           float(s.torque_constant), float(s.viscous_friction), float(s.coulomb_friction), self.inertia)
        self._goal = np.zeros(count)
        self._enabled = np.ones(count, dtype=np.int64)
        self.advance(self.position, 0.0)  # loads (or compiles) the kernel now, not at the first reading

    def advance(self, goal: np.ndarray | float, duration: float, enabled: np.ndarray | bool = True) -> None:
        """Hold ``goal`` [rad] for ``duration`` [s] (torque on where ``enabled``; 0 s: only the current of the
        present state)."""
        if duration < 0.0:
            return
        self._goal[:] = goal
        self._enabled[:] = enabled
        self._kernel(self._goal, self.position, self.speed, self.integral, self.current, self._enabled,
                     float(duration), *self._constants)


@dataclass(frozen=True)
class Response:
    """What a servo bus would read each cycle (arrays ``(cycles, joints)``)."""

    position: np.ndarray
    """[rad]."""
    speed: np.ndarray
    """[rad/s]."""
    current: np.ndarray
    """Motor current [A]."""


def free_response(servo: Servo, goals: np.ndarray, period: float | np.ndarray, start: np.ndarray | float = 0.0,
                  delay: np.ndarray | None = None) -> Response:
    """The readings of load-free joints driven by a goal log, as a run's ``log.csv`` rows pair them: goal ``k`` is
    written, held until the next reading, and row ``k`` is the state read then.

    Args:
        servo: the ``[servo]`` table.
        goals: goal angles ``(cycles, joints)`` [rad].
        period: the time from one reading to the next [s]: the control period, or one per cycle ``(cycles,)``.
        start: the joints' angles before the first goal [rad] (at rest).
        delay: per cycle ``(cycles,)``, the time from the previous reading to goal ``k``'s write [s], during which
            goal ``k − 1`` still holds (run-hw's ``timing.csv`` cycle time); default 0.
    """
    goals = np.asarray(goals, dtype=float)
    count = goals.shape[0]
    periods = np.broadcast_to(np.asarray(period, dtype=float), (count,))
    joints = FreeJoints(servo, goals.shape[1], np.asarray(start, dtype=float))
    position, speed, current = (np.empty(goals.shape) for _ in range(3))
    previous = joints.position.copy()
    for k in range(count):
        late = 0.0 if delay is None else min(float(delay[k]), float(periods[k]))
        if late > 0.0:
            joints.advance(previous, late)
        joints.advance(goals[k], float(periods[k]) - late)
        position[k], speed[k], current[k] = joints.position, joints.speed, joints.current
        previous = goals[k]
    return Response(position, speed, current)
