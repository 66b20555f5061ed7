"""Electrical power of the servos from joint torque and speed (the model of :class:`~shc_cli.spec.robot.Servo`)."""

from __future__ import annotations

import numpy as np

from shc_cli.spec.robot import Servo


def servo_power(servo: Servo, torque: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Electrical power of each servo [W].

    ``P = idle + (τ/k_t)²·R + max(τω, 0) + η·min(τω, 0)``: electronics, copper loss of the current that makes
    the torque, mechanical output power; negative mechanical power (the load back-driving the servo) is
    dissipated in the motor and drive, so it reduces the supply power only by the regenerative share η.

    Args:
        servo: the servo model.
        torque: joint torques [N·m].
        speed: joint speeds [rad/s].
    """
    current = torque / servo.torque_constant
    mechanical = torque * speed
    recovered = servo.regenerative_efficiency * np.minimum(mechanical, 0.0)
    return np.asarray(servo.idle_power + current * current * servo.winding_resistance
                      + np.maximum(mechanical, 0.0) + recovered)
