"""Reference runs for refactors that must not change behaviour (issue 25): run, then compare two sets.

    .venv/bin/python benchmarks/reference_runs.py run OUT [--python PY] [--source DIR]
    .venv/bin/python benchmarks/reference_runs.py compare BEFORE AFTER

``run`` writes, under OUT: a plan, a simulation in each engine, a replay of the insectoid recording (``--json``),
the CI smoke sweep and a 4-trial study. ``--source DIR`` runs the ``shc_cli`` of another checkout (e.g. a
``git worktree`` of the commit before the refactor) with the same interpreter. ``compare`` checks every data file
byte for byte (``cmp``) and every ``summary.json`` / JSON output for equal values, leaving out what differs from
run to run (wall times, real-time factors, versions, paths); it prints each difference and exits 1 if any.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

VOLATILE = {"wall_time_s", "loop_wall_time_s", "real_time_factor", "loop_real_time_factor", "versions",
            "started", "finished", "run_dir", "path", "created", "elapsed_s", "physics_time_s",
            "running_physics_time_s", "running_wall_time_s", "trial_wall_s", "sim_wall_s", "runs", "run"}
"""Keys whose values change from run to run (times, versions, paths)."""
SKIP_FILES = {".png", ".mp4", ".gif", ".db", ".log"}
"""Files not compared byte for byte (plots carry timestamps; the study database carries times)."""

RUNS: list[list[str]] = [
    ["plan", "bullet", "--velocity", "0.5,0,0.2", "--duration", "8", "--out", "{out}/plan"],
    ["simulate", "bullet", "--engine", "pybullet", "--duration", "3", "--out", "{out}/simulate_pybullet"],
    ["simulate", "bullet", "--engine", "mujoco", "--duration", "3", "--out", "{out}/simulate_mujoco"],
    ["sweep", "sweeps/ci_smoke.toml", "--workers", "2", "--out", "{out}/sweep"],
    ["optimize", "studies/bullet_flat.toml", "--trials", "4", "--workers", "1", "--out", "{out}/study"],
]
REPLAY = ["replay", "golden/openshc-runs/insectoid", "--robot", "bullet", "--json"]


def run(out: Path, python: str, source: Path | None) -> None:
    """All reference runs into ``out`` (which must not exist)."""
    out.mkdir(parents=True)
    env = dict(os.environ)
    if source is not None:
        env["PYTHONPATH"] = str(source)
    cwd = source or Path.cwd()
    base = [python, "-c", "import sys; from shc_cli.cli import main; sys.argv[0] = 'shc'; main()"]
    for argv in RUNS:
        args = [a.format(out=out.resolve()) for a in argv]
        print("+ shc", " ".join(args), flush=True)
        subprocess.run([*base, *args], cwd=cwd, env=env, check=False)
    print("+ shc", " ".join(REPLAY), flush=True)
    result = subprocess.run([*base, *REPLAY], cwd=cwd, env=env, capture_output=True, text=True, check=False)
    (out / "replay.json").write_text(result.stdout, encoding="utf-8")


def _strip(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _strip(v) for k, v in value.items() if k not in VOLATILE}
    if isinstance(value, list):
        return [_strip(v) for v in value]
    return value


def compare(before: Path, after: Path) -> int:
    """Print every difference between two reference sets; the number of differences."""
    differences = 0
    for old in sorted(p for p in before.rglob("*") if p.is_file()):
        rel = old.relative_to(before)
        new = after / rel
        if old.suffix in SKIP_FILES:
            continue
        if not new.exists():
            print(f"missing: {rel}")
            differences += 1
        elif old.suffix == ".json":
            a, b = (_strip(json.loads(p.read_text(encoding="utf-8") or "null")) for p in (old, new))
            if a != b:
                keys = sorted({*a, *b} if isinstance(a, dict) and isinstance(b, dict) else [])
                changed = [k for k in keys if a.get(k) != b.get(k)] if keys else ["(value)"]
                print(f"differs: {rel}: {', '.join(changed)}")
                differences += 1
        elif old.read_bytes() != new.read_bytes():
            if old.suffix == ".csv" and old.name != "log.csv" and _csv_equal(old, new):
                continue
            if old.suffix == ".toml" and _toml_equal(old, new):
                continue
            print(f"differs: {rel}")
            differences += 1
    print(f"{differences} difference(s)")
    return differences


def _csv_equal(old: Path, new: Path) -> bool:
    """Result tables carry wall times and run paths: equal apart from those columns."""
    import csv

    def rows(path: Path) -> list[dict[str, str]]:
        with path.open(encoding="utf-8", newline="") as handle:
            return [{k: v for k, v in row.items() if k not in VOLATILE and "wall" not in k
                     and k not in ("datetime_start", "datetime_complete", "duration")}
                    for row in csv.DictReader(handle)]

    return rows(old) == rows(new)


def _toml_equal(old: Path, new: Path) -> bool:
    """Robot variants name the robot they extend by absolute path: equal apart from the checkout's folder."""
    import re

    def text(path: Path) -> str:
        return re.sub(r'extends = ".*/robots/', 'extends = "robots/', path.read_text(encoding="utf-8"))

    return text(old) == text(new)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="action", required=True)
    r = sub.add_parser("run")
    r.add_argument("out", type=Path)
    r.add_argument("--python", default=sys.executable)
    r.add_argument("--source", type=Path)
    c = sub.add_parser("compare")
    c.add_argument("before", type=Path)
    c.add_argument("after", type=Path)
    args = parser.parse_args()
    if args.action == "run":
        run(args.out, args.python, args.source)
    else:
        sys.exit(1 if compare(args.before, args.after) else 0)


if __name__ == "__main__":
    main()
