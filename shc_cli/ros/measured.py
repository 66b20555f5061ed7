"""What a robot's own nodes measure, as OpenSHC takes it in: ``/joint_states``, ``/imu/data`` and ``/tip_states``.

OpenSHC's ``syropod_highlevel_controller`` next to a hardware interface node (or a simulator's joint state
publisher) subscribes three sensor topics (study §10.2) and uses them as follows; :class:`MeasuredInputs` does the
same on either node (ROS 1's :class:`~shc_cli.ros.node.RosNode`, ROS 2's :class:`~shc_cli.ros2.node.Ros2Node`):

* ``/joint_states`` (sensor_msgs/JointState), matched by joint name: at start-up OpenSHC waits up to
  ``ACQUISTION_TIME`` = 10 s for every joint's position and starts its model from them less each joint's offset
  (else from ``clamp(0, min, max)``, with a warning) — :meth:`MeasuredInputs.wait_for_joints`. Afterwards the
  measured efforts feed admittance control's tip force (``use_joint_effort``) and ``/desired_joint_states``'s effort
  field, and the measured positions shc's leg odometry.
* ``/imu/data`` (sensor_msgs/Imu): the orientation and angular velocity of IMU posing (``imu_posing``, RUNNING only)
  and inclination posing.
* ``/tip_states`` (syropod_highlevel_controller/TipState, by the name's leg prefix, ``AR_tip`` → ``AR``): each
  tip's measured force, whose magnitude is compared with the touchdown and lift-off thresholds (study §8.4) and is
  admittance control's force without ``use_joint_effort``. Its ``step_plane`` (a range sensor's) is not used:
  shc's controller has no step-plane input.

Each cycle the controller reads the newest of each (:meth:`MeasuredInputs.sensors`, through
:class:`MeasuredBackend`); while nothing arrived the controller runs as without sensors, exactly.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.backends.kinematic import KinematicBackend
from shc_cli.control.sensing import Sensors
from shc_cli.events import NOTICE

if TYPE_CHECKING:
    from shc_cli.control.controller import Command, CycleOutput
    from shc_cli.ros.outputs import NodeOutputs
    from shc_cli.ros.transport import Node
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

ACQUISITION_TIME_S = 10.0
"""How long OpenSHC waits at start-up for ``/joint_states`` to give every joint (``ACQUISTION_TIME``) [s]."""
TIP_STATE_TYPE = "syropod_highlevel_controller/TipState"


class MeasuredInputs:
    """The newest ``/joint_states``, ``/imu/data`` and ``/tip_states`` of ``node`` for ``robot`` (subscribed at once).

    Args:
        node: the ROS node (either transport).
        robot: the robot (joint names ``<LEG>_<joint>_joint``, offsets, leg names).
    """

    def __init__(self, node: Node, robot: Robot) -> None:
        from shc_cli.model.body import leg_names

        self._slots = {joint: (i, k, spec.offset) for i, (leg, names) in enumerate(leg_names(robot).items())
                       for k, (joint, spec) in enumerate(zip(names.joints, robot.legs[leg].joints.values(),
                                                             strict=True))}
        self._legs = {leg: i for i, leg in enumerate(robot.legs)}
        width = max(len(leg.joints) for leg in robot.legs.values())
        self._lock = threading.Lock()
        self._joints = np.zeros((len(robot.legs), width))
        self._efforts = np.zeros((len(robot.legs), width))
        self._seen: set[str] = set()
        self._complete = threading.Event()
        self._orientation: np.ndarray | None = None
        self._rate: np.ndarray | None = None
        self._forces: np.ndarray | None = None
        self.counts = {"/joint_states": 0, "/imu/data": 0, "/tip_states": 0}
        """Messages received per topic."""
        node.subscribe("/joint_states", "sensor_msgs/JointState", self._on_joints)
        node.subscribe("/imu/data", "sensor_msgs/Imu", self._on_imu)
        node.subscribe("/tip_states", TIP_STATE_TYPE, self._on_tips)

    # ---- the subscriptions (reader threads) ----------------------------------------------------------------

    def _on_joints(self, message: Any) -> None:
        positions, efforts = list(message.position), list(message.effort)
        with self._lock:
            self.counts["/joint_states"] += 1
            for j, name in enumerate(message.name):
                slot = self._slots.get(name)
                if slot is None or j >= len(positions):
                    continue
                i, k, offset = slot
                self._joints[i, k] = float(positions[j]) - offset
                if j < len(efforts):
                    self._efforts[i, k] = float(efforts[j])
                self._seen.add(name)
            if len(self._seen) == len(self._slots):
                self._complete.set()

    def _on_imu(self, message: Any) -> None:
        q, w = message.orientation, message.angular_velocity
        with self._lock:
            self.counts["/imu/data"] += 1
            self._orientation = np.array([q.x, q.y, q.z, q.w], dtype=float)
            self._rate = np.array([w.x, w.y, w.z], dtype=float)

    def _on_tips(self, message: Any) -> None:
        with self._lock:
            self.counts["/tip_states"] += 1
            forces = self._forces if self._forces is not None else np.zeros(len(self._legs))
            for name, wrench in zip(message.name, message.wrench, strict=False):
                i = self._legs.get(str(name).split("_", 1)[0])  # "AR_tip" or "AR": OpenSHC's leg prefix
                if i is not None:
                    f = wrench.force
                    forces[i] = float(np.sqrt(f.x * f.x + f.y * f.y + f.z * f.z))
            self._forces = forces

    # ---- what the controller reads ---------------------------------------------------------------------------

    def wait_for_joints(self, timeout: float = ACQUISITION_TIME_S,
                        clock: Callable[[], float] = time.monotonic) -> np.ndarray | None:
        """OpenSHC's start-up: wait up to ``timeout`` s (0: not at all) for ``/joint_states`` to give every joint;
        the measured positions less the offsets ``(L, n)`` [rad], or None with a one-line warning naming the missing
        joints (the controller then starts from ``clamp(0, min, max)``, as OpenSHC does)."""
        if timeout > 0:
            log.log(NOTICE, "waiting up to %.0f s for /joint_states to give the robot's %d joints", timeout,
                     len(self._slots))
        if self._complete.wait(max(timeout, 0.0)):
            with self._lock:
                log.info("starting from the measured /joint_states")
                return self._joints.copy()
        with self._lock:
            missing = sorted(set(self._slots) - self._seen)
        if timeout > 0:
            log.warning("no /joint_states for %s within %.0f s: starting from the joints' defaults "
                        "(clamp(0, min, max)), as OpenSHC does", ", ".join(missing[:3])
                        + (f" and {len(missing) - 3} more" if len(missing) > 3 else ""), timeout)
        return None

    def sensors(self) -> Sensors | None:
        """The newest measurements (None while nothing arrived: the controller runs as without sensors)."""
        with self._lock:
            joints = self._complete.is_set()
            if not joints and self._orientation is None and self._forces is None:
                return None
            return Sensors(orientation=None if self._orientation is None else self._orientation.copy(),
                           angular_rate=None if self._rate is None else self._rate.copy(),
                           joints=self._joints.copy() if joints else None,
                           joint_efforts=self._efforts.copy() if joints else None,
                           foot_forces=None if self._forces is None else self._forces.copy())

    def efforts(self) -> np.ndarray | None:
        """The last measured joint efforts ``(L, n)``, once every joint was measured (else None)."""
        with self._lock:
            return self._efforts.copy() if self._complete.is_set() else None

    def feed_efforts(self, outputs: NodeOutputs) -> Callable[[int, Command, CycleOutput, object], str | None]:
        """An observer (before ``outputs``) that gives ``/desired_joint_states`` the last measured efforts, as
        OpenSHC's "desired" effort is."""

        def observe(cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
            outputs.efforts = self.efforts()
            return None

        return observe


class MeasuredBackend(KinematicBackend):
    """Backend ``none`` with the robot's own sensors: the targets are taken as reached (OpenSHC with a hardware node
    of the user's) and the controller reads :meth:`MeasuredInputs.sensors` each cycle."""

    def __init__(self, measured: MeasuredInputs) -> None:
        self.measured = measured

    def sensors(self, wanted: bool) -> Sensors | None:
        return self.measured.sensors()
