"""``shc ros --path`` in a real ROS 1 system (Debian's roscore and rostopic): the node walks its path file once the
remote asks for RUNNING, then a goal pose published on ``/move_base_simple/goal`` (as RViz's 2D Nav Goal does)
sends it back; both are walked by the leg odometry and reported in the summary."""

from __future__ import annotations

import json
import signal
import subprocess
import time
from pathlib import Path

import pytest

from tests.ros_master import ros, ros_env

from .test_ros_session import ROOT, SHC, _wait_for

__all__ = ["ros_env"]


def _events(run: Path) -> str:
    log = run.with_name(run.name + ".partial") / "events.log"
    return log.read_text() if log.exists() else ""


@pytest.mark.slow
def test_shc_ros_walks_its_path_then_a_goal_pose(ros_env: dict[str, str], tmp_path: Path) -> None:
    env = {**ros_env, "PYTHONUNBUFFERED": "1"}
    path = tmp_path / "ahead.csv"
    path.write_text("x,y,yaw\n0.2,0.0,0.4\n")
    run = tmp_path / "session"
    node = subprocess.Popen([*SHC, "ros", "bullet", "--path", str(path), "--out", str(run)], cwd=ROOT, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    latched = []
    try:
        _wait_for(lambda: "/desired_joint_states" in ros(env, "rostopic", "list").split(), 60,
                  "the node's outputs (after its 10 s wait for /joint_states)")
        assert "nav_msgs/Path" in ros(env, "rostopic", "info", "/shc/path")
        assert "geometry_msgs/PoseStamped" in ros(env, "rostopic", "info", "/move_base_simple/goal")
        for topic, value in (("system_state", "1"), ("robot_state", "2")):  # OPERATIONAL, RUNNING (latched)
            latched.append(subprocess.Popen(["rostopic", "pub", "-l", f"/syropod_remote/{topic}", "std_msgs/Int8",
                                             f"data: {value}"], env=env, stdout=subprocess.DEVNULL,
                                            stderr=subprocess.DEVNULL, start_new_session=True))
        _wait_for(lambda: "waypoint 1 (0.200, 0.000) reached" in _events(run), 120, "the path's waypoint")
        time.sleep(2.0)  # the walker stops
        ros(env, "rostopic", "pub", "-1", "/move_base_simple/goal", "geometry_msgs/PoseStamped",
            "{header: {frame_id: odom}, pose: {position: {x: 0.0, y: 0.1}, orientation: {w: 1.0}}}", timeout=60)
        _wait_for(lambda: "waypoint 1 (0.000, 0.100) reached" in _events(run), 120, "the goal")
        time.sleep(1.0)
    finally:
        for publisher in latched:
            publisher.send_signal(signal.SIGINT)
            publisher.wait(timeout=30)
        node.send_signal(signal.SIGINT)
        _, err = node.communicate(timeout=60)
    assert node.returncode == 0, err
    summary = json.loads((run / "summary.json").read_text())
    assert summary["path_file"] == "path.csv" and (run / "path.csv").exists()
    first, goal = summary["waypoints"]
    assert (first["x"], first["y"], first["yaw"]) == (0.2, 0.0, 0.4) and first["reached"]
    assert (goal["x"], goal["y"]) == (0.0, 0.1) and goal["yaw"] == pytest.approx(0.0) and goal["reached"]
    assert max(first["position_error_m"], goal["position_error_m"]) <= 0.02
