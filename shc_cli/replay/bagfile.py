"""A ROS 1 or ROS 2 bag recorded from a running OpenSHC, as a :class:`~shc_cli.replay.source.Recorded`.

Topics read (whatever subset is present; ``/desired_joint_states`` and ``/syropod_remote/desired_velocity`` are
needed):

| topic | type | gives |
|---|---|---|
| ``/desired_joint_states`` | sensor_msgs/JointState | the cycles (one message per control cycle) and their joints |
| ``/shc/LEG/state`` | syropod_highlevel_controller/LegState | walker, poser and model tips; stance/swing progress |
| ``/shc/velocity`` | geometry_msgs/Twist | OpenSHC's desired body velocity (linear x, y, angular z) |
| ``/shc/pose`` | geometry_msgs/Twist | OpenSHC's body pose (linear = position, angular = roll, pitch, yaw) |
| ``/syropod_remote/desired_velocity`` | geometry_msgs/Twist | the velocity input |
| ``/syropod_remote/robot_state`` | std_msgs/Int8 | the requested robot state |

Outputs of a cycle are joined with its ``/desired_joint_states`` message by index when a topic has as many
messages, else by the nearest receive time. Inputs are taken as the recorder's CSVs take them: the last message
received before the cycle's ``/desired_joint_states``. Message types are those embedded in the bag (ROS 1, mcap);
bags without them use ROS Noetic/Humble types plus OpenSHC's LegState.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.errors import ShcError
from shc_cli.replay.source import Recorded

JOINTS = "/desired_joint_states"
VELOCITY_INPUT = "/syropod_remote/desired_velocity"
STATE_INPUT = "/syropod_remote/robot_state"
VELOCITY = "/shc/velocity"
POSE = "/shc/pose"
LEG_STATE = re.compile(r"^/shc/([^/]+)/state$")
RECORD_HINT = ("record them from the running controller: rosbag record /desired_joint_states "
               "/syropod_remote/desired_velocity /syropod_remote/robot_state /shc/velocity /shc/pose "
               "-e '/shc/.*/state'")


def read_bag(path: Path) -> Recorded:
    """Read the OpenSHC topics of a bag into per-cycle arrays; one-line errors for unusable bags."""
    from rosbags.highlevel import AnyReader

    from shc_cli.interop.bag import typestore_for

    ros1 = path.is_file()
    kind = "ROS 1 bag" if ros1 else "ROS 2 bag"
    try:
        with AnyReader([path], default_typestore=typestore_for("ros1" if ros1 else "mcap")) as reader:
            if reader.message_count == 0:
                raise ShcError(f"{path}: the bag is empty (no messages; {RECORD_HINT})")
            by_topic: dict[str, list[Any]] = {}
            for connection in reader.connections:
                by_topic.setdefault(connection.topic, []).append(connection)
            if JOINTS not in by_topic:
                raise ShcError(f"{path}: no {JOINTS} in the bag (topics: {_listing(by_topic)}; {RECORD_HINT})")
            if VELOCITY_INPUT not in by_topic:
                raise ShcError(f"{path}: no {VELOCITY_INPUT} in the bag, so the velocity inputs are unknown "
                               f"(topics: {_listing(by_topic)}; {RECORD_HINT})")
            not_replayed = sorted(topic for topic in by_topic if topic.startswith("/syropod_remote/")
                                  and topic not in (VELOCITY_INPUT, STATE_INPUT, "/syropod_remote/system_state")
                                  and any(c.msgcount for c in by_topic[topic]))
            wanted = [JOINTS, VELOCITY_INPUT, STATE_INPUT, VELOCITY, POSE]
            legs = [m.group(1) for topic in by_topic if (m := LEG_STATE.match(topic))
                    and all(c.msgtype.endswith("LegState") for c in by_topic[topic])]
            topics = [t for t in wanted if t in by_topic] + [f"/shc/{leg}/state" for leg in legs]
            messages: dict[str, list[tuple[int, Any]]] = {topic: [] for topic in topics}
            connections = [c for topic in topics for c in by_topic[topic]]
            for connection, stamp, raw in reader.messages(connections=connections):
                messages[connection.topic].append((stamp, reader.deserialize(raw, connection.msgtype)))
    except ShcError:
        raise
    except Exception as error:  # rosbags' reader and deserialisation errors: the file is not a readable bag
        raise ShcError(f"{path}: not a readable {kind} ({type(error).__name__}: {error})") from None
    recorded = _arrays(path, kind, messages, legs, topics)
    recorded.not_replayed = not_replayed
    return recorded


def _listing(by_topic: dict[str, Any]) -> str:
    names = sorted(by_topic)
    return ", ".join(names[:8]) + (", …" if len(names) > 8 else "")


def _arrays(path: Path, kind: str, messages: dict[str, list[tuple[int, Any]]], legs: list[str],
            topics: list[str]) -> Recorded:
    joint_messages = messages[JOINTS]
    if not joint_messages:
        raise ShcError(f"{path}: {JOINTS} has no messages ({RECORD_HINT})")
    names = list(joint_messages[0][1].name)
    n = len(joint_messages)
    joints = np.full((n, len(names)), np.nan)
    for row, (_, message) in enumerate(joint_messages):
        position = np.asarray(message.position, dtype=float)
        if list(message.name) == names and len(position) == len(names):
            joints[row] = position
        else:  # another order (or a subset): place by name
            for name, value in zip(message.name, position, strict=False):
                if name in names:
                    joints[row, names.index(name)] = value
    stamps = np.array([stamp for stamp, _ in joint_messages], dtype=np.int64)
    header = np.array([_header_time(message) for _, message in joint_messages])
    t = header - header[0] if np.all(header > 0) else (stamps - stamps[0]) * 1e-9
    command = _inputs(messages[VELOCITY_INPUT], stamps, 3, _twist_xyw, 0.0)
    recorded = Recorded(source=path, kind=kind, t=t, joint_names=names, joints=joints, command=command,
                        topics=[topic if not LEG_STATE.match(topic) else "/shc/LEG/state" for topic in topics])
    recorded.topics = list(dict.fromkeys(recorded.topics))
    if messages.get(STATE_INPUT):
        recorded.robot_state = _inputs(messages[STATE_INPUT], stamps, 1, lambda m: [float(m.data)], np.nan)[:, 0]
    if VELOCITY in messages:
        recorded.velocity = _outputs(messages[VELOCITY], stamps, 3, _twist_xyw)
    if POSE in messages:
        recorded.pose = _outputs(messages[POSE], stamps, 6, lambda m: [m.linear.x, m.linear.y, m.linear.z,
                                                                       m.angular.x, m.angular.y, m.angular.z])
    if legs:
        per_leg = [_outputs(messages[f"/shc/{leg}/state"], stamps, 11, _leg_state) for leg in legs]
        stacked = np.stack(per_leg, axis=1)  # (N, L, 11)
        recorded.legs = legs
        recorded.tips = {stage: stacked[:, :, 3 * k:3 * k + 3] for k, stage in enumerate(("walker", "poser",
                                                                                            "model"))}
        recorded.progress = stacked[:, :, 9:11]
    return recorded


def _header_time(message: Any) -> float:
    stamp = message.header.stamp
    return float(stamp.sec) + float(stamp.nanosec) * 1e-9


def _twist_xyw(message: Any) -> list[float]:
    return [message.linear.x, message.linear.y, message.angular.z]


def _leg_state(message: Any) -> list[float]:
    out: list[float] = []
    for pose in (message.walker_tip_pose, message.poser_tip_pose, message.model_tip_pose):
        p = pose.pose.position
        out += [p.x, p.y, p.z]
    return [*out, message.stance_progress, message.swing_progress]


def _inputs(items: list[tuple[int, Any]], cycles: np.ndarray, width: int, values: Any, before: float) -> np.ndarray:
    """Per cycle, the last message received before the cycle's output (``before`` where there is none)."""
    out = np.full((len(cycles), width), before)
    if not items:
        return out
    times = np.array([stamp for stamp, _ in items], dtype=np.int64)
    table = np.array([values(message) for _, message in items], dtype=float)
    last = np.searchsorted(times, cycles, side="left") - 1
    seen = last >= 0
    out[seen] = table[last[seen]]
    return out


def _outputs(items: list[tuple[int, Any]], cycles: np.ndarray, width: int, values: Any) -> np.ndarray:
    """Per cycle, the topic's message of that cycle: by index when there are as many, else the nearest in time (NaN
    for a cycle without one)."""
    out = np.full((len(cycles), width), np.nan)
    if not items:
        return out
    table = np.array([values(message) for _, message in items], dtype=float)
    if len(items) == len(cycles):
        return table
    times = np.array([stamp for stamp, _ in items], dtype=np.int64)
    right = np.clip(np.searchsorted(cycles, times), 0, len(cycles) - 1)
    left = np.clip(right - 1, 0, len(cycles) - 1)
    nearest = np.where(np.abs(cycles[left] - times) <= np.abs(cycles[right] - times), left, right)
    out[nearest] = table
    return out
