"""The sensor topics OpenSHC's node takes in (``/joint_states``, ``/imu/data``, ``/tip_states``): the start-up wait
for the measured joints and the controller's sensors (:mod:`shc_cli.ros.measured`), in process and under Debian's
real ROS 1 (``rostopic``, a rospy joint state publisher)."""

from __future__ import annotations

import csv
import logging
import signal
import subprocess
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.ros.measured import MeasuredBackend, MeasuredInputs
from shc_cli.ros.messages import MessageTypes
from shc_cli.spec.loading import load_robot
from tests.ros_master import ros, ros_env
from tests.test_ros_session import ROOT, SHC, _wait_for

__all__ = ["ros_env"]

ROBOT = load_robot("bullet").robot
NAMES = [f"{leg}_{joint}_joint" for leg, spec in ROBOT.legs.items() for joint in spec.joints]
T = MessageTypes().store.types


class _Node:
    """A node that only records its subscriptions (the callbacks are called by the test)."""

    def __init__(self) -> None:
        self.callbacks: dict[str, Callable[[object], None]] = {}
        self.types: dict[str, str] = {}

    def subscribe(self, topic: str, msgtype: str, callback: Callable[[object], None]) -> None:
        self.callbacks[topic], self.types[topic] = callback, msgtype


def _header() -> object:
    return T["std_msgs/msg/Header"](seq=0, stamp=T["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="")


def _joint_state(names: list[str], positions: list[float], efforts: list[float] | None = None) -> object:
    return T["sensor_msgs/msg/JointState"](header=_header(), name=names, position=np.array(positions),
                                            velocity=np.zeros(0), effort=np.array(efforts or []))


def _vector(x: float, y: float, z: float) -> object:
    return T["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def test_the_three_sensor_topics_are_subscribed_with_openshcs_types() -> None:
    node = _Node()
    MeasuredInputs(node, ROBOT)  # type: ignore[arg-type]
    assert node.types == {"/joint_states": "sensor_msgs/JointState", "/imu/data": "sensor_msgs/Imu",
                          "/tip_states": "syropod_highlevel_controller/TipState"}


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-1.5, 1.5), min_size=len(NAMES), max_size=len(NAMES)), st.randoms())
def test_measured_joints_are_matched_by_name_less_their_offsets(positions: list[float], order: object) -> None:
    node = _Node()
    measured = MeasuredInputs(node, ROBOT)  # type: ignore[arg-type]
    shuffled = list(zip(NAMES, positions, strict=True))
    order.shuffle(shuffled)  # type: ignore[attr-defined]
    node.callbacks["/joint_states"](_joint_state(["not_a_joint"] + [n for n, _ in shuffled],
                                                 [9.0] + [p for _, p in shuffled]))
    joints = measured.wait_for_joints(0.0)
    assert joints is not None
    for name, position in zip(NAMES, positions, strict=True):
        leg, joint = name.removesuffix("_joint").split("_", 1)
        k = list(ROBOT.legs[leg].joints).index(joint)
        assert joints[list(ROBOT.legs).index(leg), k] == pytest.approx(position - ROBOT.legs[leg].joints[joint].offset)


def test_without_every_joint_the_wait_ends_with_one_line_naming_them(caplog: pytest.LogCaptureFixture) -> None:
    node = _Node()
    measured = MeasuredInputs(node, ROBOT)  # type: ignore[arg-type]
    node.callbacks["/joint_states"](_joint_state(NAMES[1:], [0.2] * (len(NAMES) - 1)))
    started = time.monotonic()
    with caplog.at_level(logging.INFO, logger="shc_cli"):
        assert measured.wait_for_joints(0.3) is None
    assert 0.3 <= time.monotonic() - started < 2.0
    (warning,) = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert NAMES[0] in warning and "0 s" in warning and "\n" not in warning
    assert measured.sensors() is None  # incomplete joints are not a measurement


def test_nothing_received_is_no_sensors_so_the_controller_runs_as_before() -> None:
    backend = MeasuredBackend(MeasuredInputs(_Node(), ROBOT))  # type: ignore[arg-type]
    assert backend.sensors(True) is None


def test_imu_and_tip_states_reach_the_controllers_sensors() -> None:
    node = _Node()
    measured = MeasuredInputs(node, ROBOT)  # type: ignore[arg-type]
    half = np.sqrt(0.5)
    node.callbacks["/imu/data"](T["sensor_msgs/msg/Imu"](
        header=_header(), orientation=T["geometry_msgs/msg/Quaternion"](x=half, y=0.0, z=0.0, w=half),
        orientation_covariance=np.zeros(9), angular_velocity=_vector(0.1, -0.2, 0.3),
        angular_velocity_covariance=np.zeros(9), linear_acceleration=_vector(0.0, 0.0, 9.8),
        linear_acceleration_covariance=np.zeros(9)))
    wrench = T["geometry_msgs/msg/Wrench"](force=_vector(3.0, 0.0, 4.0), torque=_vector(0.0, 0.0, 0.0))
    node.callbacks["/tip_states"](T["syropod_highlevel_controller/msg/TipState"](
        header=_header(), name=["BL_tip", "nobody"], wrench=[wrench, wrench], step_plane=[]))
    node.callbacks["/joint_states"](_joint_state(NAMES, [0.0] * len(NAMES), [0.5] * len(NAMES)))
    sensors = MeasuredBackend(measured).sensors(True)
    assert sensors is not None
    assert sensors.orientation is not None and sensors.angular_rate is not None and sensors.foot_forces is not None
    np.testing.assert_allclose(sensors.orientation, [half, 0.0, 0.0, half])
    np.testing.assert_allclose(sensors.angular_rate, [0.1, -0.2, 0.3])
    expected = np.zeros(len(ROBOT.legs))
    expected[list(ROBOT.legs).index("BL")] = 5.0  # |(3, 0, 4)|: OpenSHC compares the force's magnitude
    np.testing.assert_allclose(sensors.foot_forces, expected)
    assert sensors.joint_efforts is not None and float(sensors.joint_efforts[0, 0]) == 0.5
    first = next(iter(ROBOT.legs.values())).joints.values()
    assert sensors.joints is not None  # every cycle's measured joints, less the offsets (shc's leg odometry reads them)
    np.testing.assert_allclose(sensors.joints[0, :len(first)], [-joint.offset for joint in first])


_PUBLISHER = """
import sys, rospy
from sensor_msgs.msg import JointState
from std_msgs.msg import Int8
names = sys.argv[1].split(",")
rospy.init_node("hardware_interface", disable_signals=True)
joints = rospy.Publisher("/joint_states", JointState, queue_size=10)
system = rospy.Publisher("/syropod_remote/system_state", Int8, queue_size=1, latch=True)
system.publish(Int8(1))
rate = rospy.Rate(50)
while not rospy.is_shutdown():
    joints.publish(JointState(name=names, position=[0.1 + 0.01 * k for k in range(len(names))]))
    rate.sleep()
"""


@pytest.mark.slow
def test_shc_ros_subscribes_the_sensor_topics_and_starts_from_the_measured_joints(ros_env: dict[str, str],
                                                                                   tmp_path: Path) -> None:
    """OpenSHC waits at start-up for /joint_states to give every joint and starts from them (less the offsets): a
    rospy hardware node publishing joints far from the robot file's standing pose, in another order."""
    run = tmp_path / "run"
    hardware = subprocess.Popen(["/usr/bin/python3", "-c", _PUBLISHER, ",".join(reversed(NAMES))], env=ros_env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    node = subprocess.Popen([*SHC, "ros", "bullet", "--duration", "60", "--out", str(run)], cwd=ROOT,
                            env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_for(lambda: "/desired_joint_states" in ros(ros_env, "rostopic", "list").split(), 90, "the outputs")
        for topic, msgtype in (("/joint_states", "sensor_msgs/JointState"), ("/imu/data", "sensor_msgs/Imu"),
                               ("/tip_states", "syropod_highlevel_controller/TipState")):
            info = ros(ros_env, "rostopic", "info", topic)
            assert msgtype in info and "/shc" in info.split("Subscribers:")[1], info
        log = run.with_name("run.partial") / "joints.csv"
        _wait_for(lambda: log.exists() and len(log.read_text().splitlines()) > 2, 60, "the node's first cycles")
    finally:
        hardware.send_signal(signal.SIGINT)
        hardware.kill()
        hardware.communicate()
        node.send_signal(signal.SIGINT)
        _, err = node.communicate(timeout=60)
    assert node.returncode == 0, err
    assert "waiting up to 10 s for /joint_states" in err and "no /joint_states" not in err, err
    first = next(csv.DictReader((run / "joints.csv").open()))
    for k, name in enumerate(reversed(NAMES)):
        leg, joint = name.removesuffix("_joint").split("_", 1)
        expected = 0.1 + 0.01 * k - ROBOT.legs[leg].joints[joint].offset
        assert float(first[name.removesuffix("_joint")]) == pytest.approx(expected, abs=1e-6)


@pytest.mark.parametrize("command", ["ros", "ros2"])
def test_a_negative_joint_states_timeout_is_one_line(command: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from tests.test_cli import run

    code, _, stderr = run([command, "bullet", "--joint-states-timeout", "-1", "--out", str(tmp_path / "run")], capsys,
                          monkeypatch)
    assert code == 2 and stderr.count("\n") == 1 and "--joint-states-timeout" in stderr, stderr
    assert not (tmp_path / "run").exists()
