"""A ROS 2 node (rclpy, from the ``ros2`` extra) as the transport of ``shc ros``'s session: ``shc ros2``.

The node is the same transport :class:`shc_cli.ros.node.RosNode` is for ROS 1 — :meth:`Ros2Node.advertise` and
:meth:`Ros2Node.subscribe` with the same message objects — so the session, the remote's state machine, the outputs
and the loop are ``shc ros``'s (:mod:`shc_cli.domain.ros_node`), one controller cycle per control period. Messages
are built as ``shc ros`` builds them and serialised to CDR by ``rosbags`` (ROS 2 Kilted's definitions, plus
OpenSHC's); rclpy sends those bytes, and hands subscriptions' bytes back (``raw``): no conversion through rclpy's
Python classes, whose type support (generated for OpenSHC's messages: :mod:`shc_cli.ros2.interfaces`) only
names the type and its hash on the wire.

QoS (what ROS 2 drivers expect): every publication reliable, volatile, keep-last 10 (``/tf`` 100, as tf2's
broadcaster); commands (``/syropod_remote/*``, ``<node>/path``, ``/goal_pose``) reliable, keep-last 10; sensor
topics (``/joint_states``, ``/imu/data``, ``/tip_states``) best effort, so both best-effort and reliable
publishers match. An executor thread serves the subscriptions and the parameter services.
"""

from __future__ import annotations

import contextlib
import functools
import importlib
import logging
import os
import struct
import threading
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from shc_cli.errors import ShcError
from shc_cli.ros.messages import MessageTypes

if TYPE_CHECKING:
    from shc_cli.ros.transport import ParameterSink
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

INSTALL = "python3 -m uv pip install --python .venv -e '.[ros2]'"
SENSOR_TOPICS = frozenset({"/joint_states", "/imu/data", "/tip_states"})
"""Subscribed best effort (a sensor driver's QoS); everything else reliable."""
_FLOAT64 = struct.Struct("<HHd")
"""A std_msgs/Float64 in CDR: the encapsulation (little-endian CDR, options 0) and the value."""
GOAL_TOPIC = "/goal_pose"
"""RViz 2's goal tool publishes there (geometry_msgs/PoseStamped)."""


class Ros2Error(ShcError):
    """rclpy is missing or the node could not start."""


def _rclpy() -> Any:
    try:
        import rclpy
    except ImportError:
        raise Ros2Error(f"shc ros2 needs ROS 2's rclpy: install the ros2 extra ({INSTALL})") from None
    return rclpy


@functools.cache
def store2() -> Any:
    """rosbags' ROS 2 Kilted type store with OpenSHC's messages (their definitions in ``shc_cli/ros2/msg``)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from shc_cli.ros2.interfaces import MSG_DIR

    store = get_typestore(Stores.ROS2_KILTED)
    extra: dict[str, Any] = {}
    for path in sorted((MSG_DIR / "syropod_highlevel_controller").glob("*.msg")):
        extra.update(get_types_from_msg(path.read_text(), f"syropod_highlevel_controller/msg/{path.stem}"))
    store.register(extra)
    return store


class Publisher2:
    """One topic's rclpy publisher, sending messages serialised by rosbags."""

    def __init__(self, publisher: Any, serialize: Callable[[object], bytes]) -> None:
        self._publisher, self._serialize = publisher, serialize

    @property
    def topic(self) -> str:
        return str(self._publisher.topic_name)

    @property
    def subscriber_count(self) -> int:
        return int(self._publisher.get_subscription_count())

    def publish(self, message: object) -> None:
        self._publisher.publish(self._serialize(message))


class Ros2Node:
    """The ROS 2 node ``name`` (``/ns/name`` sets the namespace) on ``$ROS_DOMAIN_ID``.

    Args:
        name: the node's name, e.g. ``/shc``.
        params_file: a ROS 2 parameter file (``shc: ros__parameters: ...``) for the declared parameters.

    Raises:
        Ros2Error: rclpy is not installed (one line: how to install it).
    """

    goal_topic = GOAL_TOPIC
    program = "shc ros2"

    def __init__(self, name: str, params_file: Path | None = None) -> None:
        rclpy = _rclpy()
        from rclpy.executors import SingleThreadedExecutor

        from shc_cli.ros2.interfaces import load

        load()
        self.types = MessageTypes()  # messages are built as shc ros builds them (ROS 1 classes, same fields)
        self.store = store2()
        namespace, _, base = ("/" + name.strip("/")).rpartition("/")
        args = ["--ros-args", "--params-file", str(params_file)] if params_file is not None else None
        self._context = rclpy.Context()
        rclpy.init(args=args, context=self._context)
        self._node = rclpy.create_node(base or "shc", namespace=namespace or "/", context=self._context)
        self.name: str = self._node.get_fully_qualified_name()
        domain = os.environ.get("ROS_DOMAIN_ID", "0")
        self.master_uri = f"ROS 2 domain {domain}"
        self.parameters: Any = None
        self._executor = SingleThreadedExecutor(context=self._context)
        self._executor.add_node(self._node)
        self._thread = threading.Thread(target=self._spin, name="ros2-executor", daemon=True)
        self._thread.start()
        self._closed = False

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException

        with contextlib.suppress(ExternalShutdownException):
            self._executor.spin()

    @property
    def node(self) -> Any:
        """The rclpy node."""
        return self._node

    def message_class(self, msgtype: str) -> Any:
        """rclpy's class of ``pkg/Msg`` or ``pkg/msg/Msg``."""
        parts = msgtype.split("/")
        return getattr(importlib.import_module(f"{parts[0]}.msg"), parts[-1])

    def advertise(self, topic: str, msgtype: str, latch: bool = False) -> Publisher2:
        """A reliable publisher of ``topic`` (transient local when ``latch``, as a latched ROS 1 topic)."""
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        name = MessageTypes.store_name(msgtype)
        qos = QoSProfile(depth=100 if topic == "/tf" else 10, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL if latch else DurabilityPolicy.VOLATILE)
        publisher = self._node.create_publisher(self.message_class(msgtype), topic, qos)
        if name == "std_msgs/msg/Float64":  # the per-joint commands, most of a cycle's messages: CDR by hand
            return Publisher2(publisher, lambda message: _FLOAT64.pack(0x0100, 0, message.data))  # type: ignore[attr-defined]
        serialize = self.store.serialize_cdr
        return Publisher2(publisher, lambda message: bytes(serialize(message, name)))

    def subscribe(self, topic: str, msgtype: str, callback: Callable[[object], None]) -> None:
        """Subscribe ``topic``: ``callback(message)`` with each message (a rosbags message of the ROS 2 type)."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy

        name = MessageTypes.store_name(msgtype)
        reliability = ReliabilityPolicy.BEST_EFFORT if topic in SENSOR_TOPICS else ReliabilityPolicy.RELIABLE
        deserialize = self.store.deserialize_cdr

        def received(raw: bytes) -> None:
            try:
                message = deserialize(raw, name)
            except Exception as error:  # a malformed message must not end the executor
                log.warning("%s: unreadable %s (%s)", topic, name, error)
                return
            callback(message)

        self._node.create_subscription(self.message_class(msgtype), topic, received,
                                       QoSProfile(depth=10, reliability=reliability), raw=True)

    def serve_parameters(self, robot: Robot, remote: ParameterSink) -> None:
        """Declare OpenSHC's dynamic parameters as ROS 2 parameters that change the running controller."""
        from shc_cli.ros2.parameters import Parameters

        self.parameters = Parameters(self._node, robot, remote)

    def close(self) -> None:
        """Stop the executor and the node (idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._executor.shutdown(timeout_sec=1.0)
        self._node.destroy_node()
        if self._context.ok():
            self._context.shutdown()
        self._thread.join(timeout=2.0)
