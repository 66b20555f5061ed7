"""Compiled per-servo laws of :class:`~shc_cli.backends.servo.ServoModel` and of the engines' servo loops.

They run every physics step (the firmware torque, the velocity motor) or every control period (the electrical
power) on arrays of a robot's ~18 servos, where NumPy's per-call overhead (≈ 1 µs for each of ~15 operations)
outweighed the arithmetic. Each is the NumPy expression it replaces written out element by element, in the same
order of operations (IEEE arithmetic, no fast-math), so the results are the same to the last bit; numba caches them
like :mod:`shc_cli.model.kernels`.
"""

from __future__ import annotations

import math

from shc_cli.model.jit import njit


@njit(cache=True)
def _clip(value, low, high):  # type: ignore[no-untyped-def]
    """``np.clip`` of one value: ``min(max(value, low), high)``."""
    if value < low:
        value = low
    if value > high:
        value = high
    return value


@njit(cache=True)
def firmware_torque(goal, position, speed, step, integral, volts_per_rad, volts_per_rad_s, volts_per_rad_per_s,  # type: ignore[no-untyped-def]
                    max_voltage, back_emf, resistance, current_limit, torque_constant, viscous, out):
    """:meth:`ServoModel.torque` of the firmware's position control into ``out`` (``integral`` updated in place
    when ``volts_per_rad_s > 0``)."""
    bound = max_voltage / volts_per_rad_s if volts_per_rad_s > 0.0 else 0.0
    for i in range(goal.shape[0]):
        error = goal[i] - position[i]
        if volts_per_rad_s > 0.0:
            integral[i] = _clip(integral[i] + error * step, -bound, bound)
        voltage = _voltage(error, speed[i], integral[i] if volts_per_rad_s > 0.0 else 0.0, volts_per_rad,
                           volts_per_rad_s, volts_per_rad_per_s, max_voltage)
        current = _clip((voltage - back_emf * speed[i]) / resistance, -current_limit, current_limit)
        out[i] = torque_constant * current - viscous * speed[i]
    return out


@njit(cache=True)
def _voltage(error, speed, integral, volts_per_rad, volts_per_rad_s, volts_per_rad_per_s, max_voltage):  # type: ignore[no-untyped-def]
    """The firmware's PWM voltage [V] from the position error [rad], the speed [rad/s] and the error's integral
    [rad·s]: P, I and D terms, limited to ± ``max_voltage``."""
    voltage = volts_per_rad * error
    if volts_per_rad_s > 0.0:
        voltage = voltage + volts_per_rad_s * integral
    if volts_per_rad_per_s > 0.0:
        voltage = voltage - volts_per_rad_per_s * speed
    return _clip(voltage, -max_voltage, max_voltage)


@njit(cache=True)
def _coast(momentum, mass, friction_impulse):  # type: ignore[no-untyped-def]
    """The speed after one implicit step [rad/s]: ``momentum`` (inertia × speed + step × drive torque) less the
    Coulomb friction's impulse over ``mass`` (inertia + step × damping); 0 when friction can stop the joint within
    the step (static friction holds it)."""
    if abs(momentum) <= friction_impulse:
        return 0.0
    return (momentum - math.copysign(friction_impulse, momentum)) / mass


@njit(cache=True)
def free_joints(goal, position, speed, integral, current, enabled, duration, step, volts_per_rad, volts_per_rad_s,  # type: ignore[no-untyped-def]
                volts_per_rad_per_s, max_voltage, back_emf, resistance, current_limit, torque_constant, viscous,
                coulomb, inertia):
    """Advance load-free servo joints by ``duration`` [s] in equal steps of at most ``step`` (the firmware period):
    ``inertia·dω/dt = k_t·I − viscous·ω − coulomb·sign(ω)`` with the motor current ``I`` of the firmware law
    (:func:`firmware_torque`'s voltage, torque–speed line and current limit), semi-implicit: the motor's
    back-EMF and the viscous damping act on the new speed (stable for any inertia > 0 and step), Coulomb friction
    as an impulse that can stop the joint (stiction). A joint whose torque is off (``enabled`` 0) gets no current
    and coasts against the gearbox friction. ``position`` [rad], ``speed`` [rad/s], ``integral`` [rad·s] and
    ``current`` [A] (at the end) are updated in place."""
    count = max(1, math.ceil(duration / step - 1e-9))
    h = duration / count
    bound = max_voltage / volts_per_rad_s if volts_per_rad_s > 0.0 else 0.0
    motor_damping = torque_constant * back_emf / resistance
    for i in range(goal.shape[0]):
        q = position[i]
        w = speed[i]
        amps = 0.0
        for _ in range(count):
            if enabled[i] == 0:
                w = _coast(inertia * w, inertia + h * viscous, h * coulomb)
                q = q + h * w
                amps = 0.0
                continue
            error = goal[i] - q
            if volts_per_rad_s > 0.0:
                integral[i] = _clip(integral[i] + error * h, -bound, bound)
            voltage = _voltage(error, w, integral[i] if volts_per_rad_s > 0.0 else 0.0, volts_per_rad,
                               volts_per_rad_s, volts_per_rad_per_s, max_voltage)
            moved = _coast(inertia * w + h * torque_constant * voltage / resistance,
                           inertia + h * (motor_damping + viscous), h * coulomb)
            amps = (voltage - back_emf * moved) / resistance
            if abs(amps) > current_limit:  # the current limit: a constant torque, only viscous damping
                amps = _clip(amps, -current_limit, current_limit)
                moved = _coast(inertia * w + h * torque_constant * amps, inertia + h * viscous, h * coulomb)
            w = moved
            q = q + h * w
        position[i] = q
        speed[i] = w
        current[i] = amps
    return position


@njit(cache=True)
def pd_torque(goal, position, speed, stiffness, damping, stall, out):  # type: ignore[no-untyped-def]
    """:meth:`ServoModel.torque` of a ``pd`` servo into ``out``."""
    for i in range(goal.shape[0]):
        out[i] = _clip(stiffness * (goal[i] - position[i]) - damping * speed[i], -stall, stall)
    return out


@njit(cache=True)
def supply_power(torque, speed, friction, viscous, holding_ratio, static_speed, torque_constant, current_limit,  # type: ignore[no-untyped-def]
                 idle, resistance, regenerative, motor_out, current_out, power_out):
    """:meth:`ServoModel.electrical`: motor torque, current and supply power of each servo into the outputs."""
    for i in range(torque.shape[0]):
        s = speed[i]
        sign = 1.0 if s > 0.0 else (-1.0 if s < 0.0 else (0.0 if s == 0.0 else s))
        moving = torque[i] + sign * friction + viscous * s
        holding = holding_ratio * torque[i]
        blend = min(abs(s) / static_speed, 1.0) if not math.isnan(s) else s
        motor = (1.0 - blend) * holding + blend * moving
        current = _clip(motor / torque_constant, -current_limit, current_limit)
        mechanical = motor * s
        motor_out[i] = motor
        current_out[i] = current
        power_out[i] = (idle + current * current * resistance + max(mechanical, 0.0)
                        + regenerative * min(mechanical, 0.0))


@njit(cache=True)
def velocity_motor(goals, q, v, gain, keep, speed, ctrl):  # type: ignore[no-untyped-def]
    """PyBullet's position motor as a speed target (MuJoCo world): ``ctrl = clip(gain·(goal − q) [+ keep·v],
    ±speed)``."""
    for i in range(goals.shape[0]):
        work = (goals[i] - q[i]) * gain
        if keep != 0.0:
            work += keep * v[i]
        ctrl[i] = max(min(work, speed), -speed)
    return ctrl


@njit(cache=True)
def velocity_motor_force(ctrl, v, kv, stall, total):  # type: ignore[no-untyped-def]
    """Add the implicit velocity actuator's force ``clip(kv·(ctrl − v), ±stall)`` to ``total``."""
    for i in range(ctrl.shape[0]):
        work = (ctrl[i] - v[i]) * kv
        total[i] += max(min(work, stall), -stall)
    return total
