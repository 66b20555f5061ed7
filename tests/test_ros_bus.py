"""``shc ros --backend bus``: OpenSHC's node driving the servos (the Protocol 2.0 emulator) in a real ROS 1 system
(Debian's roscore and rostopic, the rospy stand-in for syropod_remote), with run-hw's safety: no torque before the
remote is OPERATIONAL, a controlled shut-down on Ctrl-C, a servo fault stops commanding at once."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from shc_cli.hardware import protocol2 as p2
from shc_cli.hardware.emulator_process import EmulatorProcess
from shc_cli.record.runread import read_run
from shc_cli.spec.loading import load_robot
from tests.ros_master import ros, ros_env

__all__ = ["ros_env"]

pytestmark = pytest.mark.slow  # real-time node sessions in subprocesses

ROOT = Path(__file__).parents[1]
SHC = [sys.executable, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]
DRIVER = ["/usr/bin/python3", str(ROOT / "tests" / "ros_remote_driver.py")]


IDS = sorted(s.id for s in load_robot("bullet").robot.hardware.servos.values())


@contextmanager
def _bus(skip: int | None = None) -> Iterator[EmulatorProcess]:
    """Bullet's 30 servos on an emulated bus served by a process of its own (a thread of this one can be starved
    of CPU past the packet timeout on a loaded machine: shc_cli/hardware/emulator_process.py)."""
    with EmulatorProcess({i: "MX-106" for i in IDS if i != skip}) as bus:
        yield bus


def _wait_for(predicate: object, timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():  # type: ignore[operator]
            return
        time.sleep(0.2)
    pytest.fail(f"timed out waiting for {what}")


def _torque(bus: EmulatorProcess, skip: int | None = None) -> set[int]:
    return {int(bus.torque_on(i)) for i in IDS if i != skip}


def _node(env: dict[str, str], bus: EmulatorProcess, out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen([*SHC, "ros", "bullet", "--backend", "bus", "--port", bus.port, "--out", str(out)],
                            cwd=ROOT, env={**env, "PYTHONUNBUFFERED": "1"}, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def test_the_node_walks_the_servos_and_shuts_down_on_ctrl_c(ros_env: dict[str, str], tmp_path: Path) -> None:
    run = tmp_path / "run"
    with _bus() as bus:
        node = _node(ros_env, bus, run)
        try:
            _wait_for(lambda: "/shc" in ros(ros_env, "rosnode", "list"), 90, "the node to register")
            time.sleep(1.0)
            assert _torque(bus) == {0}  # registered, the remote not OPERATIONAL yet: the servos are left alone
            assert ros(ros_env, "rostopic", "type", "/joint_states").strip() == "sensor_msgs/JointState"
            driver = subprocess.run([*DRIVER, "0.05"], env=ros_env, capture_output=True, text=True, timeout=240)
            assert "running" in driver.stdout and "done" in driver.stdout, driver.stdout + driver.stderr
            assert _torque(bus) == {1}
            measured = ros(ros_env, "rostopic", "echo", "-n", "1", "/joint_states/position", timeout=30)
            positions = np.array([float(v) for v in measured.strip().strip("-").strip().strip("[]").split(",")])
            assert len(positions) == 30 and np.abs(positions).max() > 0.1  # the servos' angles, standing
        finally:
            node.send_signal(signal.SIGINT)
            _, err = node.communicate(timeout=90)
        assert node.returncode == 0, err
        assert _torque(bus) == {0}  # released after the shut-down
        assert all(abs(bus.position(i) - 2048) <= 3 for i in IDS)  # back where it started (0 rad)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["backend"] == "bus" and summary["fault"] is None and summary["final_state"] == "PACKED"
    assert summary["stop_reason"] == "SIGINT" and summary["stopped_by_request"] is True
    assert 50.0 < summary["rate_hz"] <= 101.0, summary  # a late cycle restarts the deadline (run-hw): slower if loaded
    log = read_run(run)
    assert (log.walk_state == "MOVING").any() and log.command[:, 0].max() == 1.0  # the remote's 0.5, 1.0 …
    assert log.states is not None
    states = [s for i, s in enumerate(log.states[:, 0]) if i == 0 or s != log.states[i - 1, 0]]
    assert states[-2:] == ["READY", "PACKED"] and "RUNNING" in states  # walked, stopped, shut down, packed
    commanded, measured_log = log.commanded, log.joints
    assert commanded is not None and abs(commanded[-1] - measured_log[-1]).max() < 0.01  # the servos followed


def test_a_servo_fault_stops_the_node_commanding(ros_env: dict[str, str], tmp_path: Path) -> None:
    run = tmp_path / "run"
    with _bus() as bus:
        node = _node(ros_env, bus, run)
        driver = None
        try:
            _wait_for(lambda: "/shc" in ros(ros_env, "rosnode", "list"), 90, "the node to register")
            driver = subprocess.Popen([*DRIVER, "0.2"], env=ros_env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      text=True)
            log = run.with_name("run.partial") / "log.csv"
            _wait_for(lambda: node.poll() is not None or (_torque(bus) == {1} and log.exists()
                                                          and ",RUNNING," in log.read_text()), 120, "the robot running")
            assert node.poll() is None, node.communicate()[1]
            bus.fault(53, "no_reply", True)  # BL_femur goes silent
            _, err = node.communicate(timeout=60)
            index = len(bus.packets())
        finally:
            if node.poll() is None:
                node.send_signal(signal.SIGINT)
                node.communicate(timeout=60)
            if driver is not None:
                driver.kill()
                driver.communicate()
        assert node.returncode == 3, err  # as run-hw: a servo fault
        assert "BL_femur" in err and "torque off" in err
        assert _torque(bus, skip=53) == {0}  # --on-fault torque-off
        assert not any(instruction == p2.SYNC_WRITE and int.from_bytes(params[0:2], "little") == 116
                       for _, instruction, params in bus.packets(index))  # no goal after the end
    summary = json.loads((run / "summary.json").read_text())
    assert "BL_femur" in summary["fault"] and summary["stopped_by_request"] is False


def test_a_missing_servo_refuses_to_start(ros_env: dict[str, str], tmp_path: Path) -> None:
    with _bus(skip=34) as bus:
        result = subprocess.run([*SHC, "ros", "bullet", "--backend", "bus", "--port", bus.port, "--out",
                                 str(tmp_path / "run")], cwd=ROOT, env=ros_env, capture_output=True, text=True,
                                timeout=120)
    assert result.returncode == 2 and "refusing to start: CR_tibia: servo 34 does not answer" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and not (tmp_path / "run").exists()


def test_the_bus_backend_needs_ports_and_ports_need_it(tmp_path: Path) -> None:
    for args, message in ((["--backend", "bus"], "the bus backend needs its serial ports"),
                          (["--port", "/dev/null"], "--port is for the bus backend, not 'none'")):
        result = subprocess.run([*SHC, "ros", "bullet", *args, "--out", str(tmp_path / "run")], cwd=ROOT,
                                capture_output=True, text=True, timeout=60)
        assert result.returncode == 2 and message in result.stderr, result.stderr
        assert len(result.stderr.strip().splitlines()) == 1


def test_the_duration_ends_with_a_shut_down_and_no_remote_means_no_torque(ros_env: dict[str, str],
                                                                          tmp_path: Path) -> None:
    """``--duration``: the node walks the robot to a stop and shuts it down, as after Ctrl-C; a node whose remote
    never becomes OPERATIONAL never enables the torque."""
    with _bus() as bus:
        node = subprocess.Popen([*SHC, "ros", "bullet", "--backend", "bus", "--port", bus.port, "--out",
                                 str(tmp_path / "idle"), "--duration", "3"], cwd=ROOT, env=ros_env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        _, err = node.communicate(timeout=120)
        assert node.returncode == 0, err
        assert not any(instruction == p2.SYNC_WRITE and params[0] == 64 and params[5] == 1
                       for _, instruction, params in bus.packets())  # torque never enabled
        assert not any(instruction == p2.SYNC_WRITE and int.from_bytes(params[0:2], "little") == 116
                       for _, instruction, params in bus.packets())  # no goal written
        run = tmp_path / "walk"
        node = subprocess.Popen([*SHC, "ros", "bullet", "--backend", "bus", "--port", bus.port, "--out", str(run),
                                 "--duration", "45", "--stop-state", "ready"], cwd=ROOT, env=ros_env,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            driver = subprocess.run([*DRIVER, "0.05"], env=ros_env, capture_output=True, text=True, timeout=240)
            assert "done" in driver.stdout, driver.stdout + driver.stderr
            _, err = node.communicate(timeout=120)
        finally:
            if node.poll() is None:
                node.kill()
        assert node.returncode == 0, err
        assert _torque(bus) == {0}
    summary = json.loads((run / "summary.json").read_text())
    assert summary["stop_reason"] == "end" and summary["complete"] is True and summary["final_state"] == "READY"
    idle = json.loads((tmp_path / "idle" / "summary.json").read_text())
    assert idle["cycles"] == 0 and idle["fault"] is None  # no remote: not one cycle run, a run directory all the same
