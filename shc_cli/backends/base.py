"""The backend protocol: what turns the controller's joint targets into the next sensor reading.

``plan``, ``simulate`` and ``run-hw`` differ only in their backend (:mod:`shc_cli.backends.kinematic`,
:mod:`shc_cli.backends.simulated`, :mod:`shc_cli.backends.dynamixel`); the one run loop
(:mod:`shc_cli.loop.run_loop`) drives any of them. One control cycle is::

    out = controller.step(command, backend.sensors(wanted))
    applied = backend.apply(out)        # joint targets as sent (after the backend's own limits)
    backend.advance()                   # one control period: physics sub-steps | real-time wait | nothing
    reading = backend.read()            # what the robot measured at the end of the period
    backend.fault()                     # a reason to stop at once (servo fault), or None

A backend that measures the ``log.csv`` quantities also gives :meth:`MeasuringBackend.measured`: the data, as a
:class:`Measured`; the loop's recorder (:class:`shc_cli.record.runlog.LogRecorder`) formats it. The kinematic backend
measures nothing and its runs are logged as the controller's own tables (``joints.csv``, ``tips.csv``, ``body.csv``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, TypeVar, runtime_checkable

if TYPE_CHECKING:
    import numpy as np

    from shc_cli.backends.engine import Reading
    from shc_cli.control.controller import Command, CycleOutput
    from shc_cli.control.sensing import Sensors

MEASURED_BODY_COLUMNS = ["x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "wx", "wy", "wz", "imu_qx",
                         "imu_qy", "imu_qz", "imu_qw", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z",
                         "height", "power_w"]
"""The body and IMU quantities a measuring backend reports (:meth:`Measured.body_values`), as columns of ``log.csv``
after the per-leg ones: ground-truth position [m], roll/pitch/yaw [rad], world linear [m/s] and angular [rad/s]
velocity, IMU quaternion (x, y, z, w, body → world), gyro [rad/s], specific force [m/s²], body height above the
terrain [m], total servo power [W]."""
ReadingT = TypeVar("ReadingT")
"""What a backend's :meth:`Backend.read` returns: the physics engine's
:class:`~shc_cli.backends.engine.Reading`, the servo bus's :class:`~shc_cli.hardware.bus.BusState`, or ``None``
(the kinematic backend measures nothing)."""
ReadingT_co = TypeVar("ReadingT_co", covariant=True)


@dataclass(slots=True)
class Measured:
    """What a measuring backend measured at the end of a cycle; ``None``: not measured (logged as 0).

    Attributes:
        joints: the real joints' positions in servo order (legs in id order, joints body to tip) ``(J,)`` [rad].
        torques: their torques ``(J,)`` [N·m].
        power: their servos' electrical power ``(J,)`` [W].
        foot_forces: contact normal force on each foot ``(L,)`` [N].
        foot_contact: whether each foot touches anything ``(L,)``.
        body: the body's ground-truth pose and twist, IMU and height (an engine's reading).
    """

    joints: np.ndarray
    torques: np.ndarray
    power: np.ndarray | None = None
    foot_forces: np.ndarray | None = None
    foot_contact: np.ndarray | None = None
    body: Reading | None = None

    def total_power(self) -> float:
        """Sum of the servos' power [W] (0 when not measured)."""
        return float(self.power.sum()) if self.power is not None else 0.0

    def body_values(self) -> list[np.ndarray | tuple[float, ...]]:
        """The values of :data:`MEASURED_BODY_COLUMNS`, in that order (``None`` when the body is not measured)."""
        r = self.body
        assert r is not None
        return [r.position, r.rpy, r.linear_velocity, r.angular_velocity, r.orientation, r.angular_rate,
                r.linear_acceleration, (r.body_height, self.total_power())]


@runtime_checkable
class Backend(Protocol[ReadingT_co]):
    """One robot, real or not, advanced one control period at a time (its readings of type ``ReadingT_co``)."""

    def start(self) -> np.ndarray | None:
        """Open the robot; returns the joint positions ``(L, n)`` [rad] it starts from (``None``: the controller's
        own start, as the kinematic backend)."""
        ...

    def begin(self) -> None:
        """Called once just before the first control cycle (torque on, real-time clock starts)."""
        ...

    def sensors(self, wanted: bool) -> Sensors | None:
        """What the controller sees in the next cycle (``wanted``: the controller uses sensor feedback)."""
        ...

    def apply(self, out: CycleOutput) -> np.ndarray:
        """Send this cycle's joint targets; returns them as sent ``(L, n)`` [rad]."""
        ...

    def advance(self) -> None:
        """One control period."""
        ...

    def read(self) -> ReadingT_co:
        """The reading at the end of the period (its type is the backend's; ``None`` when nothing is measured)."""
        ...

    def fault(self) -> str | None:
        """Why the run must stop at once (no further target is sent), or ``None``."""
        ...

    def close(self, faulted: bool = False) -> None:
        """Release the robot (``faulted``: the run ended on a fault)."""
        ...


class MeasuringBackend(Backend[ReadingT], Protocol[ReadingT]):
    """A backend whose reading fills the measured columns of ``log.csv`` (the type of
    :class:`~shc_cli.record.runlog.LogRecorder`'s backend)."""

    def measured(self, reading: ReadingT) -> Measured:
        """What ``reading`` measured."""
        ...


class InputSource(Protocol):
    """Commands for the loop once the start-up is done (timeline, stdin, keyboard, gamepad, a recording).

    :meth:`next` gives this cycle's command, ``None`` when the input is over.
    """

    def next(self) -> Command | None:
        ...

    def close(self) -> None:
        ...


@runtime_checkable
class FeedbackSource(Protocol):
    """An input source that steers by the controller's output (a path follower): the loop calls :meth:`observe`
    with every cycle's output, right after the controller's step, so the next :meth:`InputSource.next` sees it."""

    def observe(self, out: CycleOutput) -> None:
        ...
