"""Electrical power of the servos from joint torque and speed: kept for callers of the old function; the model is
:class:`shc_cli.backends.servo.ServoModel` (engine-independent)."""

from __future__ import annotations

import numpy as np

from shc_cli.backends.servo import ServoModel
from shc_cli.spec.robot import Servo


def servo_power(servo: Servo, torque: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Electrical power of each servo [W] (:meth:`ServoModel.power`).

    Args:
        servo: the servo model.
        torque: joint torques [N·m].
        speed: joint speeds [rad/s].
    """
    return ServoModel(servo).power(torque, speed)
