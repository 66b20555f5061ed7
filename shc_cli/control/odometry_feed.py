"""The odometry feed of the controller: each cycle's leg odometry (:mod:`shc_cli.control.odometry`, an shc addition)
from the commanded or measured feet, the IMU and the commanded body pose. A collaborator of
:class:`~shc_cli.control.controller.Controller` (:class:`~shc_cli.control.core.ControllerCore`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from shc_cli.control.odometry import LegOdometry, euler_yaw_rate
from shc_cli.model import kernels

if TYPE_CHECKING:
    from shc_cli.control.core import ControllerCore
    from shc_cli.control.sensing import Sensors
    from shc_cli.model.chains import FloatArray


class OdometryFeed:
    """Leg odometry fed by the controller's cycle."""

    def __init__(self, core: ControllerCore) -> None:
        self.c = core
        legs = len(core.robot.legs)
        self.odometry = LegOdometry(core.dt)
        """Leg odometry (an shc addition): read by :attr:`~shc_cli.control.controller.CycleOutput.odometry`."""
        self._stance_before = np.zeros(legs, dtype=bool)
        self._measured_feet: FloatArray = np.empty((legs, 3))
        """The feet of the measured joints [m] (the odometry reads them; it keeps only its levelled copy)."""

    def update(self, sensors: Sensors | None, stance: np.ndarray) -> tuple[float, float, float]:
        """One cycle of leg odometry (:mod:`shc_cli.control.odometry`).

        Measured joints (``sensors.joints``) are the feet at the start of this cycle: the motion since the last
        reading is the previous cycle's, so the feet in stance then are used; commanded joints are this cycle's
        targets, used with this cycle's stance. Foot contact, where measured, must hold at both readings; measured
        foot forces weigh the feet. Roll and pitch come from the IMU or else the commanded body pose; the IMU's
        heading change (of its orientation; of its angular rate × dt without one) is fused.
        """
        core = self.c
        if sensors is None:
            self._stance_before = stance
            roll, pitch, _ = core.poser.current.euler()
            return self.odometry.cycle(core.model.tips, roll, pitch, stance)
        if sensors.joints is not None:  # Chains.tips's kernel, into a buffer of the odometry's
            c, feet = core.model.chains, self._measured_feet
            kernels.tips_kernel(c.base, c.d, c.theta, c.r, c.alpha, np.ascontiguousarray(sensors.joints, dtype=float),
                                feet)
            use = self._stance_before
        else:
            feet, use = core.model.tips, stance
        self._stance_before = stance
        orientation, turn, roll, pitch = sensors.orientation, None, 0.0, 0.0
        if orientation is None:
            roll, pitch, _ = core.poser.current.euler()
            if sensors.angular_rate is not None:
                turn = euler_yaw_rate(roll, pitch, np.asarray(sensors.angular_rate, dtype=float)) * core.dt
        commanded = core.walker.desired_angular if core.walker is not None else 0.0
        return self.odometry.cycle(feet, roll, pitch, use, turn, sensors.foot_forces, orientation,
                                   sensors.foot_contact, commanded)
