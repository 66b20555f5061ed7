"""``shc ros2``'s cycle outputs equal ``shc ros``'s for the same inputs: both nodes, each on its real ROS (Debian's
ROS 1 master with ``rostopic pub``, ROS 2 with an rclpy publisher), get the same inputs — a path file to walk and the
remote's OPERATIONAL and RUNNING — and their run directories' joints are the same, cycle for cycle, from the cycle the
first state request acts on."""

from __future__ import annotations

import csv
import json
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.ros_master import ros, ros_env
from tests.test_ros2 import ros2_env
from tests.test_ros_session import ROOT, SHC, _wait_for

__all__ = ["ros2_env", "ros_env"]

PATH = "x,y,yaw\n0.2,0.05,0.3\n"
SECONDS = "30"
_REMOTE2 = """
import time, rclpy
from std_msgs.msg import Int8
rclpy.init()
node = rclpy.create_node("remote_stand_in")
system = node.create_publisher(Int8, "/syropod_remote/system_state", 10)
state = node.create_publisher(Int8, "/syropod_remote/robot_state", 10)
while True:  # until killed: syropod_remote publishes at a rate
    system.publish(Int8(data=1)); state.publish(Int8(data=2))
    rclpy.spin_once(node, timeout_sec=0.1)
"""


def _events(run: Path) -> list[dict[str, object]]:
    return [json.loads(line) for line in (run / "events.log").read_text().splitlines()]


def _joints_from_first_state(run: Path) -> np.ndarray:
    """The joints of every cycle from the one that took the robot to PACKED (the first state request's effect: on
    ROS 1 the latched request is there at the first cycle, on ROS 2 it may come a cycle after OPERATIONAL)."""
    first = next(int(str(e["cycle"])) for e in _events(run) if e["event"] == "robot_state"
                 and str(e["message"]).endswith("PACKED"))
    with (run / "joints.csv").open(encoding="utf-8", newline="") as handle:
        rows = list(csv.reader(handle))
    return np.array([[float(v) for v in row[2:]] for row in rows[1:] if int(row[0]) >= first])


def _finish(node: subprocess.Popen[str]) -> None:
    node.send_signal(signal.SIGINT)
    _, err = node.communicate(timeout=120)
    assert node.returncode == 0, err[-2000:]


@pytest.mark.slow
def test_shc_ros2_and_shc_ros_give_the_same_cycles_for_the_same_inputs(ros_env: dict[str, str],
                                                                       ros2_env: dict[str, str],
                                                                       tmp_path: Path) -> None:
    path = tmp_path / "ahead.csv"
    path.write_text(PATH)
    runs = {}
    for command, env in (("ros", ros_env), ("ros2", ros2_env)):
        run = runs[command] = tmp_path / command
        node = subprocess.Popen([*SHC, command, "bullet", "--joint-states-timeout", "0", "--path", str(path),
                                 "--duration", SECONDS, "--out", str(run)], cwd=ROOT, env=env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        remotes = []
        try:
            if command == "ros":
                _wait_for(lambda e=env: "/desired_joint_states" in ros(e, "rostopic", "list").split(), 90, "shc ros")
                for topic, value in (("system_state", "1"), ("robot_state", "2")):  # latched, as syropod_remote
                    remotes.append(subprocess.Popen(["rostopic", "pub", "-l", f"/syropod_remote/{topic}",
                                                     "std_msgs/Int8", f"data: {value}"], env=env,
                                                    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                                    start_new_session=True))
            else:
                remotes.append(subprocess.Popen([sys.executable, "-c", _REMOTE2], env=env, cwd=ROOT,
                                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
            partial = run.with_name(run.name + ".partial") / "events.log"
            _wait_for(lambda p=partial: p.exists() and "waypoint 1" in p.read_text(), 150, f"shc {command}'s path")
        finally:
            for remote in remotes:
                remote.send_signal(signal.SIGINT)
                remote.kill()
                remote.wait(timeout=30)
            _finish(node)
    one, two = (_joints_from_first_state(runs[c]) for c in ("ros", "ros2"))
    n = min(len(one), len(two))
    assert n > 1000, (len(one), len(two))
    assert np.ptp(one[:n], axis=0).max() > 0.1  # the joints moved: it walked
    np.testing.assert_array_equal(one[:n], two[:n])
    for run in runs.values():
        assert any("waypoint 1 (0.200, 0.050) reached" in str(e["message"]) for e in _events(run))
