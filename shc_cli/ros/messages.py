"""The ROS 1 message types a node can speak: rosbags' Noetic store, plus OpenSHC's and tf2's messages.

Type names are written as ROS 1 writes them (``sensor_msgs/JointState``) on the wire and as rosbags does
(``sensor_msgs/msg/JointState``) in Python; both are accepted. Definitions and md5sums are generated from the
message definitions the way ``genmsg`` does, so a node's md5sums equal those of the original packages.
"""

from __future__ import annotations

from functools import cache
from typing import Any

OPENSHC_MESSAGES = {
    "syropod_highlevel_controller/msg/TipState": """std_msgs/Header header
string[] name
geometry_msgs/Wrench[] wrench
geometry_msgs/Vector3[] step_plane
""",
    "syropod_highlevel_controller/msg/TargetTipPose": """std_msgs/Header header
string[] name
geometry_msgs/PoseStamped[] target
geometry_msgs/PoseStamped[] stance
float64[] swing_clearance
""",
}
"""OpenSHC's other messages (its ``msg/`` folder), field for field; LegState is the bag writer's."""


class MessageTypes:
    """Serialise, deserialise and describe ROS 1 messages (rosbags' Noetic type store with shc's extras)."""

    def __init__(self) -> None:
        from rosbags.typesys import get_types_from_msg

        from shc_cli.interop.bag import typestore_for

        self.store = typestore_for("ros1")
        extra: dict[str, Any] = {}
        for name, text in OPENSHC_MESSAGES.items():
            extra.update(get_types_from_msg(text, name))
        self.store.register(extra)

    @staticmethod
    def ros_name(msgtype: str) -> str:
        """``pkg/msg/Msg`` or ``pkg/Msg`` → ``pkg/Msg`` (the wire's and the master's name)."""
        parts = msgtype.split("/")
        return f"{parts[0]}/{parts[-1]}"

    @staticmethod
    def store_name(msgtype: str) -> str:
        """``pkg/Msg`` or ``pkg/msg/Msg`` → ``pkg/msg/Msg`` (rosbags' name)."""
        parts = msgtype.split("/")
        return f"{parts[0]}/msg/{parts[-1]}"

    def definition(self, msgtype: str) -> tuple[str, str]:
        """The full message definition (with its dependencies, as ``rosbag`` stores it) and its md5sum."""
        return _definition(self, self.store_name(msgtype))

    def serialize(self, message: object, msgtype: str) -> bytes:
        """ROS 1 bytes of a rosbags message."""
        return bytes(self.store.serialize_ros1(message, self.store_name(msgtype)))

    def deserialize(self, raw: bytes, msgtype: str) -> object:
        """A rosbags message from ROS 1 bytes."""
        return self.store.deserialize_ros1(raw, self.store_name(msgtype))

    def message(self, msgtype: str) -> Any:
        """The rosbags dataclass of a type (to build messages: ``types.message("std_msgs/Int8")(data=1)``)."""
        return self.store.types[self.store_name(msgtype)]


@cache
def _definition(types: MessageTypes, name: str) -> tuple[str, str]:
    text, md5 = types.store.generate_msgdef(name)
    return text, md5
