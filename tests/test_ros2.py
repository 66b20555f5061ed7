"""``shc ros2`` against real ROS 2 clients: a plain rclpy driver node in another process (tests/ros2_driver.py)
and a raw DDS reader of another vendor (cyclonedds, tests/ros2_dds_reader.py).

Every process runs with loopback-only discovery (``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``) on a random
``ROS_DOMAIN_ID``: nothing leaves the machine, and parallel tests do not meet. The Fast DDS shared-memory files a
test's processes leave in /dev/shm are removed after it. Without the ros2 extra the tests skip, except under
``CI`` (.ci/run installs it), where that is a failure.
"""

from __future__ import annotations

import contextlib
import csv
import importlib.util
import itertools
import json
import os
import random
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shc_cli.api import load_robot

ROOT = Path(__file__).resolve().parent.parent
SHC = [sys.executable, "-m", "shc_cli.cli"]
LEG_STATE_HASH = "RIHS01_82c8f90259aed81180e0982e5d458691b25f1ec11bba4e151f9ff3fce768c079"
"""OpenSHC's LegState under ROS 2 (the issue's measurement with colcon-built messages: RIHS01_82c8f902…c079; in
full as rosbags computes it from the .msg file, independently of rosidl)."""
DYNAMIC = {"step_frequency", "swing_height", "swing_width", "step_depth", "stance_span_modifier", "virtual_mass",
           "virtual_stiffness", "virtual_damping_ratio", "force_gain"}
NO_TYPE_PROPAGATION = ROOT / "tests" / "data" / "fastdds_no_type_propagation.xml"


@pytest.fixture
def ros2_env(tmp_path: Path) -> Iterator[dict[str, str]]:
    """The environment of one test's ROS 2 processes (a fresh random domain); its /dev/shm files removed after."""
    if importlib.util.find_spec("rclpy") is None or importlib.util.find_spec("cyclonedds") is None:
        if os.environ.get("CI"):
            pytest.fail("rclpy or cyclonedds missing: .ci/run must install the ros2 extra and cyclonedds")
        pytest.skip("the ros2 extra is not installed (python3 -m uv pip install --python .venv -e '.[ros2]')")
    shm = Path("/dev/shm")
    before = _fastdds_files(shm)
    with _free_domain() as domain:
        env = dict(os.environ, ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(domain),
                   ROS_LOG_DIR=str(tmp_path / "ros_log"), ROS_HOME=str(tmp_path / "ros_home"), PYTHONPATH=str(ROOT))
        env.pop("ROS_LOCALHOST_ONLY", None)
        try:
            yield env
        finally:
            for leftover in _fastdds_files(shm) - before:
                leftover.unlink(missing_ok=True)


@contextlib.contextmanager
def _free_domain() -> Iterator[int]:
    """A random ROS_DOMAIN_ID (1..100) no other test on this machine holds now (a lock file per domain: parallel
    test workers, or another checkout's CI, never share one — each runs a node named /shc)."""
    import fcntl
    import tempfile

    for domain in random.sample(range(1, 101), 100):
        lock = open(Path(tempfile.gettempdir()) / f"shc-ros2-domain-{domain}.lock", "w")  # noqa: SIM115
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            lock.close()
            continue
        try:
            yield domain
        finally:
            lock.close()
        return
    pytest.fail("every ROS_DOMAIN_ID 1..100 is held by another test")


def _fastdds_files(shm: Path) -> set[Path]:
    """Fast DDS's shared-memory segments, port files and their semaphores."""
    return {*shm.glob("fastdds_*"), *shm.glob("sem.fastdds_*")} if shm.is_dir() else set()


def _node(env: dict[str, str], seconds: float, out: Path, *extra: str) -> subprocess.Popen[str]:
    return subprocess.Popen([*SHC, "ros2", "bullet", "--duration", str(seconds), "--out", str(out), *extra],
                            env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _finish(node: subprocess.Popen[str]) -> tuple[str, str]:
    try:
        stdout, stderr = node.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        node.kill()
        stdout, stderr = node.communicate()
    assert node.returncode == 0, stderr[-2000:]
    return stdout, stderr


@pytest.mark.slow
@pytest.mark.serial  # holds the control rate against the wall clock
def test_an_rclpy_driver_walks_shc_ros2_reads_its_topics_and_sets_its_parameters(ros2_env: dict[str, str],
                                                                                   tmp_path: Path) -> None:
    run = tmp_path / "run"
    params = tmp_path / "params.yaml"  # a start value from a ROS 2 parameter file
    params.write_text("/**:\n  ros__parameters:\n    virtual_stiffness: 35.0\n")
    node = _node(ros2_env, 45, run, "--params-file", str(params))
    seen = tmp_path / "driver.json"
    driver = subprocess.run([sys.executable, str(ROOT / "tests" / "ros2_driver.py"), "24", str(seen)],
                            env=ros2_env, cwd=ROOT, capture_output=True, text=True, timeout=240)
    if driver.returncode != 0:
        node.kill()
    assert driver.returncode == 0, driver.stderr[-2000:]
    node.send_signal(2)  # Ctrl-C: the node finishes its run directory and exits 0
    stdout, stderr = _finish(node)
    assert "shc ros2: bullet / tripod as node /shc on ROS 2 domain" in stderr
    assert "stopped by" in stdout
    r = json.loads(seen.read_text())
    robot = load_robot("bullet")

    # parameters: listed, described with their range, got, and set (an out-of-range set refused with the reason)
    assert DYNAMIC | {"robot", "gait", "control_rate"} <= set(r["parameters"])
    spec = robot.walker.swing_height
    assert r["swing_range"] == [spec.min, spec.max]
    assert r["swing_height"] == spec.default and r["step_frequency"] == robot.walker.step_frequency.default
    assert r["virtual_stiffness"] == 35.0 != robot.admittance.virtual_stiffness.default
    assert not r["out_of_range"]["successful"] and "out of range" in r["out_of_range"]["reason"]
    assert r["in_range"]["successful"], r["in_range"]
    # ... and the accepted set changed the running controller: the swing apex is the new swing height
    events = [json.loads(line) for line in (run / "events.log").read_text().splitlines()]
    (change,) = [e for e in events if e["event"] == "parameter"]
    rows = list(csv.DictReader((run / "tips.csv").open()))
    before = max(float(row["AR_walker_z"]) for row in rows if int(row["cycle"]) < change["cycle"])
    after = max(float(row["AR_walker_z"]) for row in rows[-300:])  # the last three steps
    assert before == pytest.approx(spec.default, abs=0.002)
    assert after == pytest.approx(r["in_range"]["value"], abs=0.002)

    # the remote's state machine started and the commanded walk walked
    summary = json.loads((run / "summary.json").read_text())
    assert summary["node"] == "/shc" and summary["backend"] == "none"
    assert summary["odometry_distance_m"] > 0.5
    states = [e["message"] for e in events if e["event"] == "robot_state"]
    assert "robot state: READY → RUNNING" in states

    # OpenSHC's LegState read by a subscriber that has its definition: the type and hash advertised
    assert r["leg_state_type"] == ["syropod_highlevel_controller/msg/LegState"]
    assert r["leg_state_hash"] == [LEG_STATE_HASH]
    assert r["leg_names"] == ["AR"] and r["leg_states"] > 1000

    # /desired_joint_states, reliable, at the control rate: header stamps and receive times, no long gap
    stamps, received = r["stamps"], r["received"]
    assert len(stamps) > 1500
    period = robot.time_delta
    for times in (stamps, received):
        rate = (len(times) - 1) / (times[-1] - times[0])
        assert rate == pytest.approx(1.0 / period, rel=0.02)
    # no freeze once the loop runs (its first cycle after OPERATIONAL takes 0.2–0.4 s, then the clock catches up).
    # The issue's target, no interval over three periods, is not met yet: stalls of 0.07–0.23 s a few times in 24 s
    # were measured here (the ROS 1 node has one of 0.11 s in 30 s), so this bound only catches a freeze.
    gaps = [b - a for a, b in itertools.pairwise(stamps[100:])]
    assert max(gaps) < 0.5, max(gaps)


@pytest.mark.slow
def test_a_raw_dds_reader_of_another_vendor_reads_desired_joint_states_from_the_wire(ros2_env: dict[str, str],
                                                                                     tmp_path: Path) -> None:
    """cyclonedds reads ``rt/desired_joint_states`` as ``sensor_msgs::msg::dds_::JointState_``. Cyclone 11 cannot
    parse Fast DDS 3.2's XTypes type objects of sequence types ("invalid type object") and then never matches, so
    the node runs with Fast DDS's type propagation off (tests/data/fastdds_no_type_propagation.xml, a standard Fast
    DDS profile): the types then match by name, as between DDS vendors before XTypes."""
    env = dict(ros2_env, FASTDDS_DEFAULT_PROFILES_FILE=str(NO_TYPE_PROPAGATION))
    node = _node(env, 150, tmp_path / "run")
    wire = tmp_path / "wire.json"
    remote = subprocess.Popen([sys.executable, "-c", _OPERATIONAL], env=env, cwd=ROOT, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True)
    reader = subprocess.run([sys.executable, str(ROOT / "tests" / "ros2_dds_reader.py"), "400", "120", str(wire)],
                            env=env, cwd=ROOT, capture_output=True, text=True, timeout=180)
    remote.kill()
    remote.communicate()
    assert reader.returncode == 0, reader.stderr[-2000:]
    node.send_signal(2)
    _finish(node)
    w = json.loads(wire.read_text())
    robot = load_robot("bullet")
    names = [f"{leg}_{joint}_joint" for leg, spec in robot.legs.items() for joint in spec.joints]
    assert sorted(w["names"]) == sorted(names)
    assert len(w["positions"]) == len(names) and w["count"] == 400
    # the joints the node commanded, as its own joints.csv recorded them (the robot stays packed: no state request)
    joints = list(csv.DictReader((tmp_path / "run" / "joints.csv").open()))
    for name, position in zip(w["names"], w["positions"], strict=True):
        assert position == pytest.approx(float(joints[-1][name.removesuffix("_joint")]), abs=1e-6)


_OPERATIONAL = """
import time, rclpy
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import Int8
rclpy.init()
node = rclpy.create_node("operational")
qos = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
pub = node.create_publisher(Int8, "/syropod_remote/system_state", qos)
while True:  # at a rate, as syropod_remote (the node's command subscriptions are volatile), until killed
    pub.publish(Int8(data=1))
    rclpy.spin_once(node, timeout_sec=0.1)
"""


_GOAL = """
import time, rclpy
from geometry_msgs.msg import PoseStamped
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Int8
rclpy.init()
node = rclpy.create_node("rviz2_goal_tool")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
system = node.create_publisher(Int8, "/syropod_remote/system_state", qos)
state = node.create_publisher(Int8, "/syropod_remote/robot_state", qos)
goal = node.create_publisher(PoseStamped, "/goal_pose", qos)
start, sent = time.monotonic(), False
while time.monotonic() - start < 40:
    system.publish(Int8(data=1))
    state.publish(Int8(data=2))
    if not sent and goal.get_subscription_count() and time.monotonic() - start > 18:
        message = PoseStamped()
        message.header.frame_id = "odom"
        message.pose.position.x = 0.3
        goal.publish(message)
        sent = True
    rclpy.spin_once(node, timeout_sec=0.1)
assert sent
"""


@pytest.mark.slow
def test_a_goal_from_rviz2s_goal_tool_is_walked_to(ros2_env: dict[str, str], tmp_path: Path) -> None:
    """RViz 2's goal tool publishes geometry_msgs/msg/PoseStamped on /goal_pose: the node walks there (the path
    follower of ``shc ros``'s /move_base_simple/goal)."""
    node = _node(ros2_env, 55, tmp_path / "run")
    tool = subprocess.run([sys.executable, "-c", _GOAL], env=ros2_env, cwd=ROOT, capture_output=True, text=True,
                          timeout=120)
    assert tool.returncode == 0, tool.stderr[-2000:]
    node.send_signal(2)
    _finish(node)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    (waypoint,) = summary["waypoints"]
    assert (waypoint["x"], waypoint["y"]) == (0.3, 0.0) and waypoint["reached"]
    assert summary["odometry_pose"][0] == pytest.approx(0.3, abs=0.03)


_WALK = """
import sys, time, rclpy
from geometry_msgs.msg import Twist
from rclpy.qos import QoSProfile, ReliabilityPolicy
from std_msgs.msg import Int8
rclpy.init()
node = rclpy.create_node("remote")
qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
system = node.create_publisher(Int8, "/syropod_remote/system_state", qos)
state = node.create_publisher(Int8, "/syropod_remote/robot_state", qos)
velocity = node.create_publisher(Twist, "/syropod_remote/desired_velocity", qos)
walk = Twist()
walk.linear.x = 1.0
start = time.monotonic()
while time.monotonic() - start < float(sys.argv[1]):
    system.publish(Int8(data=1))
    state.publish(Int8(data=2))
    velocity.publish(walk)
    rclpy.spin_once(node, timeout_sec=0.1)
"""


@pytest.mark.slow
@pytest.mark.serial  # beside another test worker an emulated bus starved of CPU reads as a silent servo
def test_shc_ros2_drives_the_servos_of_an_emulated_bus_and_shuts_down_on_ctrl_c(ros2_env: dict[str, str],
                                                                                 tmp_path: Path) -> None:
    """``--backend bus`` as ``shc ros``'s: no torque before OPERATIONAL, the servos walk, Ctrl-C shuts the robot down
    to PACKED and releases the torque."""
    import time

    from shc_cli.hardware.emulator_process import EmulatorProcess
    from shc_cli.record.runread import read_run

    ids = sorted(s.id for s in load_robot("bullet").hardware.servos.values())
    run = tmp_path / "run"
    with EmulatorProcess({i: "MX-106" for i in ids}) as bus:
        node = subprocess.Popen([*SHC, "ros2", "bullet", "--backend", "bus", "--port", bus.port, "--out", str(run)],
                                env={**ros2_env, "PYTHONUNBUFFERED": "1"}, cwd=ROOT, stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        try:
            time.sleep(3.0)
            assert {int(bus.torque_on(i)) for i in ids} == {0}  # not OPERATIONAL yet: the servos are left alone
            remote = subprocess.run([sys.executable, "-c", _WALK, "20"], env=ros2_env, cwd=ROOT,
                                    capture_output=True, text=True, timeout=120)
            assert remote.returncode == 0, remote.stderr[-2000:]
            assert {int(bus.torque_on(i)) for i in ids} == {1}
        finally:
            node.send_signal(2)
            _finish(node)
        assert {int(bus.torque_on(i)) for i in ids} == {0}  # released after the shut-down
        assert all(abs(bus.position(i) - 2048) <= 3 for i in ids)  # back where it started (0 rad)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["backend"] == "bus" and summary["fault"] is None and summary["final_state"] == "PACKED"
    log = read_run(run)
    assert (log.walk_state == "MOVING").any()


_JOINT_STATES = """
import time, rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
from sensor_msgs.msg import JointState
from std_msgs.msg import Int8
import sys
names = sys.argv[1].split(",")
rclpy.init()
node = rclpy.create_node("hardware_interface")
joints = node.create_publisher(JointState, "/joint_states", qos_profile_sensor_data)
system = node.create_publisher(Int8, "/syropod_remote/system_state", QoSProfile(depth=10,
                               reliability=ReliabilityPolicy.RELIABLE))
while True:  # until killed
    message = JointState(name=names, position=[0.1 + 0.01 * k for k in range(len(names))])
    joints.publish(message)
    system.publish(Int8(data=1))
    rclpy.spin_once(node, timeout_sec=0.02)
"""


@pytest.mark.slow
def test_shc_ros2_starts_from_the_joints_a_hardware_node_measures(ros2_env: dict[str, str], tmp_path: Path) -> None:
    """OpenSHC waits at start-up for /joint_states to give every joint and starts from them (less the offsets):
    a hardware node publishing best effort, as sensor drivers do, with joints far from the defaults (0)."""
    robot = load_robot("bullet")
    names = [f"{leg}_{joint}_joint" for leg, spec in robot.legs.items() for joint in spec.joints]
    import time

    node = _node(ros2_env, 150, tmp_path / "run")
    hardware = subprocess.Popen([sys.executable, "-c", _JOINT_STATES, ",".join(reversed(names))], env=ros2_env,
                                cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    log = tmp_path / "run.partial" / "joints.csv"
    deadline = time.monotonic() + 120
    while not (log.exists() and len(log.read_text().splitlines()) > 2) and time.monotonic() < deadline:
        assert node.poll() is None and hardware.poll() is None
        time.sleep(0.5)
    hardware.kill()
    hardware.communicate()
    node.send_signal(2)
    _finish(node)
    first = next(csv.DictReader((tmp_path / "run" / "joints.csv").open()))
    for k, name in enumerate(reversed(names)):  # published by name, in another order than the robot's
        leg, joint = name.removesuffix("_joint").split("_", 1)
        expected = 0.1 + 0.01 * k - robot.legs[leg].joints[joint].offset
        assert float(first[name.removesuffix("_joint")]) == pytest.approx(expected, abs=1e-6)


def test_params_file_out_of_range_refuses_the_start_in_one_line(tmp_path: Path) -> None:
    params = tmp_path / "params.yaml"
    params.write_text("shc:\n  ros__parameters:\n    swing_height: 0.5\n")
    done = subprocess.run([*SHC, "ros2", "bullet", "--duration", "1", "--out", str(tmp_path / "run"),
                           "--params-file", str(params)], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == ["error: --params-file: swing_height: outside its range [0.01, 0.18] "
                                                "(give a value in the robot's range)"]
    assert not list(tmp_path.glob("run*"))  # refused before anything is written


def test_the_parameter_server_robot_is_refused_before_the_node_starts(tmp_path: Path) -> None:
    hide = ("import sys; sys.modules['rclpy'] = None; from shc_cli.cli import main; "
            f"sys.argv = ['shc', 'ros2', 'server', '--out', {str(tmp_path / 'run')!r}]; main()")
    done = subprocess.run([sys.executable, "-c", hide], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2  # rclpy hidden: refused before any ROS 2 node could be made
    assert done.stderr.strip().splitlines() == ["error: robot: 'server' reads ROS 1's parameter server (give a robot "
                                                "file (shc import openshc converts OpenSHC's parameters))"]


def test_without_the_ros2_extra_shc_ros2_says_how_to_install_it(tmp_path: Path) -> None:
    hide = ("import sys; sys.modules['rclpy'] = None; from shc_cli.cli import main; "
            f"sys.argv = ['shc', 'ros2', '--duration', '1', '--out', {str(tmp_path / 'run')!r}]; main()")
    done = subprocess.run([sys.executable, "-c", hide], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == ["error: shc ros2 needs ROS 2's rclpy: install the ros2 extra "
                                                "(python3 -m uv pip install --python .venv -e '.[ros2]')"]
    assert not list(tmp_path.glob("run*"))


def test_openshc_leg_state_hashes_as_the_issue_measured_it_from_a_colcon_build() -> None:
    """The .msg files shipped (shc_cli/ros2/msg) are OpenSHC's: rosbags' RIHS01 of LegState is the hash the
    colcon-built package advertised (RIHS01_82c8f902…c079), and TipState's fields are OpenSHC's."""
    from shc_cli.ros2.node import store2

    store = store2()
    digest = store.hash_rihs01("syropod_highlevel_controller/msg/LegState")
    assert digest == LEG_STATE_HASH and digest.startswith("RIHS01_82c8f902") and digest.endswith("c079")
    fields = [name for name, _ in store.get_msgdef("syropod_highlevel_controller/msg/TipState").fields]
    assert fields == ["header", "name", "wrench", "step_plane"]


@given(st.floats(allow_nan=False))
def test_the_per_joint_commands_hand_written_cdr_is_rosbags_cdr(value: float) -> None:
    from rosbags.typesys.stores.ros2_kilted import std_msgs__msg__Float64 as Float64

    from shc_cli.ros2.node import _FLOAT64, store2

    expected = bytes(store2().serialize_cdr(Float64(data=value), "std_msgs/msg/Float64"))
    assert _FLOAT64.pack(0x0100, 0, value) == expected
