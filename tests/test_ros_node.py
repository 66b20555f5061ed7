"""shc's pure-Python ROS 1 node against Debian's real ROS 1: master, rostopic, rosparam, rosnode, genmsg."""

from __future__ import annotations

import subprocess
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from shc_cli.ros.messages import MessageTypes
from shc_cli.ros.node import RosError, RosNode
from tests.ros_master import ros, ros_env

__all__ = ["ros_env"]

pytestmark = pytest.mark.slow  # Debian's roscore, rostopic and rosparam as subprocesses

GOLDEN_MSG = Path(__file__).parents[1] / "golden" / "openshc" / "msg"
GENMSG_MD5 = """
import sys, genmsg, genmsg.msg_loader, genmsg.gentools
ctx = genmsg.MsgContext.create_default()
search = {"syropod_highlevel_controller": [sys.argv[1]], "std_msgs": ["/usr/share/std_msgs/msg"],
          "geometry_msgs": ["/usr/share/geometry_msgs/msg"]}
spec = genmsg.msg_loader.load_msg_by_type(ctx, sys.argv[2], search)
genmsg.msg_loader.load_depends(ctx, spec, search)
print(genmsg.gentools.compute_md5(ctx, spec))
"""


@pytest.fixture(scope="module")
def types() -> MessageTypes:
    return MessageTypes()


def test_leg_state_md5sum_is_openshcs_as_genmsg_computes_it(types: MessageTypes, ros_env: dict[str, str]) -> None:
    """Debian's genmsg, run on OpenSHC's LegState.msg (golden/), gives the md5sum our node announces."""
    for name in ("syropod_highlevel_controller/LegState", "geometry_msgs/Twist"):
        theirs = subprocess.run(["/usr/bin/python3", "-c", GENMSG_MD5, str(GOLDEN_MSG), name], capture_output=True,
                                text=True, check=True).stdout.strip()
        assert types.definition(name)[1] == theirs
    assert types.definition("syropod_highlevel_controller/LegState")[1] == "dadda7ca412e345da1ddcca95ddf0ccc"


def test_rostopic_sees_and_decodes_our_publisher(types: MessageTypes, ros_env: dict[str, str]) -> None:
    with RosNode("/shc_test_pub", types, ros_env["ROS_MASTER_URI"]) as node:
        pub = node.advertise("/desired_joint_states", "sensor_msgs/JointState")
        assert ros(ros_env, "rostopic", "type", "/desired_joint_states").strip() == "sensor_msgs/JointState"
        assert "/shc_test_pub" in ros(ros_env, "rostopic", "info", "/desired_joint_states")
        assert "/shc_test_pub" in ros(ros_env, "rosnode", "list")
        echo = subprocess.Popen(["rostopic", "echo", "-n", "1", "/desired_joint_states/position"],
                                env=ros_env, stdout=subprocess.PIPE, text=True)
        message = types.message("sensor_msgs/JointState")
        header = types.message("std_msgs/Header")
        stamp = _time()
        for i in range(100):
            pub.publish(message(header=header(seq=i, stamp=stamp, frame_id=""),
                                name=["AR_coxa_joint", "AR_femur_joint"], position=np.array([0.25, -0.5]),
                                velocity=np.zeros(2), effort=np.zeros(2)))
            if echo.poll() is not None:
                break
            time.sleep(0.1)
        out = echo.communicate(timeout=10)[0]
        assert "[0.25, -0.5]" in out


def test_rostopic_pub_reaches_our_subscriber(types: MessageTypes, ros_env: dict[str, str]) -> None:
    got: list[object] = []
    arrived = threading.Event()

    def on_message(message: object) -> None:
        got.append(message)
        arrived.set()

    with RosNode("/shc_test_sub", types, ros_env["ROS_MASTER_URI"]) as node:
        node.subscribe("/syropod_remote/desired_velocity", "geometry_msgs/Twist", on_message)
        ros(ros_env, "rostopic", "pub", "-1", "/syropod_remote/desired_velocity", "geometry_msgs/Twist",
            "{linear: {x: 0.5, y: -0.25, z: 0}, angular: {x: 0, y: 0, z: 0.125}}")
        assert arrived.wait(10)
    twist = got[0]
    assert (twist.linear.x, twist.linear.y, twist.angular.z) == (0.5, -0.25, 0.125)  # type: ignore[attr-defined]


def test_parameters_set_with_rosparam_are_read(types: MessageTypes, ros_env: dict[str, str]) -> None:
    ros(ros_env, "rosparam", "set", "/syropod/parameters/time_delta", "0.01")
    ros(ros_env, "rosparam", "set", "/syropod/parameters/leg_id", "[AR, BR, CR, CL, BL, AL]")
    with RosNode("/shc_test_param", types, ros_env["ROS_MASTER_URI"]) as node:
        tree = node.get_param("/syropod/parameters")
        assert tree == {"time_delta": 0.01, "leg_id": ["AR", "BR", "CR", "CL", "BL", "AL"]}
        assert not node.has_param("/syropod/nothere")


def test_no_master_is_one_clear_error(types: MessageTypes) -> None:
    with pytest.raises(RosError, match="start roscore or set ROS_MASTER_URI"):
        RosNode("/shc_alone", types, "http://127.0.0.1:9/")


def _time() -> object:
    from rosbags.typesys.stores.ros1_noetic import builtin_interfaces__msg__Time as Time

    return Time(sec=1, nanosec=0)


def test_shc_ros_without_a_master_or_with_a_bad_backend_is_one_line(tmp_path: Path) -> None:  # no ros_env
    import os
    import sys

    shc = [sys.executable, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]
    env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:9/")
    for args, text in ((["bullet"], "start roscore or set ROS_MASTER_URI"),
                       (["bullet", "--backend", "ode"],
                        "--backend: 'ode' is not a backend (use none, mujoco, pybullet or bus)")):
        result = subprocess.run([*shc, "ros", *args, "--out", str(tmp_path / "run")], env=env, capture_output=True,
                                text=True, timeout=120)
        assert result.returncode == 2 and result.stderr.count("\n") == 1 and text in result.stderr, result.stderr
        assert not (tmp_path / "run").exists()
