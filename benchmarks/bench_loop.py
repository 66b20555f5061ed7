"""Real-time factors of the default walk in MuJoCo (issue 26): the loop and the whole command.

Each repeat runs ``shc simulate --engine mujoco --duration 60 --no-plots`` in a fresh process (kernels already
cached) and reads its ``summary.json``: the loop's factor is the analysed (RUNNING) time over its wall time
(``running_wall_time_s``; goal ≥ 50×), the physics' share is ``running_physics_time_s`` over it (``mj_step``
alone), and the command's factor is the 60 s walked over the process's whole wall time (imports, model, start-up,
log and summary; goal ≥ 25×).

Run:  .venv/bin/python benchmarks/bench_loop.py [--repeats 5] [--duration 60] [ROBOT]

Prints the medians and the same-run ratio loop wall / mj_step wall.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SHC = [sys.executable, "-m", "shc_cli.cli"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default="bullet")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--duration", type=float, default=60.0)
    options = parser.parse_args()
    loop, command, physics_share = [], [], []
    with tempfile.TemporaryDirectory() as folder:
        for repeat in range(options.repeats):
            out = Path(folder) / f"walk{repeat}"
            started = time.perf_counter()
            subprocess.run([*SHC, "simulate", options.robot, "--engine", "mujoco", "--duration",
                            str(options.duration), "--no-plots", "--out", str(out)], check=True, capture_output=True)
            wall = time.perf_counter() - started
            summary = json.loads((out / "summary.json").read_text())
            loop.append(summary["analysed_time_s"] / summary["running_wall_time_s"])
            physics_share.append(summary["running_wall_time_s"] / summary["running_physics_time_s"])
            command.append(options.duration / wall)
    print(f"loop: median {statistics.median(loop):.1f}x real time ({', '.join(f'{x:.1f}' for x in loop)})")
    print(f"whole command: median {statistics.median(command):.1f}x real time "
          f"({', '.join(f'{x:.1f}' for x in command)})")
    print(f"loop wall / mj_step wall: median {statistics.median(physics_share):.2f}")


if __name__ == "__main__":
    main()
