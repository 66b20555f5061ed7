"""Paths in ``shc ros``: a path file (``--path``), a ``nav_msgs/Path`` on ``<node>/path`` or a goal pose
``geometry_msgs/PoseStamped`` on ``/move_base_simple/goal`` (RViz's "2D Nav Goal").

:class:`RemotePath` wraps the remote's input (:class:`~shc_cli.ros.remote.RemoteInput`): the remote still sets the
system and robot states, posing, gait and parameters; while a path is being walked and the robot is RUNNING, the
path follower's velocity (:class:`~shc_cli.loop.path_input.PathInput`, steering by the leg odometry) replaces the
remote's desired velocity. A new path or goal replaces the one being walked; an empty ``nav_msgs/Path`` cancels it
(the robot stops). After the last waypoint the robot stops and the remote's velocity applies again.

Poses are in the odometry frame (``odom``: the robot's start pose), as ``shc ros`` publishes it; each pose's
orientation is the heading to turn to there, except an all-zero quaternion (no heading).
"""

from __future__ import annotations

import logging
import math
import threading
from dataclasses import replace
from typing import Any

from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.events import event
from shc_cli.loop.path_input import PathInput
from shc_cli.ros.node import RosNode
from shc_cli.ros.remote import RemoteInput
from shc_cli.ros.transport import Node
from shc_cli.spec.path import Path2D, Waypoint

log = logging.getLogger(__name__)

GOAL_TOPIC = RosNode.goal_topic
"""Where a goal pose arrives on ROS 1 (RViz's 2D Nav Goal publishes there)."""
PATH_TOPIC = "path"
"""A ``nav_msgs/Path`` arrives on ``<node name>/path`` (``/shc/path``)."""


def heading(orientation: Any) -> float | None:
    """The yaw of a ``geometry_msgs/Quaternion`` [rad]; ``None`` for the all-zero quaternion (no heading)."""
    x, y, z, w = (float(orientation.x), float(orientation.y), float(orientation.z), float(orientation.w))
    if x == y == z == w == 0.0:
        return None
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def waypoint(pose: Any) -> Waypoint:
    """A ``geometry_msgs/Pose`` as a waypoint."""
    return Waypoint(float(pose.position.x), float(pose.position.y), heading(pose.orientation))


class RemotePath:
    """The remote's input with paths to walk (module text).

    Args:
        remote: the remote's input.
        controller: the controller whose walker's limits bound the follower.
        path: a path to walk once the robot runs (``--path``), or ``None``.
    """

    def __init__(self, remote: RemoteInput, controller: Controller, path: Path2D | None = None) -> None:
        self.remote, self.controller = remote, controller
        self._lock = threading.Lock()
        self._pending: tuple[Waypoint, ...] | None = None
        self.follower = PathInput(path, controller) if path is not None else None
        self.followed: list[PathInput] = [] if self.follower is None else [self.follower]
        """Every path walked (or being walked), in order."""
        self._out: CycleOutput | None = None
        self._cycles = 0

    def subscribe(self, node: Node) -> None:
        """Subscribe ``<node>/path`` and the node's goal topic (ROS 1 :data:`GOAL_TOPIC`, ROS 2 ``/goal_pose``)."""
        node.subscribe(f"{node.name}/{PATH_TOPIC}", "nav_msgs/Path", self._on_path)
        node.subscribe(node.goal_topic, "geometry_msgs/PoseStamped", self._on_goal)

    def _on_path(self, message: Any) -> None:
        with self._lock:
            self._pending = tuple(waypoint(p.pose) for p in message.poses)

    def _on_goal(self, message: Any) -> None:
        with self._lock:
            self._pending = (waypoint(message.pose),)

    def observe(self, out: CycleOutput) -> None:
        """The loop's feedback, handed to the follower."""
        self._out, self._cycles = out, self._cycles + 1
        if self.follower is not None:
            self.follower.observe(out)

    def next(self) -> Command | None:
        command = self.remote.next()
        if command is None:
            return None
        with self._lock:
            pending, self._pending = self._pending, None
        if pending is not None:
            self.follower = PathInput(Path2D(pending), self.controller, cycle=self._cycles) if pending else None
            if self.follower is not None:
                self.followed.append(self.follower)
                if self._out is not None:
                    self.follower.observe(self._out)
            event(log, logging.INFO, "path", "path: %d waypoints to walk", len(pending))
        if self.follower is None or self.controller.state != RobotState.RUNNING:
            return command
        followed = self.follower.next()
        if followed is None:  # the last waypoint reached and the walker stopped
            self.follower = None
            return command
        return replace(command, velocity=followed.velocity)

    def summary(self) -> dict[str, object]:
        """The run summary's path fields: those of the one path walked, or (several) every waypoint without the
        start cycle (``shc analyze`` measures one path)."""
        if len(self.followed) == 1:
            return self.followed[0].summary()
        if not self.followed:
            return {}
        fields = self.followed[-1].summary()
        waypoints = [w for f in self.followed for w in f.summary()["waypoints"]]  # type: ignore[attr-defined]
        return {**fields, "path_start_cycle": None, "waypoints": waypoints}

    def close(self) -> None:
        self.remote.close()
