"""``--realtime``: how closely the simulated time tracks the wall clock over a long run (issue 28: within 1 % over
60 s).

    .venv/bin/python benchmarks/bench_realtime.py [--duration 60] [--engine mujoco] [--live]

Runs ``shc simulate --realtime`` (``--live`` adds a Foxglove client, npm's @foxglove/ws-protocol under Node, attached
for the whole run) and reports two measurements of the same run: from outside, the rows of its streamed ``log.csv``
counted by this process against its own clock as they are written (the slope from the first 300 rows to the last);
from inside, the summary's ``realtime_ratio`` (simulated ÷ wall time from the first cycle to the last, start-up
included), the largest lag behind the schedule and the cycle periods. The load average before and after is printed:
the machine's other work decides how often a cycle is late.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).parents[1]
SHC = [sys.executable, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=60.0, help="seconds of walking after start-up")
    parser.add_argument("--engine", default="mujoco")
    parser.add_argument("--live", action="store_true", help="also stream it to a Foxglove client")
    args = parser.parse_args()
    run = Path(tempfile.mkdtemp(prefix="bench-realtime-")) / "run"
    log = run.with_name("run.partial") / "log.csv"
    command = [*SHC, "simulate", "--engine", args.engine, "--realtime", "--duration", str(args.duration),
               "--no-plots", "--out", str(run)]
    if args.live:
        sys.path.insert(0, str(ROOT / "benchmarks"))
        from bench_live import client_ready

        client_ready()
        command += ["--live", "--live-port", "0"]
    load_before = os.getloadavg()
    sim = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    client = None
    if args.live:
        assert sim.stderr is not None
        for line in sim.stderr:
            if "live: ws://" in line:
                url = line.split("live: ", 1)[1].split()[0]
                client = subprocess.Popen(["node", str(ROOT / "tests" / "live_client" / "client.mjs"), url,
                                           str(args.duration + 120), "/desired_joint_states", "/tf", "/joint_states"],
                                          stdout=subprocess.DEVNULL)
                break
    samples: list[tuple[float, int]] = []
    while sim.poll() is None:
        if log.exists():
            with log.open("rb") as handle:
                rows = handle.read().count(b"\n") - 1
            if rows >= 300 and (not samples or rows != samples[-1][1]):
                samples.append((time.monotonic(), rows))
        time.sleep(0.05)
    sim.communicate()
    if client is not None:
        client.wait(timeout=60)
    load_after = os.getloadavg()
    summary = json.loads((run / "summary.json").read_text())
    (t0, r0), (t1, r1) = samples[0], samples[-1]
    with (run / "log.csv").open("rb") as handle:
        cycles = handle.read().count(b"\n") - 1
    dt = summary["sim_time_s"] / cycles
    outside = (r1 - r0) * dt / (t1 - t0)
    print(f"shc simulate --engine {args.engine} --realtime --duration {args.duration:g}"
          f"{' --live (client attached)' if args.live else ''}: {cycles} cycles, "
          f"{summary['sim_time_s']:.2f} s simulated")
    print(f"outside: {r1 - r0} rows in {t1 - t0:.3f} s of wall time: simulated ÷ wall = {outside:.5f} "
          f"({100 * (outside - 1):+.3f} %)")
    s = summary
    print(f"inside: realtime_ratio = {s['realtime_ratio']:.5f} ({100 * (s['realtime_ratio'] - 1):+.3f} %), "
          f"lag max {s['realtime_lag_max_ms']:.1f} ms, rate {s['rate_hz']:.3f} Hz, period p50/p99/max "
          f"{s['cycle_time_p50_ms']:.2f}/{s['cycle_time_p99_ms']:.2f}/{s['cycle_time_max_ms']:.1f} ms, "
          f"{s['overruns']} cycles > 1.5 periods, {s['pauses']} pauses")
    print(f"load average (1, 5, 15 min) before {load_before[0]:.1f} {load_before[1]:.1f} {load_before[2]:.1f}, "
          f"after {load_after[0]:.1f} {load_after[1]:.1f} {load_after[2]:.1f}; {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
