"""A ``shc ros2`` session recorded as a ROS 2 bag (mcap, written by rosbags from an rclpy recorder:
``tests/ros2_bag_recorder.py``) replays through ``shc replay`` with the joints equal (≤ 1e-6 rad): the ROS 2 node
runs exactly the offline controller, as ``tests/test_ros_session.py`` shows for ``shc ros``'s rosbag. The robot is
Bullet with OpenSHC's IK step (``ik.limit_avoidance_cap = 0``), the one ``shc replay`` runs (docs/deviations.md):
with shc's default cap the node's IK differs from OpenSHC's wherever the legs near their limits (0.08 rad in this
walk's turn)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.test_ros2 import ros2_env
from tests.test_ros_session import ROOT, SHC

__all__ = ["ros2_env"]


@pytest.mark.slow
def test_a_ros2_bag_of_a_shc_ros2_session_replays_exactly(ros2_env: dict[str, str], tmp_path: Path) -> None:
    bag = tmp_path / "session"
    robot = tmp_path / "bullet.toml"
    text = (ROOT / "robots" / "bullet.toml").read_text()
    assert "\n[ik]\n" in text and "limit_avoidance_cap" not in text
    robot.write_text(text.replace("\n[ik]\n", "\n[ik]\nlimit_avoidance_cap = 0.0\n"))
    node = subprocess.Popen([*SHC, "ros2", str(robot), "--joint-states-timeout", "0", "--out", str(tmp_path / "run")],
                            cwd=ROOT, env=ros2_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        recorder = subprocess.run([sys.executable, str(ROOT / "tests" / "ros2_bag_recorder.py"), str(bag), "0.1"],
                                  env=ros2_env, cwd=ROOT, capture_output=True, text=True, timeout=300)
    finally:
        node.send_signal(2)
        _, err = node.communicate(timeout=120)
    assert recorder.returncode == 0 and recorder.stdout.startswith("done"), recorder.stdout + recorder.stderr[-2000:]
    assert node.returncode == 0, err[-2000:]
    replay = subprocess.run([*SHC, "replay", str(bag), "--robot", str(robot), "--json"], cwd=ROOT, env=ros2_env,
                            capture_output=True, text=True, timeout=300)
    assert replay.returncode == 0, replay.stderr
    report = json.loads(replay.stdout)
    assert report["cycles"] > 800
    assert report["worst"]["joints_rad"] <= 1e-6, report
