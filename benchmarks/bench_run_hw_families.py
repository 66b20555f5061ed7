"""Cycle times of ``shc run-hw`` on 18 emulated servos of each family (the emulator in its own process, keeping the
1 Mbaud wire's time line: shc_cli/hardware/emulator_process.py), and the time one state read takes.

    .venv/bin/python benchmarks/bench_run_hw_families.py [--duration 60] [--models AX-12A MX-64(1.0) STS3215]

For each model: ``run-hw`` on the hexapod of tests/test_run_hw_families.py (openshc_default with 18 servos on one
bus) walking ``--velocity 1,0,0`` for ``--duration`` seconds at the model's period (100 Hz; AX-12A, read one servo
at a time, 25 Hz), then p50 / p99 / max of ``timing.csv``'s cycle time [ms] (read, controller and goal write),
the overruns, and the fastest and median of 50 state reads [ms] on the same bus (``ServoBus.read_state``). With
``--buses 3`` the 18 servos are split over three buses (3 emulators): the per-servo reads interleave.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from shc_cli.hardware.emulator_process import EmulatorProcess
from tests.test_run_hw_families import JOINTS, _robot

PERIODS = {"AX-12A": 0.04, "AX-18A": 0.04, "MX-64(1.0)": 0.01, "MX-106(1.0)": 0.01, "STS3215": 0.01}


def _reads(robot: Path, ports: list[str], count: int = 50) -> tuple[float, float]:
    from shc_cli.hardware.buses import servo_bus
    from shc_cli.spec.loading import load_robot

    loaded = load_robot(str(robot)).robot
    assert loaded is not None
    bus = servo_bus(loaded, ports)
    with bus:
        assert not bus.check()
        times = []
        for _ in range(count):
            began = time.perf_counter()
            bus.read_state()
            times.append(time.perf_counter() - began)
    return min(times) * 1e3, float(np.median(times)) * 1e3


def run(model: str, duration: float, buses: int, folder: Path, period: float | None) -> dict[str, Any]:
    groups = [list(range(1 + 18 // buses * b, 1 + 18 // buses * (b + 1))) for b in range(buses)]
    with ExitStack() as stack:
        ports = [stack.enter_context(EmulatorProcess({i: model for i in ids}, wire_time=True)).port for ids in groups]
        return _measure(model, duration, buses, folder, period, ports)


def _measure(model: str, duration: float, buses: int, folder: Path, period: float | None,
             ports: list[str]) -> dict[str, Any]:
    """The run and the reads on the served ``ports`` (bus 0 first)."""
    dt = period or PERIODS[model]
    robot = _robot(folder, model, period=dt)
    if buses > 1:
        text = robot.read_text()
        for k, key in enumerate(JOINTS):
            text = text.replace(f"{key} = {{ id = {k + 1}", f"{key} = {{ id = {k + 1}, bus = {k // (18 // buses)}")
        robot.write_text(text)
    fastest, median = _reads(robot, ports)
    out = folder / f"run-{model}-{buses}"
    port_options = [a for p in ports for a in ("--port", p)]
    command = [sys.executable, "-m", "shc_cli.cli", "run-hw", str(robot), *port_options,
               "--velocity", "1,0,0", "--duration", str(duration), "--stop-state", "running", "--out", str(out)]
    result = subprocess.run(command, capture_output=True, text=True, timeout=duration * 10 + 300)
    if result.returncode != 0:
        return {"model": model, "error": result.stderr.strip()}
    summary = json.loads((out / "summary.json").read_text())
    times = np.loadtxt(out / "timing.csv", delimiter=",", skiprows=1, usecols=2)
    return {"model": model, "buses": buses, "period_ms": dt * 1e3, "cycles": summary["cycles"],
            "p50_ms": round(float(np.percentile(times, 50)), 2),
            "p99_ms": round(float(np.percentile(times, 99)), 2),
            "max_ms": round(float(times.max()), 2), "overruns": summary["overruns"],
            "read_fastest_ms": round(fastest, 2), "read_median_ms": round(median, 2),
            "wire_time_ms": round(summary["wire_time_ms"], 2)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--models", nargs="+", default=["AX-12A", "MX-64(1.0)", "STS3215"])
    parser.add_argument("--buses", type=int, default=1, choices=(1, 2, 3))
    parser.add_argument("--period", type=float, default=None, help="control period [s] instead of the model's")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        for model in args.models:
            print(json.dumps(run(model, args.duration, args.buses, Path(folder), args.period)), flush=True)


if __name__ == "__main__":
    main()
