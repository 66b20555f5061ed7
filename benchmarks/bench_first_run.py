"""The first ``shc simulate`` after an install against the second, with and without ``shc warmup`` (issue 26).

A fresh install has an empty numba cache: each repeat points ``NUMBA_CACHE_DIR`` at a new empty folder (as a new
clone's ``__pycache__``), then times, each in a fresh process:

* ``cold``: ``shc simulate --duration 3`` on the empty cache (what a first command paid before the set-up ran
  ``shc warmup``), then the same command again (``warm``);
* ``warmup``: ``shc warmup`` on a second empty cache, then ``first`` and ``second`` simulate after it, and
  ``workspace`` (``shc workspace bullet``) after them.

Run:  .venv/bin/python benchmarks/bench_first_run.py [--repeats 3]

Prints the median of each [s] and the same-run ratios first/second (goal ≤ 1.5) and cold/warm.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SHC = [sys.executable, "-m", "shc_cli.cli"]


def timed(args: list[str], cache: Path) -> float:
    """Wall time [s] of ``shc ARGS`` in a fresh process with numba's cache in ``cache``."""
    started = time.perf_counter()
    subprocess.run([*SHC, *args], check=True, capture_output=True, env={**os.environ, "NUMBA_CACHE_DIR": str(cache)})
    return time.perf_counter() - started


def simulate(out: Path) -> list[str]:
    """The arguments of the timed simulation (the default robot and engine, 3 s after start-up)."""
    return ["simulate", "--duration", "3", "--no-plots", "--out", str(out)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    repeats = parser.parse_args().repeats
    times: dict[str, list[float]] = {k: [] for k in ("cold", "warm", "warmup", "first", "second", "workspace")}
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as folder:
            root = Path(folder)

            times["cold"].append(timed(simulate(root / "cold"), root / "a"))
            times["warm"].append(timed(simulate(root / "warm"), root / "a"))
            times["warmup"].append(timed(["warmup"], root / "b"))
            times["first"].append(timed(simulate(root / "first"), root / "b"))
            times["second"].append(timed(simulate(root / "second"), root / "b"))
            times["workspace"].append(timed(["workspace", "bullet"], root / "b"))
    median = {k: statistics.median(v) for k, v in times.items()}
    for name, value in median.items():
        print(f"{name:10s} median {value:6.2f} s  ({', '.join(f'{t:.2f}' for t in times[name])})")
    ratios = [f / s for f, s in zip(times["first"], times["second"], strict=True)]
    colds = [c / w for c, w in zip(times["cold"], times["warm"], strict=True)]
    print(f"first/second after warmup: median {statistics.median(ratios):.2f} (goal <= 1.5); "
          f"cold/warm without it: median {statistics.median(colds):.2f}")


if __name__ == "__main__":
    main()
