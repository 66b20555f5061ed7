"""PyBullet vs MuJoCo: speed of ``shc simulate`` in the same benchmark run, and every robot on every terrain.

Run:  .venv/bin/python benchmarks/bench_engines.py speed [--duration 60] [--repeats 3]
      .venv/bin/python benchmarks/bench_engines.py terrains [--duration 10] [--engine mujoco]

``speed``: ``--repeats`` times, alternating the engines, runs the whole command
``shc simulate --engine E --gait tripod --duration D`` as a subprocess (start-up, imports and plots included)
and prints per engine the median simulated ÷ wall time of the simulation loop (``summary.json``), of the whole
command, simulated ÷ the command's CPU time (what a free core would give: these machines are shared), the mean
speed and whether it fell; then the MuJoCo ÷ PyBullet ratio of the loop figures, pairing the
runs made one after the other, and the load (``uptime``) before and after.

``terrains``: every shipped robot on every terrain (flat, ramp:10, blocks, stairs:0.05,0.3 and a generated
height field of 0–5 cm bumps) for ``--duration`` seconds of walking at throttle 1 with the robot's own gait:
distance, mean speed, fell or not.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SHC = [sys.executable, "-m", "shc_cli.cli"]
ROBOTS = sorted(path.stem for path in (ROOT / "robots").glob("*.toml"))
"""Every shipped robot."""


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()


def simulate(engine: str, duration: float, out: Path,
             extra: list[str] | None = None) -> tuple[dict[str, object], float, float]:
    """One whole ``shc simulate`` command; returns its summary, its wall time and its CPU time [s]."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    started = time.perf_counter()
    subprocess.run([*SHC, "simulate", "--engine", engine, "--gait", "tripod", "--duration", f"{duration:g}",
                    "--out", str(out), *(extra or [])], check=True, cwd=ROOT, capture_output=True)
    wall = time.perf_counter() - started
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return json.loads((out / "summary.json").read_text()), wall, cpu


def speed(duration: float, repeats: int) -> None:
    print(f"load before: {uptime()}")
    figures: dict[str, list[tuple[float, float, float, bool, float]]] = {"pybullet": [], "mujoco": []}
    with tempfile.TemporaryDirectory() as folder:
        for repeat in range(repeats):
            for engine in ("mujoco", "pybullet") if repeat % 2 else ("pybullet", "mujoco"):
                summary, wall, cpu = simulate(engine, duration, Path(folder) / f"{engine}{repeat}")
                simulated = float(summary["sim_time_s"])  # type: ignore[arg-type]
                loop = simulated / float(summary["wall_time_s"])  # type: ignore[arg-type]
                figures[engine].append((loop, simulated / wall, float(summary["mean_speed_mps"]),  # type: ignore[arg-type]
                                        bool(summary["fell"]), simulated / cpu))
                print(f"  {engine:8s} run {repeat}: loop {loop:6.1f}× real time, whole command "
                      f"{figures[engine][-1][1]:5.1f}× (÷ its CPU time {simulated / cpu:5.1f}×), "
                      f"{figures[engine][-1][2]:.4f} m/s, fell {summary['fell']}", flush=True)
    print(f"load after:  {uptime()}")
    for engine, rows in figures.items():
        print(f"{engine:8s} median: loop {statistics.median(r[0] for r in rows):6.1f}× real time, whole command "
              f"{statistics.median(r[1] for r in rows):5.1f}× "
              f"(÷ CPU time {statistics.median(r[4] for r in rows):5.1f}×), "
              f"speed {statistics.median(r[2] for r in rows):.4f} m/s, fell {any(r[3] for r in rows)}")
    ratios = [m[0] / p[0] for m, p in zip(figures["mujoco"], figures["pybullet"], strict=True)]
    print(f"MuJoCo ÷ PyBullet, loop, paired runs: {', '.join(f'{r:.1f}' for r in ratios)} "
          f"(median {statistics.median(ratios):.1f})")


def terrains(duration: float, engine: str) -> None:
    print(f"load before: {uptime()}")
    with tempfile.TemporaryDirectory() as folder:
        field = Path(folder) / "bumps.csv"
        x, y = np.meshgrid(np.arange(120) * 0.05, np.arange(60) * 0.05)
        np.savetxt(field, 0.025 * (1.0 + np.sin(2.1 * x) * np.cos(1.7 * y)), delimiter=",", fmt="%.5f")
        kinds = ["flat", "ramp:10", "blocks", "stairs:0.05,0.3", f"heightfield:{field}"]
        print(f"{'robot':20s}" + "".join(f"{k.split(':')[0] if k.startswith('height') else k:>18s}" for k in kinds))
        for robot in ROBOTS:
            cells = []
            for kind in kinds:
                out = Path(folder) / f"{robot}-{len(cells)}"
                try:
                    subprocess.run([*SHC, "simulate", robot, "--engine", engine, "--terrain", kind, "--duration",
                                    f"{duration:g}", "--no-plots", "--out", str(out)], check=True, cwd=ROOT,
                                   capture_output=True, text=True)
                    summary = json.loads((out / "summary.json").read_text())
                    cells.append(f"{'FELL ' if summary['fell'] else ''}{summary['forward_distance_m']:.2f} m")
                except subprocess.CalledProcessError as error:
                    cells.append("error: " + (error.stderr.strip().splitlines() or ["?"])[-1][:10])
            print(f"{robot:20s}" + "".join(f"{c:>18s}" for c in cells))
    print(f"load after:  {uptime()}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("speed", "terrains"))
    parser.add_argument("--duration", type=float, default=None)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--engine", default="mujoco")
    args = parser.parse_args()
    os.environ.setdefault("CI", "1")  # no progress bars
    if args.what == "speed":
        speed(args.duration or 60.0, args.repeats)
    else:
        terrains(args.duration or 10.0, args.engine)


if __name__ == "__main__":
    main()
