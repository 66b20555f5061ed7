"""Cycle time of ``shc run-hw`` on emulated servo buses (each emulator in its own process).

    .venv/bin/python benchmarks/bench_run_hw.py [--repeats 3] [--duration 5]

Runs ``shc run-hw bullet --velocity 1,0,0`` (30 MX-106 at 100 Hz) on one bus and on two buses (right legs on bus 0,
left legs on bus 1), ``--stop-state running``, and prints per run and the median over runs: the cycle time mean
and p99 [ms], overruns, read retries and the computed 1 Mbaud wire time of the busiest bus [ms].
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROWS = {"R": (1, 2, 3), "L": (4, 5, 6)}
"""Bullet's servo ids: 10 × row + joint (1–5); rows 1–3 are the right legs, 4–6 the left."""


def _serve(bus_index: int, ids: list[int], ports: Any, stop: Any) -> None:
    from shc_cli.hardware.emulator import BusEmulator

    with BusEmulator({i: "MX-106" for i in ids}) as bus:
        ports.put((bus_index, bus.port))
        stop.wait()


def _ids(rows: tuple[int, ...]) -> list[int]:
    return [10 * row + joint for row in rows for joint in range(1, 6)]


def _two_bus_robot(folder: Path) -> Path:
    lines = ['extends = "bullet"', 'name = "bullet_two_buses"', "[hardware.servos]"]
    legs = {4: "CL", 5: "BL", 6: "AL"}
    joints = ("coxa", "coxat", "femur", "tibia", "tarsus")
    lines += [f"{legs[row]}_{joint} = {{ id = {10 * row + k + 1}, bus = 1 }}" for row in ROWS["L"]
              for k, joint in enumerate(joints)]
    path = folder / "two_buses.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def run(buses: int, duration: float, folder: Path, index: int) -> dict[str, Any]:
    context = multiprocessing.get_context("spawn")
    ports, stop = context.Queue(), context.Event()
    groups = [_ids(ROWS["R"] + ROWS["L"])] if buses == 1 else [_ids(ROWS["R"]), _ids(ROWS["L"])]
    servers = [context.Process(target=_serve, args=(b, ids, ports, stop), daemon=True) for b, ids in enumerate(groups)]
    for server in servers:
        server.start()
    names = [name for _, name in sorted(ports.get(timeout=30) for _ in servers)]  # bus order
    robot = "bullet" if buses == 1 else str(_two_bus_robot(folder))
    out = folder / f"run-{buses}-{index}"
    command = [sys.executable, "-m", "shc_cli.cli", "run-hw", robot, *[a for n in names for a in ("--port", n)],
               "--velocity", "1,0,0", "--duration", str(duration), "--stop-state", "running", "--out", str(out)]
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=300)
    finally:
        stop.set()
        for server in servers:
            server.join(timeout=10)
    if result.returncode != 0:
        raise SystemExit(result.stderr)
    summary: dict[str, Any] = json.loads((out / "summary.json").read_text())
    return summary


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--duration", type=float, default=5.0)
    args = parser.parse_args()
    keys = ("cycle_time_mean_ms", "cycle_time_p99_ms", "overruns", "cycles", "read_retries", "wire_time_ms")
    with tempfile.TemporaryDirectory() as tmp:
        results: dict[int, list[dict[str, Any]]] = {1: [], 2: []}
        for index in range(args.repeats):
            for buses in (1, 2):  # interleaved: both see the same machine load
                summary = run(buses, args.duration, Path(tmp), index)
                results[buses].append(summary)
                print(f"{buses} bus{'es' if buses > 1 else ''} run {index}: "
                      + ", ".join(f"{k} {summary[k]:.3g}" for k in keys), flush=True)
        for buses, runs in results.items():
            print(f"median, {buses} bus{'es' if buses > 1 else ''}: "
                  + ", ".join(f"{k} {statistics.median(r[k] for r in runs):.3g}" for k in keys))


if __name__ == "__main__":
    main()
