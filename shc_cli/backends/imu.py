"""The simulated IMU, the same for every engine: specific force and angular rate in the body frame, with noise."""

from __future__ import annotations

import numpy as np

from shc_cli.model.body import GRAVITY


class Imu:
    """An IMU on the body: the engine gives the body's rotation and velocities, this gives the readings.

    The linear acceleration is the change of the body's velocity over one control period (the rate the sensors
    are read at), so it is the mean acceleration of that period; its noise and the rate's are Gaussian.

    Args:
        control_period: time between readings [s].
        noise: standard deviation of the noise added to every component (m/s² and rad/s alike); 0 = none.
        seed: seed of the noise.
    """

    def __init__(self, control_period: float, noise: float, seed: int) -> None:
        self.control_period = control_period
        self.noise = noise
        self.rng = np.random.default_rng(seed)
        self._previous_velocity = np.zeros(3)

    def sense(self, rotation: np.ndarray, velocity: np.ndarray,
              angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Specific force [m/s²] (at rest +9.81 along the body's up axis) and angular rate [rad/s], body frame.

        Args:
            rotation: body → world rotation matrix.
            velocity: the body's (centre-of-mass) velocity in the world frame [m/s].
            angular_velocity: the body's angular velocity in the world frame [rad/s].
        """
        acceleration = (velocity - self._previous_velocity) / self.control_period
        self._previous_velocity = velocity
        specific_force = rotation.T @ (acceleration + np.array([0.0, 0.0, GRAVITY]))
        rate = rotation.T @ angular_velocity
        if self.noise > 0.0:
            specific_force = specific_force + self.rng.normal(0.0, self.noise, 3)
            rate = rate + self.rng.normal(0.0, self.noise, 3)
        return specific_force, rate
