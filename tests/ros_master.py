"""A real ROS 1 master (Debian's ``roscore``) for the tests of shc's ROS node, on a free port of 127.0.0.1.

Without Debian's ROS packages (``.ci/run`` installs them) the tests skip — except in CI (``CI`` set), where a
missing master is a failure, so a broken install cannot pass as skipped.
"""

from __future__ import annotations

import os
import shutil
import socket
import subprocess
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture(scope="module")
def ros_env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    """The environment of a running ``roscore`` (ROS_MASTER_URI, ROS_HOME); the master stops after the module."""
    if shutil.which("roscore") is None:
        if os.environ.get("CI"):
            pytest.fail("roscore not found: .ci/run must install Debian's ros-core and python3-rostopic")
        pytest.skip("Debian's ROS 1 packages are not installed (apt-get install ros-core python3-rostopic ...)")
    port = _free_port()
    home: Path = tmp_path_factory.mktemp("ros_home")
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}/", ROS_HOME=str(home), ROS_IP="127.0.0.1",
               ROS_LOG_DIR=str(home / "log"))
    core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env=env, start_new_session=True)
    master = xmlrpc.client.ServerProxy(env["ROS_MASTER_URI"])
    deadline = time.monotonic() + 30
    while True:
        try:
            master.getPid("/test")
            if subprocess.run(["rosparam", "get", "/rosversion"], env=env, capture_output=True).returncode == 0:
                break
        except OSError:
            pass
        if time.monotonic() > deadline or core.poll() is not None:
            core.kill()
            pytest.fail("roscore did not start within 30 s")
        time.sleep(0.2)
    try:
        yield env
    finally:
        os.killpg(core.pid, 15)
        core.wait(timeout=20)


def ros(env: dict[str, str], *args: str, timeout: float = 30) -> str:
    """A ROS command-line tool's standard output (``rostopic``, ``rosparam``, ``rosnode`` …); fails on exit ≠ 0."""
    result = subprocess.run(list(args), env=env, capture_output=True, text=True, timeout=timeout)
    assert result.returncode == 0, f"{' '.join(args)}: {result.stderr}"
    return result.stdout
