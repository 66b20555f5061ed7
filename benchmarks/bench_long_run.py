"""Memory of an open-ended run and its finish on SIGTERM (issue 26, trap 2).

Starts ``shc simulate --engine mujoco --duration 36000 --no-plots`` (10 hours asked for), sends SIGTERM ``--after``
seconds after the run began its log (the imports and the model take seconds more, many on a loaded machine, before
any memory could depend on the duration) and reports the process's peak resident memory (``VmHWM``, read every
0.1 s until the signal) and the finished run directory: ``summary.json`` with ``complete`` false and the rows
logged. Before the fix the commands of all 3.6 million cycles were built first (1.7 GB) and a SIGTERM left
``.partial/`` with only ``robot.toml``.

Run:  .venv/bin/python benchmarks/bench_long_run.py [--after 10] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SHC = [sys.executable, "-m", "shc_cli.cli"]


def peak_mb(pid: int) -> float:
    """Peak resident memory of ``pid`` so far [MB] (Linux)."""
    status = Path(f"/proc/{pid}/status").read_text()
    return int(status.split("VmHWM:")[1].split()[0]) / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--after", type=float, default=10.0)
    parser.add_argument("--repeats", type=int, default=3)
    options = parser.parse_args()
    peaks = []
    with tempfile.TemporaryDirectory() as folder:
        for repeat in range(options.repeats):
            out = Path(folder) / f"long{repeat}"
            process = subprocess.Popen([*SHC, "simulate", "--engine", "mujoco", "--duration", "36000", "--no-plots",
                                        "--out", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            peak, logging_since = 0.0, None
            log = out.with_name(out.name + ".partial") / "log.csv"
            while logging_since is None or time.perf_counter() - logging_since < options.after:
                peak = max(peak, peak_mb(process.pid))
                if logging_since is None and log.exists():
                    logging_since = time.perf_counter()
                time.sleep(0.1)
            process.send_signal(signal.SIGTERM)
            process.wait(timeout=300)
            summary = json.loads((out / "summary.json").read_text())
            rows = (out / "log.csv").read_text().count("\n") - 1
            peaks.append(peak)
            print(f"run {repeat}: peak {peak:.0f} MB; exit {process.returncode}; complete {summary['complete']}, "
                  f"stop_reason {summary['stop_reason']}, {rows} rows ({summary['sim_time_s']:.1f} s simulated)")
    print(f"peak resident memory: median {statistics.median(peaks):.0f} MB (goal <= 400 MB)")


if __name__ == "__main__":
    main()
