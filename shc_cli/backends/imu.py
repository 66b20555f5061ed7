"""The simulated IMU, the same for every engine: specific force and angular rate in the body frame, with noise, and
its orientation, with a gyro yaw-rate bias when asked."""

from __future__ import annotations

import math

import numpy as np

from shc_cli.model.body import GRAVITY


class Imu:
    """An IMU on the body: the engine gives the body's rotation and velocities, this gives the readings.

    The linear acceleration is the change of the body's velocity over one control period (the rate the sensors
    are read at), so it is the mean acceleration of that period; its noise and the rate's are Gaussian.

    A gyro yaw-rate bias ``yaw_bias`` makes the IMU read the body turning about the vertical ``yaw_bias`` faster
    than it does: it is added to the angular rate (about the world's vertical, in the body frame), and the
    orientation the IMU reports — integrated from its gyro, as a real IMU's — drifts in yaw by ``yaw_bias`` × the
    time since the first reading (roll and pitch stay true: a real IMU's accelerometer holds them).

    Args:
        control_period: time between readings [s].
        noise: standard deviation of the noise added to every component (m/s² and rad/s alike); 0 = none.
        seed: seed of the noise.
        yaw_bias: gyro yaw-rate bias [rad/s]; 0 = none.
    """

    def __init__(self, control_period: float, noise: float, seed: int, yaw_bias: float = 0.0) -> None:
        self.control_period = control_period
        self.noise = noise
        self.yaw_bias = yaw_bias
        self.rng = np.random.default_rng(seed)
        self._previous_velocity = [0.0, 0.0, 0.0]
        self._readings = 0

    def sense(self, rotation: np.ndarray, velocity: np.ndarray,
              angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Specific force [m/s²] (at rest +9.81 along the body's up axis) and angular rate [rad/s], body frame.

        Args:
            rotation: body → world rotation matrix.
            velocity: the body's (centre-of-mass) velocity in the world frame [m/s].
            angular_velocity: the body's angular velocity in the world frame [rad/s].
        """
        # Elementwise on Python floats (the same IEEE operations as NumPy's, cheaper on 3 values); the products
        # with the rotation stay NumPy's.
        v, before, period = velocity.tolist(), self._previous_velocity, self.control_period
        self._previous_velocity = v
        specific_force = rotation.T @ np.array([(v[0] - before[0]) / period + 0.0, (v[1] - before[1]) / period + 0.0,
                                                (v[2] - before[2]) / period + GRAVITY])
        rate = rotation.T @ angular_velocity
        if self.yaw_bias != 0.0:
            rate = rate + rotation.T @ np.array([0.0, 0.0, self.yaw_bias])
        if self.noise > 0.0:
            specific_force = specific_force + self.rng.normal(0.0, self.noise, 3)
            rate = rate + self.rng.normal(0.0, self.noise, 3)
        return specific_force, rate

    def orientation(self, quaternion: np.ndarray) -> np.ndarray:
        """The orientation the IMU reports (x, y, z, w) for the body's true one ``quaternion`` (x, y, z, w), read
        once a control period after :meth:`sense`: the true one without a yaw bias, else turned about the world's
        vertical by the drift ``yaw_bias`` × the time since the first reading [rad]."""
        if self.yaw_bias == 0.0:
            return quaternion
        drift = self.yaw_bias * self._readings * self.control_period
        self._readings += 1
        c, s = math.cos(drift / 2), math.sin(drift / 2)
        x, y, z, w = np.asarray(quaternion, dtype=float).tolist()
        return np.array([c * x - s * y, c * y + s * x, c * z + s * w, c * w - s * z])
