"""What ``shc ros``'s session needs of a node: ROS 1's (:class:`shc_cli.ros.node.RosNode`) or ROS 2's
(:class:`shc_cli.ros2.node.Ros2Node`, ``shc ros2``) — the same session, remote, outputs and loop on either."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from shc_cli.ros.messages import MessageTypes
    from shc_cli.ros.outputs import Sender
    from shc_cli.spec.robot import Robot


class ParameterSink(Protocol):
    """Where a parameter client's set lands: the remote's dynamic-parameter change
    (:meth:`shc_cli.ros.remote.RemoteInput.set_parameter`)."""

    def set_parameter(self, name: str, value: float) -> None:
        ...


class Node(Protocol):
    """A node: its name, where it is (``master_uri``: ROS 1's master, or ROS 2's domain), topics and parameters."""

    name: str
    master_uri: str
    types: MessageTypes
    goal_topic: str
    """Where a goal pose arrives (RViz's goal tool: ROS 1 ``/move_base_simple/goal``, ROS 2 ``/goal_pose``)."""
    program: str
    """The command the node runs in (``shc ros``, ``shc ros2``), for messages."""

    def advertise(self, topic: str, msgtype: str, latch: bool = False) -> Sender:
        ...

    def subscribe(self, topic: str, msgtype: str, callback: Callable[[object], None]) -> None:
        ...

    def serve_parameters(self, robot: Robot, remote: ParameterSink) -> None:
        """Offer the robot's dynamic parameters to parameter clients (ROS 1: the remote's adjustment only)."""
        ...

    def close(self) -> None:
        ...
