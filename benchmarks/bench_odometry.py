"""Leg-odometry drift on MuJoCo: one ``shc simulate`` per setting, then ``shc analyze --json`` (docs/odometry.md).

    .venv/bin/python benchmarks/bench_odometry.py            # the acceptance set and the gait × speed sweep
    .venv/bin/python benchmarks/bench_odometry.py --quick    # the acceptance walk only
    .venv/bin/python benchmarks/bench_odometry.py --part sweep   # the gait × speed sweep only

Prints a Markdown table: robot, gait, terrain, velocity input, duration, distance walked, odometry drift [% of the
distance] and heading error [deg] at the end. Each run is 20 s of walking after start-up (``--duration``).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

SHC = str(Path(sys.executable).parent / "shc")

ACCEPTANCE = [
    ("bullet", "tripod", "flat", "1,0,0.3"),
    ("bullet", "tripod", "flat", "1,0,0"),
    ("bullet", "tripod", "ramp:10", "1,0,0.3"),
    ("bullet", "tripod", "blocks", "1,0,0.3"),
    ("bullet_mammalian", "bipod", "flat", "1,0,0.3"),
    ("quadruped", "quad_wave", "flat", "1,0,0.3"),
]
"""(robot, gait, terrain, velocity input) of the acceptance runs."""
SWEEP = [("bullet", gait, "flat", velocity) for gait in ("tripod", "ripple", "wave", "amble")
         for velocity in ("0.5,0,0.15", "1,0,0.3")]
"""The gait × speed sweep: half and full throttle, each with a turn of 0.3 × its linear throttle."""


def measure(robot: str, gait: str, terrain: str, velocity: str, duration: float, folder: Path) -> dict[str, object]:
    """One simulate run and its analysis: the row of the table."""
    out = folder / f"{robot}-{gait}-{terrain.replace(':', '')}-{velocity.replace(',', '_')}"
    subprocess.run([SHC, "simulate", robot, "--gait", gait, "--terrain", terrain, "--velocity", velocity,
                    "--duration", str(duration), "--no-plots", "--out", str(out)], check=True, capture_output=True)
    result = json.loads(subprocess.run([SHC, "analyze", str(out), "--json"], check=True, capture_output=True,
                                       text=True).stdout)
    walked = result["path_speed_mps"] * result["window_s"]
    return {"robot": robot, "gait": gait, "terrain": terrain, "velocity": velocity, "walked_m": walked,
            "drift_percent": result["odometry_drift_percent"],
            "heading_error_deg": result["odometry_heading_error_deg"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the acceptance walk only")
    parser.add_argument("--part", choices=("all", "acceptance", "sweep"), default="all", help="which settings")
    parser.add_argument("--duration", type=float, default=20.0, help="seconds of walking per run")
    args = parser.parse_args()
    parts = {"all": ACCEPTANCE + SWEEP, "acceptance": ACCEPTANCE, "sweep": SWEEP}
    settings = ACCEPTANCE[:1] if args.quick else list(dict.fromkeys(parts[args.part]))  # each setting once
    print("| robot | gait | terrain | velocity | walked m | drift % | heading ° |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for setting in settings:
            row = measure(*setting, args.duration, Path(folder))
            drift = row["drift_percent"]
            print(f"| {row['robot']} | {row['gait']} | {row['terrain']} | {row['velocity']} | {row['walked_m']:.2f} | "
                  f"{'–' if drift is None else f'{drift:.2f}'} | {row['heading_error_deg']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
