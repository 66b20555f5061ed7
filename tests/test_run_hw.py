"""``shc run-hw`` end to end against the Protocol 2.0 servo emulator: start-up, walking, faults, Ctrl-C."""

from __future__ import annotations

import json
import os
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
from shc_cli.hardware.emulator_process import EmulatorProcess, promptly
from shc_cli.record.runread import read_run
from shc_cli.spec.loading import load_robot
from tests.run_waits import wait_running

pytestmark = pytest.mark.slow  # real-time runs of shc run-hw (subprocesses) on the emulated bus

SHC = [sys.executable, "-m", "shc_cli.cli"]


@contextmanager
def _bus(skip: int | None = None) -> Iterator[EmulatorProcess]:
    """Bullet's 30 servos on an emulated bus served by a process of its own (hardware/emulator_process.py) while
    ``run-hw`` runs in another: as a thread of this (pytest) process, on a loaded 2-core machine or beside CI's other
    test worker, the emulator was kept off the CPU past the SDK's packet timeout and run-hw reported a false "no reply
    from AR_coxa" (real servos answer on their own). The run-hw the test starts meanwhile runs ahead of other work
    where allowed (:func:`promptly`), as on a robot's computer."""
    robot = load_robot("bullet").robot
    with promptly(), EmulatorProcess({s.id: "MX-106" for s in robot.hardware.servos.values() if s.id != skip}) as bus:
        yield bus


def _run_hw(bus: EmulatorProcess, out: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """The CLI in its own process."""
    return subprocess.run([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(out), *args],
                          capture_output=True, text=True, timeout=120)


def _goal_writes_after(bus: EmulatorProcess, index: int) -> int:
    return sum(1 for packet in bus.packets(index) if packet.instruction == p2.SYNC_WRITE
               and int.from_bytes(packet.params[0:2], "little") == 116)


def test_walks_on_the_emulated_bus_and_stops_with_torque_off(tmp_path: Path) -> None:
    with _bus() as bus:
        result = _run_hw(bus, tmp_path / "run", "--velocity", "1,0,0", "--duration", "2")
        assert result.returncode == 0, result.stderr
        summary = json.loads((tmp_path / "run" / "summary.json").read_text())
        assert summary["fault"] is None and summary["stopped_by_request"] is True
        assert summary["cycles"] > 508 + 200  # start-up, 2 s walking, the stop
        assert bus.ids() and all(bus.table(i, 64) == b"\0" for i in bus.ids())  # torque off at the end
        assert all(abs(bus.position(i) - bus.goal(i)) <= 3 for i in bus.ids())  # the servos followed
    log = read_run(tmp_path / "run")  # the simulate format: analyze and export bag read it
    assert len(log.t) == summary["cycles"]
    assert log.running.any() and (log.walk_state == "MOVING").any()
    commanded, measured = log.commanded, log.joints
    assert commanded is not None
    assert abs(commanded[-1] - measured[-1]).max() < 0.01  # [rad]: commanded vs emulated at the end
    # the shut-down: stopped walking, then back to the joints it started from (all servos at 2048 ticks = 0 rad)
    assert summary["final_state"] == "PACKED" and log.states is not None and log.states[-1, 0] == "PACKED"
    assert abs(commanded[-1] - measured[0]).max() < 1e-3
    analysis = subprocess.run([*SHC, "analyze", str(tmp_path / "run"), "--json"], capture_output=True, text=True,
                              timeout=120)
    assert analysis.returncode == 0, analysis.stderr
    report = json.loads(analysis.stdout)
    assert report["scenario"] == "hardware" and report["window_s"] > 2.0  # the RUNNING cycles
    bag = subprocess.run([*SHC, "export", "bag", str(tmp_path / "run"), "--out", str(tmp_path / "run_bag")],
                         capture_output=True, text=True, timeout=120)
    assert bag.returncode == 0, bag.stderr
    assert (tmp_path / "run_bag" / "metadata.yaml").exists()


def test_dry_run_never_enables_torque_or_writes_goals(tmp_path: Path) -> None:
    with _bus() as bus:
        result = _run_hw(bus, tmp_path / "dry", "--dry-run", "--duration", "0.5", "--stop-state", "ready")
        assert result.returncode == 0, result.stderr
        assert _goal_writes_after(bus, 0) == 0
        assert not any(p.instruction == p2.SYNC_WRITE and p.params[0] == 64 and p.params[5] == 1 for p in bus.packets())


def test_refuses_to_start_with_a_missing_servo_or_a_hardware_error(tmp_path: Path) -> None:
    with _bus(skip=34) as bus:
        result = _run_hw(bus, tmp_path / "missing")
        assert result.returncode == 2
        assert "refusing to start: CR_tibia: servo 34 does not answer" in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1 and not (tmp_path / "missing").exists()
    with _bus() as bus:
        bus.fault(53, "hardware_error", 32)
        result = _run_hw(bus, tmp_path / "hot")
        assert result.returncode == 2 and "BL_femur: hardware error (overload)" in result.stderr


@pytest.mark.parametrize("fault", ["vanish", "overload", "corrupt_crc"])
def test_a_fault_mid_run_stops_commanding_within_the_missed_reads_limit(fault: str, tmp_path: Path) -> None:
    with _bus() as bus:
        process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                    "--velocity", "1,0,0", "--duration", "5", "--on-fault", "hold"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        wait_running(tmp_path / "run", process, extra_s=1.0)  # into walking
        if fault == "vanish":
            marker = bus.vanish(42)
        elif fault == "corrupt_crc":
            marker = bus.fault(42, "corrupt_crc", True)
        else:
            marker = bus.fault(42, "hardware_error", 32)
        _, stderr = process.communicate(timeout=60)
        assert process.returncode == 3, stderr  # a fault has its own exit code (docs/commands.md)
        reason = {"vanish": "no reply from CL_coxat", "corrupt_crc": "corrupt reply (CRC or length) from CL_coxat",
                  "overload": "CL_coxat: overload"}[fault]
        assert f"fault: {reason}" in stderr
        summary = json.loads((tmp_path / "run" / "summary.json").read_text())
        assert "CL_coxat" in summary["fault"]
        events = [json.loads(line) for line in (tmp_path / "run" / "events.log").read_text().splitlines()]
        [fault_event] = [e for e in events if e["event"] == "fault"]  # the run directory keeps the fault too
        assert reason in fault_event["message"] and fault_event["level"] == "error"
        assert isinstance(fault_event["cycle"], int) and fault_event["cycle"] >= summary["cycles"] - 1
        # a hardware error stops at once; a servo that stopped answering is a fault at its 3rd cycle unread
        # (hardware.missed_reads_fault), the two before bridged with its last reading, each writing its goals
        assert _goal_writes_after(bus, marker) <= (2 if fault == "overload" else 2 + 2)
        assert bus.table(13, 64) == b"\1"  # --on-fault hold: the others keep their torque


@pytest.mark.parametrize("stop_signal", [signal.SIGINT, signal.SIGTERM])
def test_ctrl_c_stops_walking_and_keeps_a_complete_log(stop_signal: signal.Signals, tmp_path: Path) -> None:
    """Ctrl-C (SIGINT) or SIGTERM: the walk stops, the robot shuts down to PACKED, the torque goes off, the log is
    complete."""
    with _bus() as bus:
        process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                    "--velocity", "1,0,0", "--duration", "60"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        wait_running(tmp_path / "run", process, extra_s=1.0)
        process.send_signal(stop_signal)
        _, stderr = process.communicate(timeout=60)
        assert process.returncode == 0, stderr
        summary = json.loads((tmp_path / "run" / "summary.json").read_text())
        assert summary["stopped_by_request"] is True and summary["fault"] is None
        log = read_run(tmp_path / "run")
        assert len(log.t) == summary["cycles"] and log.walk_state[-1] == "STOPPED"
        assert summary["final_state"] == "PACKED"  # stopped walking, then shut down
        assert bus.ids() and all(bus.table(i, 64) == b"\0" for i in bus.ids())


def test_stdin_commands_and_the_watchdog(tmp_path: Path) -> None:
    """JSON lines drive the walk, the gait and the robot state; when they stop coming, the watchdog zeroes the
    velocity; the end of input ends the run."""
    with _bus() as bus:
        process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                    "--input", "stdin", "--watchdog", "0.3", "--stop-state", "ready"],
                                   stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        assert process.stdin is not None

        def send(line: str, wait_s: float = 0.1) -> None:
            assert process.stdin is not None
            process.stdin.write(line + "\n")
            process.stdin.flush()
            time.sleep(wait_s)

        wait_running(tmp_path / "run", process)  # process start, bus check, the 5 s start-up
        for index in range(30):  # 3 s of walking commands; a gait change on the way
            send('{"velocity": [1.0, 0.0, 0.0], "gait": "wave"}' if index == 5 else '{"velocity": [1.0, 0.0, 0.0]}')
        send("not json")
        send('{"velocity": [1.0, 0.0]}')
        time.sleep(4.0)  # silence: the watchdog stops the walk
        send('{"state": "ready"}', 1.0)  # direct mode: READY once stopped
        send('{"state": "running"}', 0.5)
        _, stderr = process.communicate(timeout=60)  # closes stdin: end of input
        assert process.returncode == 0, stderr
        assert "ignored line 'not json'" in stderr and "velocity needs 3 numbers" in stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["watchdog_trips"] == 1 and summary["fault"] is None
    events = [json.loads(line) for line in (tmp_path / "run" / "events.log").read_text().splitlines()]
    assert any("ignored line 'not json'" in e["message"] for e in events)  # the input thread's warnings
    assert [e["event"] for e in events].count("watchdog") == 1
    assert summary["gait"] == "wave" and summary["final_state"] == "READY"
    log = read_run(tmp_path / "run")
    walked = log.command[:, 0] == 1.0
    assert walked.sum() > 150  # the commanded cycles
    after = int(walked.nonzero()[0][-1]) + 1
    assert (log.command[after:, 0] == 0.0).all() and "STOPPED" in set(log.walk_state[after:])
    assert log.states is not None
    order = [s for i, s in enumerate(log.states[after:, 0]) if i == 0 or s != log.states[after + i - 1, 0]]
    assert order == ["RUNNING", "READY", "RUNNING", "READY"]  # asked for READY, RUNNING; the end of input: READY


def test_keyboard_keys_drive_the_robot_and_the_terminal_is_restored(tmp_path: Path) -> None:
    import pty
    import termios

    master, slave = pty.openpty()
    before = termios.tcgetattr(slave)
    try:
        with _bus() as bus:
            process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                        "--input", "keyboard", "--stop-state", "ready"],
                                       stdin=slave, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            wait_running(tmp_path / "run", process)
            os.write(master, b"www")  # three presses: 0.3 forward
            time.sleep(1.5)
            os.write(master, b" ")
            time.sleep(0.3)
            os.write(master, b"x")  # stop and shut down
            _, stderr = process.communicate(timeout=60)
            assert process.returncode == 0, stderr
            assert "keys: w/s forward/back" in stderr
        assert termios.tcgetattr(slave) == before  # cbreak mode undone
    finally:
        os.close(master)
        os.close(slave)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["stopped_by_request"] is True and summary["final_state"] == "READY"
    log = read_run(tmp_path / "run")
    forward = log.command[:, 0]
    assert 0.3 in set(np.round(forward, 6)) and forward[-1] == 0.0  # the presses add up; space zeroes
    assert (log.walk_state[forward == 0.3] != "STOPPED").any()  # it set off


@pytest.mark.parametrize(("input_mode", "message"), [
    ("gamepad:/dev/input/event99", "/dev/input/event99: cannot open the gamepad"),
    ("keyboard", "standard input is not a terminal"),
    ("joystick", "'joystick' is not an input"),
    ("commands", "'commands' is not an input"),
])
def test_unusable_inputs_are_one_line_errors(input_mode: str, message: str, tmp_path: Path) -> None:
    with _bus() as bus:
        result = subprocess.run([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(tmp_path / "run"),
                                 "--input", input_mode], capture_output=True, text=True, timeout=60,
                                stdin=subprocess.DEVNULL)
    assert result.returncode == 2 and message in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and not (tmp_path / "run").exists()


def _two_bus_robot(tmp_path: Path) -> Path:
    """Bullet with its left legs on a second bus and a current limit."""
    lines = ['extends = "bullet"', 'name = "bullet_two_buses"', "[hardware]", "current_limit_ma = 1000.0",
             "[hardware.servos]"]
    lines += [f"{leg}_{joint} = {{ id = {10 * row + col + 1}, bus = 1 }}"
              for row, leg in ((4, "CL"), (5, "BL"), (6, "AL"))
              for col, joint in enumerate(("coxa", "coxat", "femur", "tibia", "tarsus"))]
    path = tmp_path / "two_buses.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_two_buses_profile_velocity_and_current_limit(tmp_path: Path) -> None:
    robot_file = _two_bus_robot(tmp_path)
    right = {i: "MX-106" for row in (1, 2, 3) for i in range(10 * row + 1, 10 * row + 6)}
    left = {i: "MX-106" for row in (4, 5, 6) for i in range(10 * row + 1, 10 * row + 6)}
    with promptly(), EmulatorProcess(right) as bus0, EmulatorProcess(left) as bus1:
        missing = subprocess.run([*SHC, "run-hw", str(robot_file), "--port", bus0.port], capture_output=True,
                                 text=True, timeout=60)
        assert missing.returncode == 2 and "servos are on buses 0, 1, but 1 port given" in missing.stderr
        result = subprocess.run([*SHC, "run-hw", str(robot_file), "--port", bus0.port, "--port", bus1.port,
                                 "--out", str(tmp_path / "run"), "--velocity", "1,0,0", "--duration", "1",
                                 "--profile-velocity", "--stop-state", "ready"], capture_output=True, text=True,
                                timeout=120)
        assert result.returncode == 0, result.stderr
        assert "current limit 1000 mA written to 30 servos" in result.stderr
        assert "return delay time 0 µs written to 30 servos" in result.stderr  # from the factory 500 µs
        for bus in (bus0, bus1):
            ids = bus.ids()
            assert all(int.from_bytes(bus.table(i, 38, 2), "little") == round(1000 / 3.36) for i in ids)
            packets = bus.packets()
            writes = [p for p in packets if p.instruction == p2.SYNC_WRITE
                      and int.from_bytes(p.params[0:2], "little") == 112]
            assert writes and all(int.from_bytes(p.params[2:4], "little") == 8 for p in writes)  # speed + goal
            speeds = [int.from_bytes(p.params[at + 1:at + 5], "little") for p in writes
                      for at in range(4, len(p.params), 9)]
            assert min(speeds) >= 1 and max(speeds) > 20  # [0.229 rpm]: 0 would mean no limit
            assert all(abs(bus.position(i) - bus.goal(i)) <= 3 for i in ids)
            reads = [p for p in packets if p.instruction == p2.SYNC_READ and p.params[0] == 126]
            assert len(reads) > 500 and set(reads[-1].params[4:]) == set(ids)  # only its own servos
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["fault"] is None and summary["port"] == f"{bus0.port}, {bus1.port}"


def test_refuses_servos_not_in_position_mode_or_with_narrow_position_limits(tmp_path: Path) -> None:
    with _bus() as bus:
        bus.poke(23, 11, bytes([1]))  # velocity mode
        bus.poke(44, 52, (1000).to_bytes(4, "little"))  # min position limit inside the joint's range
        result = _run_hw(bus, tmp_path / "run")
    assert result.returncode == 2, result.stderr
    assert "BR_femur: servo 23 is in velocity operating mode; set Operating Mode (address 11) to 3" in result.stderr
    assert "CL_tibia: the joint limits" in result.stderr and "servo 44's position limits 1000..4095" in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_sequence_mode_unpacks_starts_up_and_packs_again_on_the_servos(tmp_path: Path) -> None:
    """A robot with ``start_up.sequence``: from the servos' positions the controller estimates PACKED, unpacks, runs
    the stepped start-up, walks, and at the end of the input runs the shut-down sequence and packs."""
    robot_file = tmp_path / "sequence.toml"
    robot_file.write_text('extends = "bullet"\nname = "bullet_sequence"\n[start_up]\nsequence = true\n')
    with _bus() as bus:
        result = subprocess.run([*SHC, "run-hw", str(robot_file), "--port", bus.port, "--out", str(tmp_path / "run"),
                                 "--velocity", "1,0,0", "--duration", "0.5"], capture_output=True, text=True,
                                timeout=120)
        assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["fault"] is None and summary["final_state"] == "PACKED"
    log = read_run(tmp_path / "run")
    assert log.states is not None
    states = log.states[:, 0]
    order = [s for i, s in enumerate(states) if i == 0 or s != states[i - 1]]
    assert order == ["PACKED", "READY", "RUNNING", "READY", "PACKED"]
    assert (log.walk_state == "MOVING").any() or (log.walk_state == "STARTING").any()
