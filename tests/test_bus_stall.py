"""``shc run-hw`` on a healthy emulated bus while its computer is starved (issue 42, point 2): CPU hogs spinning on
every core beside it, and run-hw itself stopped (SIGSTOP … SIGCONT) for 40–150 ms at random moments — the stalls
measured on a loaded machine (a Raspberry Pi running a browser; a test machine at load 4). Minutes of walking
without a fault; the summary counts the reads it repeated and bridged. Then a servo is unplugged: still a fault,
exit 3, the torque off.

The emulator runs in a process of its own, ahead of other work where allowed (:func:`promptly`: a real bus does
not share the host's CPU); run-hw and the hogs at the ordinary priority. ``SHC_STALL_S`` sets the walking time
(default 120 s per family). Figures: run with ``-s``, each run prints one line.
"""

from __future__ import annotations

import contextlib
import json
import os
import random
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from shc_cli.hardware.emulator_process import EmulatorProcess, promptly
from tests.run_waits import StderrLines, wait_running_on_stderr

pytestmark = [pytest.mark.slow, pytest.mark.serial]

SHC = [sys.executable, "-m", "shc_cli.cli"]
JOINTS = [f"{leg}_{joint}" for leg in ("AR", "BR", "CR", "CL", "BL", "AL") for joint in ("coxa", "femur", "tibia")]
UNPLUGGED = 5
"""BR_femur."""
FAMILIES = {"XM430-W350": 0.01, "AX-12A": 0.05, "STS3215": 0.01}
"""Model → control period [s]: 100 Hz; 20 Hz for 18 AX-12A read one by one (docs/performance.md: 25 Hz on a quiet
machine; the hogs slow every round trip through the pty)."""
STALL_S = (0.04, 0.15)
"""Each stall of run-hw [s]."""
BETWEEN_S = (0.2, 1.5)
"""Time between stalls [s]."""


def _robot(folder: Path, model: str) -> Path:
    lines = ['extends = "openshc_default"', 'name = "hexapod_stall"', f"time_delta = {FAMILIES[model]}",
             "[hardware]", f'model = "{model}"', "return_delay_us = 0", "[hardware.servos]",
             *(f"{key} = {{ id = {k + 1} }}" for k, key in enumerate(JOINTS))]
    path = folder / "hexapod_stall.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


class _Staller(threading.Thread):
    """Stops ``pid`` for a random 40–150 ms every 0.2–1.5 s until :meth:`finish` (seeded: the same stalls each
    run of the test, the machine's own load aside)."""

    def __init__(self, pid: int, seed: int) -> None:
        super().__init__(daemon=True)
        self.pid, self.random = pid, random.Random(seed)
        self.done = threading.Event()
        self.stalls: list[float] = []

    def run(self) -> None:
        while not self.done.wait(self.random.uniform(*BETWEEN_S)):
            length = self.random.uniform(*STALL_S)
            try:
                os.kill(self.pid, signal.SIGSTOP)
                time.sleep(length)
            except ProcessLookupError:
                return
            finally:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(self.pid, signal.SIGCONT)
            self.stalls.append(length)

    def finish(self) -> None:
        self.done.set()
        self.join(timeout=5.0)


def _hogs() -> list[subprocess.Popen[bytes]]:
    """One spinning process per core, at the ordinary priority."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"], preexec_fn=lambda: os.nice(0))
            for _ in range(os.cpu_count() or 2)]


@pytest.mark.parametrize("model", list(FAMILIES))
def test_a_starved_run_hw_on_a_healthy_bus_never_faults_and_an_unplugged_servo_still_does(
        model: str, tmp_path: Path) -> None:
    walk_s = float(os.environ.get("SHC_STALL_S", "120"))
    robot = _robot(tmp_path, model)
    with promptly():  # the emulator ahead of other work (it stands for servos, which have their own CPUs)
        bus = EmulatorProcess({k + 1: model for k in range(18)}, wire_time=model != "XM430-W350")
        bus.start()
    hogs = _hogs()
    staller: _Staller | None = None
    try:
        process = subprocess.Popen([*SHC, "-v", "run-hw", str(robot), "--port", bus.port, "--out",
                                    str(tmp_path / "run"), "--velocity", "0.5,0,0.1", "--duration",
                                    str(walk_s + 120)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        lines = StderrLines(process)
        try:
            staller = _Staller(process.pid, seed=42)
            staller.start()  # from the start checks on
            wait_running_on_stderr(process, lines, timeout_s=300)
            walking = time.monotonic()
            while time.monotonic() - walking < walk_s and process.poll() is None:
                time.sleep(0.5)
            assert process.poll() is None, lines.text()  # minutes of stalls and hogs: still walking
            staller.finish()
            unplugged = time.monotonic()
            bus.vanish(UNPLUGGED)
            process.wait(timeout=120)
            detected = time.monotonic() - unplugged
        finally:
            if staller is not None:
                staller.finish()
            if process.poll() is None:
                process.kill()
        stderr = lines.text()
        assert process.returncode == 3, stderr
        deadline = time.monotonic() + 5.0  # the torque-off SYNC WRITE has no reply: the emulator takes it soon after
        while any(bus.torque_on(k + 1) for k in range(18) if k + 1 != UNPLUGGED) and time.monotonic() < deadline:
            time.sleep(0.05)
        torque = [bus.torque_on(k + 1) for k in range(18) if k + 1 != UNPLUGGED]
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
        bus.stop()
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["fault"].startswith("no reply from BR_femur in 3 consecutive cycles"), summary["fault"]
    assert not any(torque)
    events = [json.loads(line) for line in (tmp_path / "run" / "events.log").read_text().splitlines()]
    assert [e["event"] for e in events].count("fault") == 1  # the unplugging's, none before
    stalls = len(staller.stalls) if staller else 0
    print(f"\n{model}: {summary['cycles']} cycles at {1 / FAMILIES[model]:.0f} Hz, {stalls} stalls of run-hw "
          f"({STALL_S[0] * 1e3:.0f}–{STALL_S[1] * 1e3:.0f} ms), {len(hogs)} hogs; read retries "
          f"{summary['read_retries']}, bridged cycles {summary['bridged_cycles'] - 2} before the unplugging (reads "
          f"{summary['bridged_reads'] - 2 * 14}), overruns {summary['overruns']}, faults before the unplugging 0; "
          f"unplugged BR_femur: fault after {detected:.2f} s (wall, the shut-down included)")
