"""A geared position servo (Dynamixel-style) and its electrical power, independent of any physics engine.

The model of one servo of the robot's ``[servo]`` table (every joint the same model), in output-shaft units:

* **Firmware position control** (ROBOTIS e-Manual, MX-106(2.0) / X series position mode): the position error in
  ticks times ``K_P = Position P Gain / 128``, plus ``K_I = Position I Gain / 65536`` times the error summed every
  firmware period, plus ``K_D = Position D Gain / 16`` times the error's change per firmware period, is a PWM
  command in control-table units (885 = 100 % of the supply voltage), limited to ``pwm_limit``. The motor voltage is
  that share of ``supply_voltage``. The sum is the integral over time ÷ ``firmware_period`` and the change is the
  derivative × ``firmware_period`` (the D term acts on the measured speed, so goal steps give no kick); the sum
  stops growing where its own term alone reaches the PWM limit (anti-windup). I and D are 0 from the factory.
* **DC motor behind a gearbox**: torque ``τ = k_t·(V − k_e·ω)/R`` with ``k_t`` = ``torque_constant`` (stall torque
  ÷ stall current), ``R`` = ``winding_resistance`` and ``k_e`` = supply voltage ÷ ``no_load_speed`` (the
  torque–speed line through stall torque and no-load speed). Together: a proportional servo of stiffness
  ``k_t/R · V·(K_P/885)·ticks/(2π)`` [N·m/rad] with the back-EMF damping ``k_t·k_e/R`` [N·m·s/rad] plus the gearbox's
  viscous friction, within ± the stall torque (and ± ``k_t``·``current_limit``).
* **Armature**: the rotor's inertia reflected through the gearbox, for engines that model joint armature.
* **Gearbox friction with asymmetry**: a moving joint's motor must also overcome Coulomb and viscous friction
  (motoring: more torque than the load; back-driven: friction carries part of the load); a joint holding a static
  load needs only ``holding_ratio`` of the load torque from the motor, since the gear train's static friction
  carries the rest — why a real geared servo stands cheaply. Between rest and ``static_speed`` the two blend.
* **Electrical power**: idle electronics + copper loss ``I²R`` of the motor current + the motor's positive
  mechanical power (load work plus friction work); negative motor power (the load back-driving the motor) is
  dissipated in the winding and H-bridge and returns only ``regenerative_efficiency`` of itself to the supply.

An engine uses it in one of two ways: implicit (stiffness, damping, torque limit from :meth:`ServoModel.gains`
given to the engine's own PD motor, e.g. PyBullet's stable PD or a MuJoCo position actuator) or explicit
(:meth:`ServoModel.torque` per physics step from goal, position and speed). Either way the engine reports the
output torque and joint speed, and :meth:`ServoModel.electrical` turns them into motor current and supply power.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from shc_cli.spec.robot import Servo

PWM_FULL_SCALE = 885.0
"""e-Manual PWM units at 100 % duty (MX(2.0), X series)."""
P_GAIN_DIVISOR = 128.0
"""e-Manual: K_P = Position P Gain (control table) / 128."""
I_GAIN_DIVISOR = 65536.0
"""e-Manual: K_I = Position I Gain (control table) / 65536."""
D_GAIN_DIVISOR = 16.0
"""e-Manual: K_D = Position D Gain (control table) / 16."""


@dataclass(frozen=True)
class Gains:
    """What an engine's PD motor needs: output-shaft units."""

    stiffness: float
    """Torque per rad of position error [N·m/rad]."""
    damping: float
    """Torque per rad/s of joint speed [N·m·s/rad] (back-EMF + gearbox viscous friction)."""
    torque_limit: float
    """Largest torque the servo gives [N·m]."""
    max_speed: float
    """No-load speed [rad/s]."""
    armature: float
    """Reflected rotor inertia [kg·m²]."""
    coulomb_friction: float
    """Gearbox Coulomb friction [N·m] (for engines that apply joint friction themselves)."""


@dataclass(frozen=True)
class Electrical:
    """The electrical state of every servo (arrays of one shape)."""

    motor_torque: np.ndarray
    """Torque the motor makes, friction and holding included, at the output shaft [N·m]."""
    current: np.ndarray
    """Motor current [A]."""
    power: np.ndarray
    """Supply power [W]."""


class ServoModel:
    """One servo model (see the module docstring); vectorised over joints. It keeps the I term's sum, one per
    servo, so each simulated robot has its own instance.

    Args:
        servo: the robot's ``[servo]`` table.
    """

    def __init__(self, servo: Servo) -> None:
        self.servo = servo
        s = servo
        self.back_emf = s.supply_voltage / s.no_load_speed
        """``k_e`` [V·s/rad] at the output shaft: the torque–speed line's slope ``k_t·k_e/R``."""
        # volts per (PWM unit per tick), in radians: each gain K (PWM units per tick) times this is V per rad
        pwm_volts_per_rad = s.supply_voltage / PWM_FULL_SCALE * s.ticks_per_revolution / (2.0 * math.pi)
        self.volts_per_rad = pwm_volts_per_rad * s.position_p_gain / P_GAIN_DIVISOR
        """Motor voltage per rad of position error [V/rad] before the PWM limit."""
        self.max_voltage = s.supply_voltage * s.pwm_limit / PWM_FULL_SCALE
        """Largest motor voltage [V]."""
        self.volts_per_rad_s = pwm_volts_per_rad * s.position_i_gain / I_GAIN_DIVISOR / s.firmware_period
        """Motor voltage per rad·s of integrated position error [V/(rad·s)] (the I term)."""
        self.volts_per_rad_per_s = pwm_volts_per_rad * s.position_d_gain / D_GAIN_DIVISOR * s.firmware_period
        """Motor voltage per rad/s of joint speed [V·s/rad] (the D term, on the measured speed)."""
        self._integral: np.ndarray | None = None
        self.torque_limit = min(s.stall_torque, s.torque_constant * self.max_voltage / s.winding_resistance,
                                s.torque_constant * s.current_limit)
        """Largest output torque [N·m]: stall torque, PWM limit and current limit."""
        # the kernels' scalar arguments, converted once (the same values every call)
        self._pd = ((float(s.stiffness), float(s.damping), float(s.stall_torque)) if s.control == "pd" else None)
        self._firmware = (self.volts_per_rad, self.volts_per_rad_s, self.volts_per_rad_per_s, self.max_voltage,
                          self.back_emf, float(s.winding_resistance), float(s.current_limit),
                          float(s.torque_constant), float(s.viscous_friction))
        self._friction = float(s.coulomb_friction)
        self._supply = (float(s.viscous_friction), float(s.holding_ratio), float(s.static_speed),
                        float(s.torque_constant), float(s.current_limit), float(s.idle_power),
                        float(s.winding_resistance), float(s.regenerative_efficiency))

    @cached_property
    def _kernels(self) -> Any:
        """The compiled laws, imported on first use (a model built for its :meth:`gains` loads no numba)."""
        return _kernels()

    def gains(self) -> Gains:
        """Stiffness, damping and limits for an engine's implicit PD motor (``control`` 'dynamixel' or 'pd')."""
        s = self.servo
        if s.control == "pd":
            return Gains(s.stiffness, s.damping, s.stall_torque, s.no_load_speed, s.armature, s.coulomb_friction)
        per_volt = s.torque_constant / s.winding_resistance
        return Gains(stiffness=per_volt * self.volts_per_rad,
                     damping=per_volt * (self.back_emf + self.volts_per_rad_per_s) + s.viscous_friction,
                     torque_limit=self.torque_limit, max_speed=s.no_load_speed, armature=s.armature,
                     coulomb_friction=s.coulomb_friction)

    def torque(self, goal: np.ndarray, position: np.ndarray, speed: np.ndarray, step: float = 0.0) -> np.ndarray:
        """Output torque of the firmware's position control [N·m] (explicit form, one physics step).

        The PWM voltage from the position error (P, I and D terms), limited; the motor's torque–speed line; the
        current limit; gearbox viscous friction. (Coulomb friction is left to the engine or to :meth:`electrical`.)

        Args:
            goal, position, speed: goal and measured angle [rad], measured speed [rad/s] of each servo.
            step: the physics step this torque holds for [s]: the I term integrates the error over it (0: no
                integration, e.g. for a one-off evaluation).
        """
        goal, position, speed = (np.asarray(a, dtype=float) for a in (goal, position, speed))
        out = np.empty(goal.shape)
        self.torque_into(goal.ravel(), position.ravel(), speed.ravel(), float(step), out.ravel())
        return out

    def torque_into(self, goal: np.ndarray, position: np.ndarray, speed: np.ndarray, step: float,
                    out: np.ndarray) -> None:
        """:meth:`torque` written into ``out`` [N·m], without conversions: every argument a contiguous 1-D float64
        array of one length (e.g. views into an engine's state), ``step`` a float — an engine's per-physics-step
        path, where :meth:`torque`'s checks and copies cost more than the law."""
        kernels = self._kernels
        if self._pd is not None:
            kernels.pd_torque(goal, position, speed, *self._pd, out)
            return
        integral = self.integral_for(goal)
        kernels.firmware_torque(goal, position, speed, step, out if integral is None else integral,  # (unused)
                                *self._firmware, out)

    def integral_for(self, goal: np.ndarray) -> np.ndarray | None:
        """The I term's running sum of the error [rad·s], one per servo of ``goal`` (created at first use), which
        :func:`~shc_cli.backends.servo_kernels.firmware_torque` updates; None without an I term."""
        if self.volts_per_rad_s > 0.0 and self._integral is None:
            self._integral = np.zeros(goal.shape, dtype=float)
        return self._integral

    @property
    def firmware_parameters(self) -> tuple[float, ...]:
        """:func:`~shc_cli.backends.servo_kernels.firmware_torque`'s scalar arguments after ``integral``, in order
        (``volts_per_rad`` … ``viscous``)."""
        return self._firmware

    @property
    def supply_parameters(self) -> tuple[float, ...]:
        """:func:`~shc_cli.backends.servo_kernels.supply_power`'s scalar arguments of :meth:`power` (the engine
        applies no Coulomb friction), in order (``friction`` … ``regenerative``)."""
        return (self._friction, *self._supply)

    def electrical(self, torque: np.ndarray, speed: np.ndarray, friction_in_engine: bool = False) -> Electrical:
        """Motor torque, current and supply power from the output torque and joint speed the engine reports.

        Args:
            torque: output-shaft torque of each servo [N·m] (the engine's motor torque, net of viscous friction).
            speed: joint speed [rad/s].
            friction_in_engine: the engine applied the gearbox's Coulomb friction itself (then ``torque`` is
                already the motor's torque while moving); otherwise it is added here.
        """
        torque = np.asarray(torque, float)
        speed = np.asarray(speed, float)
        if torque.shape != speed.shape:
            torque, speed = (np.ascontiguousarray(a) for a in np.broadcast_arrays(torque, speed))
        motor, current, power = np.empty(torque.shape), np.empty(torque.shape), np.empty(torque.shape)
        self._kernels.supply_power(torque.ravel(), speed.ravel(), 0.0 if friction_in_engine else self._friction,
                                   *self._supply, motor.ravel(), current.ravel(), power.ravel())
        return Electrical(motor_torque=motor, current=current, power=power)

    def power(self, torque: np.ndarray, speed: np.ndarray, friction_in_engine: bool = False) -> np.ndarray:
        """Supply power of each servo [W] (:meth:`electrical`'s ``power``)."""
        return self.electrical(torque, speed, friction_in_engine).power


def _kernels() -> Any:
    """The compiled servo laws (:mod:`shc_cli.backends.servo_kernels`), imported on first use: numba loads only
    when a servo is simulated."""
    from shc_cli.backends import servo_kernels

    return servo_kernels
