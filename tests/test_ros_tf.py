"""``/tf`` of ``shc ros``, ``shc ros2`` and ``--live``: OpenSHC's ``odom_ideal → base_link`` (the ideal odometry —
integrated commanded velocity — composed with the body pose) under the leg odometry's ``odom``, one parent per
frame; during a walk the robot moves through both frames."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from shc_cli.api import load_gait, load_robot
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.ros.messages import MessageTypes
from shc_cli.ros.outputs import NodeOutputs, ideal_odometry

from .test_live import _live_run


class _Sink:
    def __init__(self) -> None:
        self.messages: list[Any] = []

    @property
    def subscriber_count(self) -> int:
        return 1

    def publish(self, message: object) -> None:
        self.messages.append(message)


class _Transport:
    def __init__(self) -> None:
        self.types = MessageTypes()
        self.topics: dict[str, _Sink] = {}

    def advertise(self, topic: str, msgtype: str, latch: bool = False) -> _Sink:
        return self.topics.setdefault(topic, _Sink())


def _matrix(t: Any) -> np.ndarray:
    q, p = t.transform.rotation, t.transform.translation
    m = np.eye(4)
    m[:3, :3] = Rotation.from_quat([q.x, q.y, q.z, q.w]).as_matrix()
    m[:3, 3] = [p.x, p.y, p.z]
    return m


def _pose(x: float, y: float, z: float, roll: float, pitch: float, yaw: float) -> np.ndarray:
    m = np.eye(4)
    m[:3, :3] = Rotation.from_euler("ZYX", [yaw, pitch, roll]).as_matrix()
    m[:3, 3] = [x, y, z]
    return m


def _walked(cycles: int) -> tuple[Controller, list[Any], list[Any]]:
    robot = load_robot("bullet")
    controller = Controller(robot, load_gait("tripod"))
    transport = _Transport()
    outputs = NodeOutputs(transport, robot, individual=False, ideal=ideal_odometry(controller))
    outs = []
    for k in range(cycles):
        out = controller.step(Command(velocity=(0.6, 0.2, 0.3) if k > 400 else (0.0, 0.0, 0.0),
                                      state_request=RobotState.RUNNING))
        outputs(k, Command(), out, None)
        outs.append(out)
    return controller, outs, transport.topics["/tf"].messages


def test_every_frame_has_one_parent_and_odom_ideal_is_openshcs_composition() -> None:
    controller, outs, tfs = _walked(900)
    assert controller.walker is not None and controller.state == RobotState.RUNNING
    transforms = tfs[-1].transforms
    children = [t.child_frame_id for t in transforms]
    assert len(children) == len(set(children))  # no frame with two parents
    parents = {t.child_frame_id: t.header.frame_id for t in transforms}
    assert parents["odom_ideal"] == "odom" and parents["base_link"] == "odom_ideal"
    assert "odom" not in parents  # the root
    # odom_ideal → base_link = ideal odometry (walk plane: position, yaw) ∘ the body's pose in the walk plane
    out = outs[-1]
    walker = controller.walker
    px, py, pz = walker.odometry_position
    ideal = _pose(px, py, pz, 0.0, 0.0, walker.odometry_yaw)
    expected = ideal @ _pose(*out.pose)
    np.testing.assert_allclose(_matrix(transforms[1]), expected, atol=1e-9)
    # odom → base_link (through odom_ideal) = the leg odometry's planar pose ∘ the same body pose
    ox, oy, oyaw = out.odometry
    np.testing.assert_allclose(_matrix(transforms[0]) @ _matrix(transforms[1]),
                               _pose(ox, oy, 0.0, 0.0, 0.0, oyaw) @ _pose(*out.pose), atol=1e-9)


def test_the_tf_moves_the_robot_through_the_world_during_a_walk() -> None:
    controller, outs, tfs = _walked(900)
    start = _matrix(tfs[400].transforms[1])[:3, 3]
    end = _matrix(tfs[-1].transforms[1])[:3, 3]
    assert np.hypot(*(end - start)[:2]) > 0.1  # not on the spot: the ideal odometry walked
    legs = (_matrix(tfs[-1].transforms[0]) @ _matrix(tfs[-1].transforms[1]))[:3, 3]
    assert np.hypot(*legs[:2]) > 0.1  # and so did the leg odometry
    walker = controller.walker
    assert walker is not None
    # the ideal odometry is the integrated commanded velocity: its heading is the integral of the yaw rates
    commanded = sum(out.velocity[2] for out in outs if out.robot_state == RobotState.RUNNING) * 0.01
    assert math.isclose(walker.odometry_yaw, commanded, rel_tol=0.05, abs_tol=1e-3)


@pytest.mark.slow
def test_a_live_walk_streams_tf_that_moves_through_odom(tmp_path: Path) -> None:
    # a live stream builds its messages while /desired_joint_states has a client
    messages = _live_run(["plan", "--duration", "4", "--realtime", "--no-plots", "--velocity", "0.5,0,0", "--out",
                          str(tmp_path / "plan")], ["/tf", "/desired_joint_states"])
    tfs = [m["message"]["transforms"] for m in messages if m["topic"] == "/tf"]
    assert len(tfs) > 100
    first, last = ({t["child_frame_id"]: t for t in tf} for tf in (tfs[0], tfs[-1]))
    assert first["base_link"]["header"]["frame_id"] == "odom_ideal"
    assert last["odom_ideal"]["header"]["frame_id"] == "odom"
    x0, x1 = (float(tf["base_link"]["transform"]["translation"]["x"]) for tf in (first, last))
    assert x1 - x0 > 0.1, (x0, x1)
