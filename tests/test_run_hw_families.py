"""``shc run-hw`` end to end on a Dynamixel Protocol 1.0 bus (AX-12A: a READ per servo; MX-64 with 1.0 firmware:
BULK READ) and a Feetech STS3215 bus: 18 emulated servos (shc_cli/hardware/emulator_protocol1.py, keeping the 1 Mbaud
wire's time line), a 3-DOF hexapod that extends openshc_default. Goals on the bus in the model's ticks, faults
mid-walk, the rate check. Every real-time walk is marked slow and serial: .ci/run runs them alone after the other
slow tests, since beside another test worker on 2 cores an emulated bus starved past the packet timeout reads as a
silent servo (a fresh clone's fast suite on a loaded machine failed two walks so). Refusals before the walk run the
command in-process (nothing real-time happens in them) and stay in the fast suite.

The emulator is served by a process of its own (shc_cli/hardware/emulator_process.py) while run-hw runs in another:
as a thread of pytest's process, on a loaded 2-core machine or beside CI's other test worker, it was kept off the CPU
past the SDKs' packet timeouts (a false "no reply"; a real bus does not share the host's CPU).
"""

from __future__ import annotations

import json
import math
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from shc_cli.hardware import protocol1 as p1
from shc_cli.hardware.emulator_process import EmulatorProcess, Heard, promptly
from shc_cli.record.runread import read_run
from tests.run_waits import StderrLines, wait_running_on_stderr

from .test_cli import run

SHC = [sys.executable, "-m", "shc_cli.cli"]
JOINTS = [f"{leg}_{joint}" for leg in ("AR", "BR", "CR", "CL", "BL", "AL") for joint in ("coxa", "femur", "tibia")]
"""Servo id k + 1 drives JOINTS[k]."""
FAMILIES = {"AX-12A": (0.1, 1024, 300.0, 30), "MX-64(1.0)": (0.01, 4096, 360.0, 30),
            "STS3215": (0.01, 4096, 360.0, 42)}
"""Model → (control period [s] of the fast tests; ticks over the range [°]; the Goal Position address). AX-12A
reads each servo: its 18 round trips through the pty cost this (loaded, 2-core) test machine 18–45 ms, so its fast
tests run at 10 Hz, which run-hw's rate check accepts however busy the machine is; the slow 60 s test runs it at
the documented 25 Hz (docs/performance.md)."""
RATES = {"AX-12A": 0.04, "MX-64(1.0)": 0.01, "STS3215": 0.01}
"""The 60 s runs' periods [s]: 100 Hz, and 25 Hz for 18 AX-12A read one by one on one bus."""
FAULTED = 5
"""The servo the fault tests break: BR_femur."""
QUICK = ["[start_up]", "time_to_start = 1.5", "[walker.step_frequency]", "default = 2.0"]
"""The robot of the short walks and the fault tests starts up in 1.5 s and steps at 2 Hz: run-hw keeps the wall clock,
and openshc_default's 6 s start-up and 1 Hz steps (2.5 s to start walking, 2 s to stop) were most of each such test's
time (the long walks and the benchmark keep them)."""


def _robot(folder: Path, model: str, period: float | None = None, extra: str = "", quick: bool = False) -> Path:
    """The hexapod on one bus of ``model`` servos: AL_coxa turned against its joint with its zero off the middle
    and a joint offset, so the goal ticks test direction, zero and offset; ``quick``: :data:`QUICK`."""
    dt, ticks, _, _ = FAMILIES[model]
    zero = ticks // 2 - 12
    lines = ['extends = "openshc_default"', f'name = "hexapod_{model[:2].lower()}"', f"time_delta = {period or dt}",
             *(QUICK if quick else []),
             "[legs.AL.joints.coxa]", "offset = 0.05", "[hardware]", f'model = "{model}"', "return_delay_us = 0",
             extra, "[hardware.servos]"]
    lines += [f"{key} = {{ id = {k + 1} }}" if key != "AL_coxa" else
              f"{key} = {{ id = {k + 1}, direction = -1, zero_ticks = {zero} }}" for k, key in enumerate(JOINTS)]
    path = folder / f"{model.replace('(', '').replace(')', '')}.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@contextmanager
def _bus(model: str, latency_s: float = 0.0) -> Iterator[EmulatorProcess]:
    """18 servos of ``model`` (ids 1–18) on one emulated bus keeping the 1 Mbaud wire's time line; the run-hw the
    test starts meanwhile runs ahead of other work where allowed (:func:`promptly`)."""
    with promptly(), EmulatorProcess({k + 1: model for k in range(18)}, wire_time=True, latency_s=latency_s) as bus:
        yield bus


def _goal_writes(bus: EmulatorProcess, model: str, start: int = 0) -> list[Heard]:
    address = FAMILIES[model][3]
    return [p for p in bus.packets(start) if p.instruction == p1.SYNC_WRITE and p.params[0] == address]


@pytest.mark.slow
@pytest.mark.serial  # a real-time walk on an emulated bus (module docstring)
@pytest.mark.parametrize("model", list(FAMILIES))
def test_walks_and_the_goals_are_the_models_ticks(model: str, tmp_path: Path) -> None:
    """A goal on the bus = zero + direction × (angle + offset) in the model's ticks (AX-12A: 1024 per 300°); the
    robot walks, packs and the torque goes off."""
    robot = _robot(tmp_path, model, quick=True)
    with _bus(model) as bus:
        result = subprocess.run([*SHC, "run-hw", str(robot), "--port", bus.port, "--out", str(tmp_path / "run"),
                                 "--velocity", "1,0,0", "--duration", "1", "--stop-state", "running"],
                                capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, result.stderr
        assert not any(bus.torque_on(k + 1) for k in range(18))
        writes = _goal_writes(bus, model)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["fault"] is None and summary["sim_time_s"] > 2.0
    log = read_run(tmp_path / "run")
    assert (log.walk_state == "MOVING").any()
    commanded = log.commanded
    assert commanded is not None
    _, ticks, degrees, _ = FAMILIES[model]
    per_rad = ticks / math.radians(degrees)
    last = writes[-1].params  # the last goal write is the log's last commanded row
    on_bus = {last[at]: int.from_bytes(last[at + 1:at + 3], "little") for at in range(2, len(last), 1 + last[1])}
    columns = [f"{key}_commanded" for key in JOINTS]
    row = dict(zip(columns, commanded[-1].reshape(-1), strict=True))  # (L, n): legs in file order
    for k, key in enumerate(JOINTS):
        zero, direction, offset = (ticks // 2 - 12, -1, 0.05) if key == "AL_coxa" else (ticks // 2, 1, 0.0)
        expected = round(zero + direction * (row[f"{key}_commanded"] + offset) * per_rad)
        assert on_bus[k + 1] == expected, key
    assert on_bus[16] != ticks // 2 - 12  # the offset moved it


FAULTS = ["overload", "vanish", "corrupt"]


@pytest.mark.slow
@pytest.mark.serial  # real-time walks on an emulated bus (module docstring)
@pytest.mark.parametrize(("model", "fault"), [(model, fault) for model in FAMILIES for fault in FAULTS])
def test_a_fault_mid_walk_stops_the_goals_names_the_servo_and_exits_3(model: str, fault: str,
                                                                       tmp_path: Path) -> None:
    """Each fault on each family's bus."""
    robot = _robot(tmp_path, model, quick=True)
    with _bus(model) as bus:
        process = subprocess.Popen([*SHC, "-v", "run-hw", str(robot), "--port", bus.port, "--out",
                                    str(tmp_path / "run"), "--velocity", "1,0,0", "--duration", "30"],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines = StderrLines(process)
        try:
            wait_running_on_stderr(process, lines, extra_s=0.5)
            if fault == "overload":
                marker = bus.protect(FAULTED)
            elif fault == "vanish":
                marker = bus.vanish(FAULTED)
            else:
                marker = bus.fault(FAULTED, "corrupt_checksum", True)
            process.wait(timeout=120)
        finally:
            if process.poll() is None:
                process.kill()
        stderr = lines.text()
        assert process.returncode == 3, stderr
        reason = {"overload": "BR_femur: overload", "vanish": "no reply from BR_femur",
                  "corrupt": "corrupt reply (checksum or length) from BR_femur"}[fault]
        assert f"fault: {reason}" in stderr
        # a protection bit stops at once; a silent or garbled servo at its 3rd cycle unread (missed_reads_fault),
        # the two cycles before bridged with its last reading, each writing its goals
        assert len(_goal_writes(bus, model, marker)) <= (1 if fault == "overload" else 1 + 2)
        heard = [k + 1 for k in range(18) if not (fault == "vanish" and k + 1 == FAULTED)]  # a vanished one hears none
        assert not any(bus.torque_on(servo) for servo in heard)  # torque released
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert "BR_femur" in summary["fault"]


def test_refuses_a_rate_the_bus_cannot_keep_and_says_which_it_can(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """18 AX-12A read one by one behind an adapter with 1.5 ms of turnaround: ≥ 27 ms a cycle, so 100 Hz is
    refused before the torque goes on, naming the rate it keeps and the time_delta that works."""
    robot = _robot(tmp_path, "AX-12A", period=0.01)
    with _bus("AX-12A", latency_s=0.0015) as bus:
        code, _, stderr = run(["run-hw", str(robot), "--port", bus.port, "--out", str(tmp_path / "run")], capsys,
                              monkeypatch)
        assert not any(p.instruction == p1.SYNC_WRITE and p.params[0] == 24 and p.params[3] == 1
                       for p in bus.packets())  # the torque never went on
    assert code == 2, stderr
    assert "refusing to start: one cycle's reads and goal write take" in stderr
    assert "one read per servo, 18 servos on the busiest bus" in stderr and "set time_delta = " in stderr
    assert len(stderr.strip().splitlines()) == 2  # the return delay written, then the one-line error
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize(("model", "file_model", "message"), [
    ("AX-12A", "AX-18A", "AR_coxa: servo 1 is model number 12, not a AX-18A (18)"),
    ("STS3215", "MX-64(1.0)", "AR_coxa: servo 1 is model number 2563, not a MX-64(1.0) (310)"),  # STS firmware
])
def test_refuses_the_wrong_model_or_protocol(model: str, file_model: str, message: str, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                             monkeypatch) -> None:
    robot = _robot(tmp_path, model)
    robot.write_text(robot.read_text().replace(f'model = "{model}"', f'model = "{file_model}"'))
    with _bus(model) as bus:
        code, _, stderr = run(["run-hw", str(robot), "--port", bus.port, "--out", str(tmp_path / "run")], capsys,
                              monkeypatch)
    assert code == 2 and message in stderr, stderr


def test_refuses_wheel_mode_and_angle_limits_narrower_than_the_joints(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    robot = _robot(tmp_path, "AX-12A")
    with _bus("AX-12A") as bus:
        bus.set(4, 6, 0)
        bus.set(4, 8, 0)  # both angle limits 0: wheel mode
        bus.set(9, 6, 400)  # CW limit inside CR_tibia's range
        code, _, stderr = run(["run-hw", str(robot), "--port", bus.port, "--out", str(tmp_path / "run")], capsys,
                              monkeypatch)
    assert code == 2, stderr
    assert "BR_coxa: servo 4 is in wheel mode" in stderr
    assert "CR_tibia: the joint limits" in stderr and "servo 9's angle limits 400..1023" in stderr


def test_validate_refuses_two_protocols_on_one_bus(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    robot = _robot(tmp_path, "AX-12A")
    robot.write_text(robot.read_text().replace("AR_coxa = { id = 1 }", 'AR_coxa = { id = 1, model = "STS3215" }'))
    code, _, stderr = run(["validate", str(robot)], capsys, monkeypatch)
    assert code == 2
    assert "AX-12A speaks Dynamixel Protocol 1.0, but AR_coxa on bus 0 speaks Feetech STS/SCS" in stderr
    assert "put each protocol on a bus of its own" in stderr


@pytest.mark.slow
@pytest.mark.serial  # alone on the machine in .ci/run: beside another worker the STS bus starved once in CI
@pytest.mark.parametrize("model", list(FAMILIES))
def test_a_long_walk_holds_the_rate(model: str, tmp_path: Path) -> None:
    """A long walk on 18 servos at the family's rate (100 Hz; AX-12A 25 Hz): no fault, and the cycle-time
    distribution (printed) keeps its median within the period. AX-12A walks 60 s (1,500 cycles of 18 reads), the
    others 20 s (their 60 s figures are benchmarks/bench_run_hw_families.py's)."""
    duration = 60 if model == "AX-12A" else 20
    robot = _robot(tmp_path, model, period=RATES[model])
    with _bus(model) as bus:
        result = subprocess.run([*SHC, "run-hw", str(robot), "--port", bus.port, "--out", str(tmp_path / "run"),
                                 "--velocity", "1,0,0", "--duration", str(duration), "--stop-state", "running"],
                                capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    times = np.loadtxt(tmp_path / "run" / "timing.csv", delimiter=",", skiprows=1, usecols=2)
    period_ms = RATES[model] * 1e3
    print(f"{model}: {summary['cycles']} cycles, p50 {np.percentile(times, 50):.2f} ms, p99 "
          f"{np.percentile(times, 99):.2f} ms, max {times.max():.2f} ms, {summary['overruns']} overruns")
    assert summary["fault"] is None and summary["sim_time_s"] > duration
    assert np.percentile(times, 50) < period_ms


@pytest.mark.parametrize("model", ["AX-12A", "STS3215", "XM430-W350"])
def test_a_port_that_is_not_there_is_one_line_naming_it(model: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Every family opens its ports the same way (hardware.bus.open_port): a missing adapter is one line that names
    the port and how to give it, exit 2, nothing written."""
    robot = _robot(tmp_path, "AX-12A")
    robot.write_text(robot.read_text().replace('model = "AX-12A"', f'model = "{model}"'))
    code, _, stderr = run(["run-hw", str(robot), "--port", "/dev/ttyNOTHERE0", "--out", str(tmp_path / "run")],
                          capsys, monkeypatch)
    assert code == 2, stderr
    assert stderr.strip().splitlines() == [
        "error: /dev/ttyNOTHERE0: cannot open the serial port: no such device (give the servo bus adapter with "
        "--port, e.g. /dev/ttyUSB0)"], stderr
    assert not (tmp_path / "run").exists()
