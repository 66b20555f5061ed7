"""The acceptance figures of ``shc ros`` and ``shc ros2``: ``/desired_joint_states`` over a walk, seen by a reliable
subscriber that is not shc (rospy on Debian's ROS 1, rclpy on ROS 2).

    .venv/bin/python benchmarks/bench_ros_rate.py [--ros 1|2|both] [--seconds 30] [--json OUT]

For each ROS: a master on a free port of 127.0.0.1 (ROS 1) or a random ``ROS_DOMAIN_ID`` with loopback-only discovery
(ROS 2); ``shc ros[2] bullet --joint-states-timeout 0``; a listener (:data:`ROS1_LISTENER`, :data:`ROS2_LISTENER`)
that subscribes ``/desired_joint_states`` reliably with a deep queue, then sends OPERATIONAL, RUNNING and a walk
(throttle 0.5 forward) and records each message's header stamp, receive time (and ROS 1's ``seq``) until the node
exits. Printed for the ``--seconds`` s from the first RUNNING cycle: the rate by header stamps and by receive times,
the longest interval of each (and how many exceed three control periods), the messages lost (the node's cycles −
those received; ROS 1 also ``seq`` gaps), and the node's own period p50/p99/max from its summary (periods longer than
its resync limit are counted as ``pauses`` and left out of those, as ``shc ros`` reports them), its overruns (over
1.5 periods) and its largest lag behind the schedule.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import random
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).parents[1]
SHC = [sys.executable, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]
PERIOD = 0.01

ROS1_LISTENER = """
import json, sys, time, threading, rospy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState
from std_msgs.msg import Float32MultiArray, Int8
out = sys.argv[1]
rospy.init_node("rate_listener", disable_signals=True)
got, running = [], []
def on_joints(m):
    got.append((m.header.stamp.to_sec(), time.time(), m.header.seq))
rospy.Subscriber("/desired_joint_states", JointState, on_joints, queue_size=100000, tcp_nodelay=True)
rospy.Subscriber("/shc/walkspace", Float32MultiArray, lambda m: running or running.append(time.time()))
system = rospy.Publisher("/syropod_remote/system_state", Int8, queue_size=1, latch=True)
state = rospy.Publisher("/syropod_remote/robot_state", Int8, queue_size=1, latch=True)
velocity = rospy.Publisher("/syropod_remote/desired_velocity", Twist, queue_size=1, latch=True)
while not rospy.get_published_topics() or "/desired_joint_states" not in [t for t, _ in rospy.get_published_topics()]:
    time.sleep(0.2)
time.sleep(1.0)
twist = Twist(); twist.linear.x = 0.5
velocity.publish(twist); system.publish(Int8(1)); state.publish(Int8(2))
last = time.time()
while True:  # until the node has stopped publishing for 3 s
    n = len(got); time.sleep(1.0)
    last = time.time() if len(got) != n else last
    if got and time.time() - last > 3.0:
        break
json.dump({"messages": got, "running": running[0] if running else None}, open(out, "w"))
"""

ROS2_LISTENER = """
import json, sys, time, rclpy
from rclpy.qos import QoSProfile, ReliabilityPolicy, DurabilityPolicy
from geometry_msgs.msg import Twist
from sensor_msgs.msg import JointState
from std_msgs.msg import Float32MultiArray, Int8
out = sys.argv[1]
rclpy.init()
node = rclpy.create_node("rate_listener")
got, running = [], []
deep = QoSProfile(depth=10000, reliability=ReliabilityPolicy.RELIABLE)
node.create_subscription(JointState, "/desired_joint_states",
                         lambda m: got.append((m.header.stamp.sec + m.header.stamp.nanosec * 1e-9, time.time(), 0)),
                         deep)
node.create_subscription(Float32MultiArray, "/shc/walkspace", lambda m: running or running.append(time.time()), deep)
latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL)
system = node.create_publisher(Int8, "/syropod_remote/system_state", 10)
state = node.create_publisher(Int8, "/syropod_remote/robot_state", 10)
velocity = node.create_publisher(Twist, "/syropod_remote/desired_velocity", 10)
while node.count_publishers("/desired_joint_states") == 0 or system.get_subscription_count() == 0:
    rclpy.spin_once(node, timeout_sec=0.1)
end = time.time() + 1.0
while time.time() < end:
    rclpy.spin_once(node, timeout_sec=0.05)
twist = Twist(); twist.linear.x = 0.5
last, sent = time.time(), 0.0
while True:  # the remote's messages at 10 Hz (as syropod_remote publishes), until the node stops for 3 s
    if time.time() - sent > 0.1:
        system.publish(Int8(data=1)); state.publish(Int8(data=2)); velocity.publish(twist); sent = time.time()
    n = len(got)
    rclpy.spin_once(node, timeout_sec=0.02)
    last = time.time() if len(got) != n else last
    if got and time.time() - last > 3.0:
        break
json.dump({"messages": got, "running": running[0] if running else None}, open(out, "w"))
"""


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def _fastdds_files(shm: Path) -> set[Path]:
    return {*shm.glob("fastdds_*"), *shm.glob("sem.fastdds_*")} if shm.is_dir() else set()


def _figures(seen: dict[str, Any], summary: dict[str, Any], seconds: float, seq: bool) -> dict[str, Any]:
    messages = seen["messages"]
    start = seen["running"] if seen["running"] is not None else messages[0][1]
    window = [m for m in messages if start <= m[1] <= start + seconds]
    figures: dict[str, Any] = {"messages": len(messages), "cycles": summary["cycles"],
                               "lost": summary["cycles"] - len(messages), "window_messages": len(window)}
    for name, k in (("stamp", 0), ("receive", 1)):
        times = [m[k] for m in window]
        gaps = [b - a for a, b in itertools.pairwise(times)]
        figures[f"{name}_rate_hz"] = (len(times) - 1) / (times[-1] - times[0])
        figures[f"{name}_max_interval_ms"] = max(gaps) * 1e3
        figures[f"{name}_intervals_over_3_periods"] = sum(g > 3 * PERIOD for g in gaps)
    if seq:
        seqs = [m[2] for m in messages]
        figures["seq_gaps"] = sum(b - a - 1 for a, b in itertools.pairwise(seqs))
    for key in ("rate_hz", "cycle_time_p50_ms", "cycle_time_p99_ms", "cycle_time_max_ms", "overruns", "pauses",
                "realtime_lag_max_ms"):
        figures[f"node_{key}"] = summary.get(key)
    return figures


def _run(ros: str, seconds: float, folder: Path) -> dict[str, Any]:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    core = None
    if ros == "1":
        port = _free_port()
        env.update(ROS_MASTER_URI=f"http://127.0.0.1:{port}/", ROS_IP="127.0.0.1", ROS_HOME=str(folder / "home1"))
        core = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        time.sleep(5)
        listener = ["/usr/bin/python3", "-c", ROS1_LISTENER]
    else:
        env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST", ROS_DOMAIN_ID=str(random.randint(101, 200)),
                   ROS_HOME=str(folder / "home2"), ROS_LOG_DIR=str(folder / "log2"))
        env.pop("ROS_LOCALHOST_ONLY", None)
        listener = [sys.executable, "-c", ROS2_LISTENER]
    shm = Path("/dev/shm")
    before = _fastdds_files(shm)
    run, seen_file = folder / f"run{ros}", folder / f"seen{ros}.json"
    command = "ros" if ros == "1" else "ros2"
    node = subprocess.Popen([*SHC, command, "bullet", "--joint-states-timeout", "0", "--duration", str(seconds + 25),
                             "--out", str(run)], cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    try:
        done = subprocess.run([*listener, str(seen_file)], env=env, capture_output=True, text=True,
                              timeout=seconds + 240)
        if done.returncode != 0:
            raise SystemExit(f"listener failed: {done.stderr[-2000:]}")
        node.communicate(timeout=120)
    finally:
        if node.poll() is None:
            node.kill()
        if core is not None:
            os.killpg(core.pid, 15)
            core.wait(timeout=30)
        for leftover in _fastdds_files(shm) - before:  # Fast DDS leaves its shared-memory files behind
            leftover.unlink(missing_ok=True)
    summary = json.loads((run / "summary.json").read_text())
    return _figures(json.loads(seen_file.read_text()), summary, seconds, seq=ros == "1")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ros", choices=("1", "2", "both"), default="both")
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="bench-ros-rate-"))
    load = os.getloadavg()
    results = {}
    for ros in (("1", "2") if args.ros == "both" else (args.ros,)):
        results[f"ros{ros}"] = figures = _run(ros, args.seconds, folder)
        print(f"ROS {ros}: " + ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                                        for k, v in figures.items()), flush=True)
    print(f"load average before: {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f}; after: "
          f"{' / '.join(f'{x:.1f}' for x in os.getloadavg())}")
    if args.json is not None:
        args.json.write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
