"""The cost of ``--live`` on the simulation loop: same-run pairs of ``shc simulate`` without and with a Foxglove
client attached (npm's @foxglove/ws-protocol under Node, tests/live_client), and ``--realtime``'s tracking of the
wall clock.

    .venv/bin/python benchmarks/bench_live.py [--duration 20] [--pairs 3]

Prints, per pair, the loop's wall time after RUNNING (summary ``running_wall_time_s``) without and with the stream,
their medians and the median ratio; then one ``--realtime --live`` run of the same length: simulated over wall time.
Installs the client's npm packages (``npm ci`` in tests/live_client) when they are missing.
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

ROOT = Path(__file__).parents[1]
SHC = [sys.executable, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]


def run(duration: float, folder: Path, live: bool, realtime: bool = False) -> dict[str, float]:
    args = [*SHC, "simulate", "--engine", "mujoco", "--duration", str(duration), "--no-plots", "--out", str(folder)]
    if live:
        args += ["--live", "--live-port", "0"]
    if realtime:
        args += ["--realtime"]
    sim = subprocess.Popen(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    client = None
    if live:
        assert sim.stderr is not None
        for line in sim.stderr:
            if "live: ws://" in line:
                url = line.split("live: ", 1)[1].split()[0]
                client = subprocess.Popen(["node", str(ROOT / "tests" / "live_client" / "client.mjs"), url,
                                           str(duration * 20 + 60), "/desired_joint_states", "/tf", "/joint_states"],
                                          stdout=subprocess.DEVNULL)
                break
    started = time.perf_counter()
    sim.communicate()
    wall = time.perf_counter() - started
    if client is not None:
        client.wait(timeout=60)
    summary = json.loads((folder / "summary.json").read_text())
    return {"running_wall_time_s": summary["running_wall_time_s"], "sim_time_s": summary["sim_time_s"],
            "wall_s": wall}


def client_ready() -> None:
    """Install the client's npm packages (pinned by its package-lock.json) if they are not there."""
    client = ROOT / "tests" / "live_client"
    if not (client / "node_modules" / "@foxglove" / "ws-protocol").exists():
        subprocess.run(["npm", "ci", "--no-audit", "--no-fund", "--silent"], cwd=client, check=True, timeout=300)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--pairs", type=int, default=3)
    args = parser.parse_args()
    client_ready()
    base = Path(tempfile.mkdtemp(prefix="bench-live-"))
    plain, live, ratios = [], [], []
    for i in range(args.pairs):
        a = run(args.duration, base / f"plain{i}", live=False)["running_wall_time_s"]
        b = run(args.duration, base / f"live{i}", live=True)["running_wall_time_s"]
        plain.append(a)
        live.append(b)
        ratios.append(b / a)
        print(f"pair {i}: loop {a:.2f} s without, {b:.2f} s with a live client (×{b / a:.2f})", flush=True)
    print(f"median: {statistics.median(plain):.2f} s without, {statistics.median(live):.2f} s with; "
          f"ratio ×{statistics.median(ratios):.2f}")
    real = run(args.duration, base / "realtime", live=True, realtime=True)
    print(f"--realtime --live: {real['sim_time_s']:.2f} s simulated in {real['wall_s']:.2f} s of wall time "
          "(start-up and summary included)")


if __name__ == "__main__":
    main()
