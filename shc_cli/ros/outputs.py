"""What ``syropod_highlevel_controller`` publishes each cycle, from one cycle's output (study §10.3).

``/desired_joint_states`` (all joints: desired position without offset, desired velocity, the last measured effort),
the per-joint ``/<LEG>_<joint>_joint/command`` (Float64, desired position + offset) when the individual interface
is on, ``/shc/<LEG>/state`` (OpenSHC's LegState), ``/shc/velocity`` and ``/shc/pose`` (Twist), ``/shc/walkspace``
(Float32MultiArray, RUNNING only), ``/tf`` and shc's ``/odom`` (nav_msgs/Odometry: the leg odometry, ``odom →
base_link``, planar pose and its velocity in base_link; an shc addition, docs/odometry.md). Headers carry the wall
clock.

``/tf`` is one tree, each frame with one parent: ``odom → odom_ideal → base_link → {walk_plane, <LEG>_tip}``.
``odom_ideal → base_link`` is OpenSHC's (``StateController::publishFrameTransforms``): the ideal odometry — the
walk plane's pose integrated from the commanded velocity (``WalkController::getOdometryIdeal``) — composed with the
body's current pose in the walk plane. OpenSHC sends it only while no ``odom`` frame is on the tree; shc's leg
odometry is one, so shc hangs ``odom_ideal`` under it: ``odom → odom_ideal`` is the leg odometry's planar pose times
the inverse of the ideal one, so that ``odom → base_link`` (looked up through ``odom_ideal``) is the leg odometry
composed with the same body pose, and ``odom_ideal → base_link`` stays exactly OpenSHC's. The
publisher is an observer of the run loop; after publishing it lets the remote input take its snapshot, as OpenSHC's
``spinOnce`` follows its publications.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from shc_cli.control.controller import Command, CycleOutput, RobotState
from shc_cli.interop.bag import LEG_STATE_TYPE, Messages, quaternions
from shc_cli.model.body import leg_names
from shc_cli.ros.messages import MessageTypes
from shc_cli.spec.robot import Robot


class Sender(Protocol):
    """A topic's publisher (:class:`shc_cli.ros.node.Publisher`, or a live channel)."""

    @property
    def subscriber_count(self) -> int:
        ...

    def publish(self, message: object) -> None:
        ...


class Transport(Protocol):
    """Where topics go: a ROS node (:class:`shc_cli.ros.node.RosNode`) or a live server
    (:class:`shc_cli.live.foxglove_server.FoxgloveTransport`)."""

    types: MessageTypes

    def advertise(self, topic: str, msgtype: str, latch: bool = False) -> Sender:
        ...

_RUNNING = RobotState.RUNNING
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


class NodeOutputs:
    """Publishes a cycle's outputs on OpenSHC's topics (see the module's text).

    Args:
        node: where the topics go: the ROS node, or a live server.
        robot: the robot (leg and joint names, joint offsets).
        individual: publish the per-joint command topics (OpenSHC's ``individual_control_interface``).
        combined: publish ``/desired_joint_states`` (``combined_control_interface``).
        walkspace: gives the controller's walkspace (radius [m] by bearing [°]), published while RUNNING as OpenSHC's
            9 radii at bearings 0, 45, …, 360°; None: not published.
        after: called before each cycle's publications (the remote input's :meth:`latch`).
        always: publish also while nobody listens (default: without ``sensors``, as a ROS node does).
        sensors: also publish what a simulated robot's sensors read: ``/joint_states`` (measured), ``/imu/data``,
            ``/<LEG>/foot_force`` (WrenchStamped) and ``/shc/power`` (Float64, W), as ``shc export bag`` does.
        joint_states: publish the measured ``/joint_states`` only (a robot on servos: its bus reading's positions
            [rad], velocities [rad/s] and currents as efforts [A], as ``run-hw`` logs them); implied by ``sensors``.
        efforts: the last measured joint efforts ``(L, n)`` [N·m] or None (published as 0).
        ideal: gives the ideal odometry (the walk plane's position [m] and yaw [rad] in ``odom_ideal``), or None
            before the walk controller exists (:func:`ideal_odometry`); None: the walk plane stays at the origin.
    """

    def __init__(self, node: Transport, robot: Robot, individual: bool = True, combined: bool = True,
                 walkspace: Callable[[], dict[int, float]] | None = None,
                 after: Callable[[], None] | None = None, sensors: bool = False,
                 always: bool | None = None, joint_states: bool = False,
                 ideal: Callable[[], tuple[np.ndarray, float] | None] | None = None) -> None:
        self.m = Messages(node.types.store)
        self.ideal = ideal
        self.after = after
        self.efforts: np.ndarray | None = None
        self.period = robot.time_delta
        names = leg_names(robot)
        self.legs = list(robot.legs)
        self.joint_ids = [joint for leg in names.values() for joint in leg.joints]
        self.slots = [(i, k) for i, leg in enumerate(self.legs) for k in range(len(robot.legs[leg].joints))]
        self.rows = np.array([i for i, _ in self.slots])
        self.cols = np.array([k for _, k in self.slots])
        self.offsets = np.array([joint.offset for leg in robot.legs.values() for joint in leg.joints.values()])
        self.walkspace = walkspace
        self.combined = node.advertise("/desired_joint_states", "sensor_msgs/JointState") if combined else None
        self.individual: list[Sender] = [node.advertise(f"/{name}/command", "std_msgs/Float64")
                                            for name in self.joint_ids] if individual else []
        self.leg_states = [node.advertise(f"/shc/{leg}/state", LEG_STATE_TYPE) for leg in self.legs]
        self.velocity = node.advertise("/shc/velocity", "geometry_msgs/Twist")
        self.pose = node.advertise("/shc/pose", "geometry_msgs/Twist")
        self.walkspace_pub = node.advertise("/shc/walkspace", "std_msgs/Float32MultiArray")
        self.tf = node.advertise("/tf", "tf2_msgs/TFMessage")
        self.odom = node.advertise("/odom", "nav_msgs/Odometry")
        self._odometry: tuple[float, float, float] | None = None
        self.sensors = sensors
        self.measured_joints = joint_states and not sensors
        if sensors or joint_states:
            self.joint_states = node.advertise("/joint_states", "sensor_msgs/JointState")
        if sensors:
            self.imu = node.advertise("/imu/data", "sensor_msgs/Imu")
            self.feet = [node.advertise(f"/{leg}/foot_force", "geometry_msgs/WrenchStamped") for leg in self.legs]
            self.foot_frames = [names[leg].foot for leg in self.legs]
            self.power = node.advertise("/shc/power", "std_msgs/Float64")
        self.seq = 0
        # a ROS node publishes whether or not anyone listens, as OpenSHC; a live stream builds nothing while no
        # client is connected
        self.always = not sensors if always is None else always
        self.combined_or_any = self.combined if self.combined is not None else self.tf

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        """Publish this cycle (an observer of the run loop; never stops the run). The remote input's snapshot is
        taken just before ``/desired_joint_states`` goes out: what a recorder saw before that message is what the
        next cycle uses (OpenSHC's publish-then-spin order, without the time our publishing takes)."""
        if self.after is not None:
            self.after()
        if not self.always and not self.combined_or_any.subscriber_count:
            return None  # nobody listens (a live server without clients): build nothing
        self.publish(out, cycle=cycle)
        if self.sensors and reading is not None:
            self.publish_sensors(reading)
        elif self.measured_joints and reading is not None:
            self.publish_bus_joints(reading, cycle)
        return None

    def publish_bus_joints(self, reading: Any, cycle: int) -> None:
        """A servo bus reading (:class:`~shc_cli.hardware.bus.BusState`) as ``/joint_states`` (its header's ``seq``
        the cycle): positions [rad], velocities [rad/s], currents as efforts [A]."""
        now = time.time()
        sec, nanosec = int(now), round((now % 1.0) * 1e9) % 1_000_000_000
        rows, cols = self.rows, self.cols
        header = self.m.header(sec, nanosec, "")
        header.seq = cycle
        self.joint_states.publish(self.m.T["sensor_msgs/msg/JointState"](
            header=header, name=self.joint_ids,
            position=np.asarray(reading.positions)[rows, cols].astype(float),
            velocity=np.asarray(reading.velocities)[rows, cols].astype(float),
            effort=np.asarray(reading.currents)[rows, cols].astype(float) / 1000.0))

    def publish_sensors(self, reading: Any, stamp: float | None = None) -> None:
        """A simulated reading's measured joints, IMU, foot forces and electrical power."""
        T, m = self.m.T, self.m
        now = time.time() if stamp is None else stamp
        sec, nanosec = int(now), round((now % 1.0) * 1e9) % 1_000_000_000
        self.joint_states.publish(T["sensor_msgs/msg/JointState"](
            header=m.header(sec, nanosec, ""), name=self.joint_ids,
            position=np.asarray(reading.joints)[self.rows, self.cols].astype(float),
            velocity=np.asarray(reading.joint_velocities)[self.rows, self.cols].astype(float),
            effort=np.asarray(reading.joint_efforts)[self.rows, self.cols].astype(float)))
        zeros9 = np.zeros(9)
        self.imu.publish(T["sensor_msgs/msg/Imu"](
            header=m.header(sec, nanosec, "base_link"), orientation=m.quaternion(np.asarray(reading.orientation)),
            orientation_covariance=zeros9, angular_velocity=m.vector(np.asarray(reading.angular_rate)),
            angular_velocity_covariance=zeros9, linear_acceleration=m.vector(np.asarray(reading.linear_acceleration)),
            linear_acceleration_covariance=zeros9))
        for publisher, frame, force in zip(self.feet, self.foot_frames, np.asarray(reading.foot_forces).tolist(),
                                           strict=True):
            publisher.publish(T["geometry_msgs/msg/WrenchStamped"](
                header=m.header(sec, nanosec, frame), wrench=T["geometry_msgs/msg/Wrench"](
                    force=m.vector(np.array([0.0, 0.0, force])), torque=m.vector(np.zeros(3)))))
        self.power.publish(T["std_msgs/msg/Float64"](data=float(np.sum(reading.servo_power))))

    def publish(self, out: CycleOutput, stamp: float | None = None, cycle: int | None = None) -> None:
        """Every topic of one cycle, stamped ``stamp`` (seconds since the epoch; default now); ``/desired_joint_states``
        carries the cycle as its header's ``seq`` (default: a count of the published cycles)."""
        T, m = self.m.T, self.m
        now = time.time() if stamp is None else stamp
        sec, nanosec = int(now), round((now % 1.0) * 1e9) % 1_000_000_000
        joints = out.joints[self.rows, self.cols]
        velocities = out.joint_velocities[self.rows, self.cols]
        efforts = self.efforts[self.rows, self.cols] if self.efforts is not None else np.zeros_like(joints)
        if self.combined is not None:
            header = m.header(sec, nanosec, "")
            header.seq = self.seq if cycle is None else cycle
            self.combined.publish(T["sensor_msgs/msg/JointState"](header=header, name=self.joint_ids,
                                                                  position=joints, velocity=velocities,
                                                                  effort=efforts))
        if self.individual:
            for publisher, value in zip(self.individual, (joints + self.offsets).tolist(), strict=True):
                publisher.publish(T["std_msgs/msg/Float64"](data=value))
        for i, publisher in enumerate(self.leg_states):
            publisher.publish(self._leg_state(sec, nanosec, out, i))
        vx, vy, wz = out.velocity
        self.velocity.publish(self._twist((vx, vy, 0.0), (0.0, 0.0, wz)))
        self.pose.publish(self._twist(out.pose[:3], out.pose[3:]))
        if self.walkspace is not None and out.robot_state == _RUNNING:
            layout = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
            radii = self.walkspace()
            if radii:
                values = [radii.get(bearing % 360, 0.0) for bearing in range(0, 361, 45)]
                self.walkspace_pub.publish(T["std_msgs/msg/Float32MultiArray"](
                    layout=layout, data=np.asarray(values, dtype=np.float32)))
        self.tf.publish(self._tf(sec, nanosec, out))
        self.odom.publish(self._odom(sec, nanosec, out.odometry))
        self.seq += 1

    def _twist(self, linear: Any, angular: Any) -> Any:
        T, m = self.m.T, self.m
        return T["geometry_msgs/msg/Twist"](linear=m.vector(np.asarray(linear, dtype=float)),
                                            angular=m.vector(np.asarray(angular, dtype=float)))

    def _leg_state(self, sec: int, nanosec: int, out: CycleOutput, i: int) -> Any:
        T, m = self.m.T, self.m
        leg = self.legs[i]
        count = int(np.count_nonzero(self.rows == i))

        def stamped(position: np.ndarray, frame: str) -> Any:
            return T["geometry_msgs/msg/PoseStamped"](header=m.header(sec, nanosec, frame),
                                                      pose=m.pose(np.concatenate([position, _IDENTITY])))

        zero_pose = m.pose(np.concatenate([np.zeros(3), _IDENTITY]))
        poser = out.poser_tips[i] if np.all(np.isfinite(out.poser_tips[i])) else np.zeros(3)
        return T[LEG_STATE_TYPE](
            header=m.header(sec, nanosec, "base_link"), name=leg,
            walker_tip_pose=stamped(out.walker_tips[i], "walk_plane"),
            target_tip_pose=stamped(np.zeros(3), "walk_plane"),
            poser_tip_pose=stamped(poser, "base_link"), model_tip_pose=stamped(out.model_tips[i], "base_link"),
            actual_tip_pose=stamped(out.model_tips[i], "base_link"),
            model_tip_velocity=T["geometry_msgs/msg/TwistStamped"](
                header=m.header(sec, nanosec, "base_link"), twist=self._twist(np.zeros(3), np.zeros(3))),
            joint_positions=out.joints[i, :count].astype(float).copy(),
            joint_velocities=out.joint_velocities[i, :count].astype(float).copy(),
            joint_efforts=(self.efforts[i, :count].astype(float).copy() if self.efforts is not None
                           else np.zeros(count)),
            stance_progress=float(out.stance_progress[i]), swing_progress=float(out.swing_progress[i]),
            time_to_swing_end=0.0, pose_delta=zero_pose, auto_pose=zero_pose, tip_force=m.vector(np.zeros(3)),
            admittance_delta=m.vector(np.zeros(3)), virtual_stiffness=0.0)

    def _odom(self, sec: int, nanosec: int, pose: tuple[float, float, float]) -> Any:
        """The leg odometry as nav_msgs/Odometry: pose in ``odom``, velocity (the change since the last published
        cycle ÷ the control period) in base_link axes."""
        T, m = self.m.T, self.m
        x, y, yaw = pose
        last = self._odometry or pose
        self._odometry = pose
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy = (x - last[0]) / self.period, (y - last[1]) / self.period
        linear = np.array([c * vx + s * vy, -s * vx + c * vy, 0.0])
        angular = np.array([0.0, 0.0, (yaw - last[2]) / self.period])
        quaternion = np.array([0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)])
        return T["nav_msgs/msg/Odometry"](
            header=m.header(sec, nanosec, "odom"), child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=m.pose(np.array([x, y, 0.0, *quaternion])),
                                                           covariance=np.zeros(36)),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=self._twist(linear, angular),
                                                             covariance=np.zeros(36)))

    def _tf(self, sec: int, nanosec: int, out: CycleOutput) -> Any:
        T, m = self.m.T, self.m
        x, y, z, roll, pitch, yaw = out.pose
        ideal = self.ideal() if self.ideal is not None else None
        plane, heading = (np.zeros(3), 0.0) if ideal is None else (np.asarray(ideal[0], dtype=float), ideal[1])
        turn = _rotation(0.0, 0.0, heading)
        position = plane + turn @ np.array([x, y, z])  # odometry_ideal.addPose(current_pose)
        body_q = quaternions((turn @ _rotation(roll, pitch, yaw))[None])[0]
        ox, oy, oyaw = out.odometry  # odom → odom_ideal: the leg odometry's planar pose ∘ the ideal one's inverse
        offset = _rotation(0.0, 0.0, oyaw - heading)
        shift = np.array([ox, oy, 0.0]) - offset @ plane
        transforms = [m.transform(sec, nanosec, "odom", "odom_ideal",
                                  np.array([*shift, *quaternions(offset[None])[0]])),
                      m.transform(sec, nanosec, "odom_ideal", "base_link", np.array([*position, *body_q])),
                      m.transform(sec, nanosec, "base_link", "walk_plane",
                                  np.array([0.0, 0.0, -z, *quaternions(_rotation(-roll, -pitch, 0.0)[None])[0]]))]
        transforms += [m.transform(sec, nanosec, "base_link", f"{leg}_tip", np.concatenate([out.model_tips[i],
                                                                                             _IDENTITY]))
                       for i, leg in enumerate(self.legs)]
        return T["tf2_msgs/msg/TFMessage"](transforms=transforms)


def ideal_odometry(controller: Any) -> Callable[[], tuple[np.ndarray, float] | None]:
    """What :class:`NodeOutputs`'s ``ideal`` reads from ``controller``: its walk controller's ideal odometry
    (position [m], yaw [rad]), None while there is none (before RUNNING)."""

    def read() -> tuple[np.ndarray, float] | None:
        walker = controller.walker
        return None if walker is None else (walker.odometry_position, walker.odometry_yaw)

    return read


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """Rotation matrix of roll, pitch, yaw (z·y·x) [rad]."""
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw),
                              math.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])
