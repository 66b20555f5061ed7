"""Bags as a running OpenSHC and ``rosbag record`` would write them, built from a recording of the real binary.

Message types: OpenSHC's own ``LegState.msg`` (golden/openshc/msg/, from csiro-robotics/syropod_highlevel_controller)
registered in a rosbags typestore, the rest from ROS Noetic (ROS 1) or Humble (ROS 2). Timing as recorded: each
cycle's LegStates, ``/shc/velocity`` and ``/shc/pose`` shortly before its ``/desired_joint_states``; the remote's
inputs at 10 Hz (and when they change) between two cycles' outputs, so that the input the recorder saw before a
cycle's output is the recording's ``cmd_*`` of that cycle.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.replay.source import Recorded

from .conftest import GOLDEN

LEG_STATE = "syropod_highlevel_controller/msg/LegState"
BASE_NS = 1_700_000_000 * 10**9
"""Bag time of cycle 0 [ns]; cycle c is received at BASE_NS + c·10 ms."""
PERIOD_NS = 10_000_000


def typestore(ros1: bool) -> Any:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC if ros1 else Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg((GOLDEN / "openshc" / "msg" / "LegState.msg").read_text(), LEG_STATE))
    return store


def write_openshc_bag(recorded: Recorded, path: Path, ros1: bool, topics: set[str] | None = None,
                      more_inputs: tuple[str, ...] = ()) -> Path:
    """Write ``recorded`` as OpenSHC's topics (all, or only ``topics``) into a ROS 1 ``.bag`` file or a ROS 2 mcap
    bag directory at ``path``; ``more_inputs``: Int8 remote topics with one message (0) at cycle 0."""
    store = typestore(ros1)
    T = store.types
    assert recorded.tips is not None and recorded.progress is not None
    assert recorded.velocity is not None and recorded.pose is not None

    def header(t: float, frame: str) -> Any:
        sec = int(t)
        stamp = T["builtin_interfaces/msg/Time"](sec=1_700_000_000 + sec, nanosec=round((t - sec) * 1e9))
        if ros1:
            return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)
        return T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)

    def vector(x: float, y: float, z: float) -> Any:
        return T["geometry_msgs/msg/Vector3"](x=float(x), y=float(y), z=float(z))

    def twist(linear: tuple[float, ...], angular: tuple[float, ...]) -> Any:
        return T["geometry_msgs/msg/Twist"](linear=vector(*linear), angular=vector(*angular))

    def pose(p: np.ndarray) -> Any:
        return T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]), z=float(p[2])),
            orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0))

    def stamped(t: float, frame: str, p: np.ndarray) -> Any:
        return T["geometry_msgs/msg/PoseStamped"](header=header(t, frame), pose=pose(p))

    zero3 = np.zeros(3)
    per_leg = len(recorded.joint_names) // len(recorded.legs)

    def leg_state(cycle: int, i: int, leg: str) -> Any:
        t = float(recorded.t[cycle])
        tips = recorded.tips
        assert tips is not None and recorded.progress is not None
        joints = recorded.joints[cycle, i * per_leg:(i + 1) * per_leg].copy()
        return T[LEG_STATE](
            header=header(t, "base_link"), name=leg,
            walker_tip_pose=stamped(t, "walk_plane", tips["walker"][cycle, i]),
            target_tip_pose=stamped(t, "walk_plane", zero3),
            poser_tip_pose=stamped(t, "base_link", tips["poser"][cycle, i]),
            model_tip_pose=stamped(t, "base_link", tips["model"][cycle, i]),
            actual_tip_pose=stamped(t, "base_link", zero3),
            model_tip_velocity=T["geometry_msgs/msg/TwistStamped"](header=header(t, "base_link"),
                                                                   twist=twist((0, 0, 0), (0, 0, 0))),
            joint_positions=joints, joint_velocities=np.zeros(per_leg), joint_efforts=np.zeros(per_leg),
            stance_progress=float(recorded.progress[cycle, i, 0]), swing_progress=float(recorded.progress[cycle, i, 1]),
            time_to_swing_end=0.0, pose_delta=pose(zero3), auto_pose=pose(zero3), tip_force=vector(0, 0, 0),
            admittance_delta=vector(0, 0, 0), virtual_stiffness=0.0)

    count = len(recorded.joint_names)
    streams: list[tuple[str, str, Any]] = []  # (topic, type, per-cycle message builder returning [(ns, msg)])

    def joints_at(c: int) -> list[tuple[int, Any]]:
        message = T["sensor_msgs/msg/JointState"](header=header(float(recorded.t[c]), ""), name=recorded.joint_names,
                                                  position=recorded.joints[c].copy(), velocity=np.zeros(count),
                                                  effort=np.zeros(count))
        return [(BASE_NS + c * PERIOD_NS, message)]

    def changed(c: int, values: np.ndarray) -> bool:
        return c % 10 == 0 or bool(np.any(values[c] != values[c - 1]))

    def velocity_input(c: int) -> list[tuple[int, Any]]:
        if not changed(c, recorded.command):
            return []
        vx, vy, wz = recorded.command[c]
        return [(BASE_NS + c * PERIOD_NS - PERIOD_NS // 2, twist((vx, vy, 0.0), (0.0, 0.0, wz)))]

    def state_input(c: int) -> list[tuple[int, Any]]:
        return [(BASE_NS + c * PERIOD_NS - PERIOD_NS // 2, T["std_msgs/msg/Int8"](data=2))] if c % 10 == 0 else []

    streams.append(("/syropod_remote/desired_velocity", "geometry_msgs/msg/Twist", velocity_input))
    streams.append(("/syropod_remote/robot_state", "std_msgs/msg/Int8", state_input))
    for i, leg in enumerate(recorded.legs):
        streams.append((f"/shc/{leg}/state", LEG_STATE,
                        lambda c, i=i, leg=leg: [(BASE_NS + c * PERIOD_NS - 300_000, leg_state(c, i, leg))]))
    velocity, body = recorded.velocity, recorded.pose
    streams.append(("/shc/velocity", "geometry_msgs/msg/Twist", lambda c: [(BASE_NS + c * PERIOD_NS - 200_000, twist(
        (velocity[c, 0], velocity[c, 1], 0.0), (0.0, 0.0, velocity[c, 2])))]))
    streams.append(("/shc/pose", "geometry_msgs/msg/Twist", lambda c: [(BASE_NS + c * PERIOD_NS - 100_000, twist(
        tuple(body[c, :3]), tuple(body[c, 3:])))]))
    streams.append(("/desired_joint_states", "sensor_msgs/msg/JointState", joints_at))
    if topics is not None:
        streams = [s for s in streams if s[0] in topics]
    for topic in more_inputs:
        streams.insert(0, (topic, "std_msgs/msg/Int8",
                           lambda c: [(BASE_NS - PERIOD_NS // 2, T["std_msgs/msg/Int8"](data=0))] if c == 0 else []))
    if ros1:
        from rosbags.rosbag1 import Writer as Writer1

        writer: Any = Writer1(path)
        serialize = store.serialize_ros1
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
        serialize = store.serialize_cdr
    with writer:
        connections = {topic: writer.add_connection(topic, msgtype, typestore=store) for topic, msgtype, _ in streams}
        for cycle in range(recorded.cycles):
            for topic, msgtype, build in streams:
                for stamp, message in build(cycle):
                    writer.write(connections[topic], stamp, serialize(message, msgtype))
    return path
