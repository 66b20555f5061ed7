"""Whether two shc source trees write the same outputs, byte for byte: what a speed-up or a refactor must show.

Each command of the suite runs once with each tree's sources (``PYTHONPATH``, from this checkout's directory, so
robots and paths resolve alike) into its own directory; then every table the two wrote is compared byte for byte
(``log.csv``, ``joints.csv``, ``tips.csv``, ``body.csv``, ``path.csv``; ``workspace --json``'s output): the
summary's and the events' wall times differ from run to run and are not compared. The suite: ``simulate
--duration 20`` of six robots, bullet on a 10° ramp and along ``paths/square_2m.csv``, ``plan bullet --duration
20``, and a plan script (gait change, step-frequency changes, cruise, manual posing and its reset, a leg lifted for
manipulation and put back) planned on two robots and simulated on one; ``workspace --json`` planar and volumetric.
Prints one line per file and exits 1 when any differs or a command fails.

Run:  .venv/bin/python benchmarks/same_outputs.py --compare TREE [--out DIR]
"""

from __future__ import annotations

import argparse
import filecmp
import os
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]

SCRIPT = """\
[[step]]
at = 0.0
velocity = [1.0, 0.0, 0.2]
[[step]]
at = 4.0
pose_velocity = [0, 0, 0.5, 0.3, 0, 0.2]
[[step]]
at = 6.0
pose_velocity = [0, 0, 0, 0, 0, 0]
pose_reset = "all"
[[step]]
at = 10.0
gait = "wave"
parameters = { step_frequency = 1.5, swing_height = 0.06 }
cruise = true
[[step]]
at = 16.0
cruise = false
velocity = [0.5, 0.3, 0]
parameters = { step_frequency = 0.8 }
[[step]]
at = 20.0
velocity = [0, 0, 0]
leg_toggle = "AR"
[[step]]
at = 23.0
tip_velocity = { AR = [0, 0, 0.5] }
[[step]]
at = 26.0
tip_velocity = { AR = [0, 0, 0] }
leg_toggle = "AR"
[[step]]
at = 30.0
velocity = [0.6, 0, 0]
"""
"""The plan script of the suite (``--commands``)."""


def suite(script: Path) -> dict[str, list[str]]:
    """The commands: name → ``shc`` arguments (a run directory is added where the command writes one)."""
    runs = {f"simulate_{robot}": ["simulate", robot, "--duration", "20"]
            for robot in ("bullet", "bullet_insectoid_a", "athena", "quadruped", "octopod", "bullet_openshc")}
    runs |= {"simulate_ramp": ["simulate", "--terrain", "ramp:10", "--duration", "20"],
             "simulate_path": ["simulate", "--path", "paths/square_2m.csv", "--duration", "30"],
             "plan_bullet": ["plan", "bullet", "--duration", "20"],
             "plan_script_bullet": ["plan", "bullet", "--commands", str(script), "--duration", "36"],
             "plan_script_insectoid": ["plan", "bullet_insectoid_a", "--commands", str(script), "--duration", "36"],
             "simulate_script": ["simulate", "bullet", "--commands", str(script), "--duration", "36"]}
    for robot in ("bullet", "athena", "octopod"):
        runs[f"workspace_{robot}"] = ["workspace", robot, "--json"]
        runs[f"workspace_{robot}_volumetric"] = ["workspace", robot, "--volumetric", "--json"]
    return runs


def run_all(tree: Path, out: Path, runs: dict[str, list[str]]) -> list[str]:
    """Every command with ``tree``'s sources into ``out``; the names of those that failed."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = str(tree)
    out.mkdir(parents=True)
    failed = []
    for name, arguments in runs.items():
        printing = arguments[0] == "workspace"
        command = [sys.executable, "-m", "shc_cli.cli", *arguments,
                   *([] if printing else ["--out", str(out / name), "--no-plots"])]
        done = subprocess.run(command, env=env, cwd=HERE, capture_output=True, text=True)
        if done.returncode != 0:
            failed.append(f"{name}: {done.stderr.strip().splitlines()[-1:] }")
        elif printing:
            (out / f"{name}.json").write_text(done.stdout)
    return failed


def tables(folder: Path) -> list[Path]:
    """The compared files under ``folder``, relative to it."""
    return sorted(p.relative_to(folder) for p in folder.rglob("*") if p.suffix in (".csv", ".json")
                  and p.name != "summary.json")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--compare", type=Path, required=True, help="the other shc source tree (e.g. main)")
    parser.add_argument("--out", type=Path, default=None, help="keep the outputs here (default: a temporary folder)")
    options = parser.parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        folder = (options.out or Path(temporary)).resolve()
        folder.mkdir(parents=True, exist_ok=True)
        script = folder / "script.toml"
        script.write_text(SCRIPT)
        runs = suite(script)
        other, this = folder / "compared", folder / "this"
        failed = run_all(options.compare.resolve(), other, runs) + run_all(HERE, this, runs)
        different = 0
        for name in sorted(set(tables(other)) | set(tables(this))):
            a, b = other / name, this / name
            same = a.exists() and b.exists() and filecmp.cmp(a, b, shallow=False)
            different += not same
            lines = len(a.read_bytes().splitlines()) if a.exists() else 0
            print(f"{'same' if same else 'DIFFERENT'} {name} ({lines} lines)")
        for text in failed:
            print(f"FAILED {text}")
        print(f"{len(runs)} commands per tree; {different} file(s) differ; {len(failed)} command(s) failed")
    if different or failed:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
