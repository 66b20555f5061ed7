"""Export of a run to a ROS bag: reading the run and writing each format, in one process.

Run:  .venv/bin/python benchmarks/bench_export.py RUN_DIR [--repeats 3]

RUN_DIR is a ``shc simulate`` run, e.g. the 80 s one of docs/performance.md
(``shc simulate --duration 75 --no-plots --out runs/long80``: 5 s start-up + 75 s at 100 Hz = 8,002 cycles).
Prints the median of each step [s]: reading the run directory, then writing mcap, sqlite3 and ros1.
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import tempfile
import time
from pathlib import Path

from shc_cli.interop.bag import export_bag
from shc_cli.record.runread import read_run


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    times: dict[str, list[float]] = {"read": [], "mcap": [], "sqlite3": [], "ros1": []}
    with tempfile.TemporaryDirectory() as directory:
        for repeat in range(args.repeats):
            started = time.perf_counter()
            log = read_run(args.run)
            times["read"].append(time.perf_counter() - started)
            for fmt in ("mcap", "sqlite3", "ros1"):
                out = Path(directory) / f"{fmt}{repeat}"
                started = time.perf_counter()
                export_bag(log, out, fmt)
                times[fmt].append(time.perf_counter() - started)
                shutil.rmtree(out) if out.is_dir() else out.unlink()
    print(f"{len(log.t)} cycles: " + ", ".join(f"{k} {statistics.median(v):.2f} s" for k, v in times.items()))


if __name__ == "__main__":
    main()
