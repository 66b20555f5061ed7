"""``shc ros`` against Debian's roscore: the rate of /desired_joint_states over a walk, and the cycle periods.

    .venv/bin/python benchmarks/bench_ros.py [--seconds 60]

Starts a roscore on a free port, ``shc ros bullet``, and the rospy stand-in for syropod_remote
(tests/ros_remote_driver.py) with the insectoid schedule scaled to the duration; prints the node's summary
(rate_hz, cycle_time_p50/p99/max_ms, overruns) and the rate rosbag saw (messages over their receive times).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=60.0)
    args = parser.parse_args()
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    folder = Path(tempfile.mkdtemp(prefix="bench-ros-"))
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}/", ROS_IP="127.0.0.1", ROS_HOME=str(folder))
    core = subprocess.Popen(["roscore", "-p", str(port)], env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)
    time.sleep(5)
    shc = [sys.executable, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]
    node = subprocess.Popen([*shc, "ros", "bullet", "--out", str(folder / "run")], cwd=ROOT, env=env,
                            stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(8)
        scale = args.seconds / 70.0  # the recording's schedule is 70 s of walking and standing
        subprocess.run(["/usr/bin/python3", str(ROOT / "tests" / "ros_remote_driver.py"), str(scale)], env=env,
                       check=True, timeout=args.seconds * 3 + 120)
    finally:
        node.send_signal(signal.SIGINT)
        node.communicate(timeout=60)
        os.killpg(core.pid, signal.SIGTERM)
    summary = json.loads((folder / "run" / "summary.json").read_text())
    keys = ("cycles", "rate_hz", "cycle_time_p50_ms", "cycle_time_p99_ms", "cycle_time_max_ms", "overruns", "pauses")
    print(json.dumps({k: summary.get(k) for k in keys}, indent=1))


if __name__ == "__main__":
    main()
