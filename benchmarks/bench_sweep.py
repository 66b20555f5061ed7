"""Wall time of the 160-run paper sweep on MuJoCo with 2 workers (issue 26: ≤ 100 s).

``sweeps/bullet_cot.toml`` is copied with its engine set to MuJoCo (``engine = "mujoco"`` in ``[fixed]``, replacing
any engine the file chooses: ``--engine`` only applies to runs whose file does not choose one) and run as
``shc sweep COPY --workers 2 --out DIR``. Prints the wall time, the CPU time of the command and its workers (user +
system, children included: the wall time two idle cores would need is about half of it). Python's bytecode cache
is on, as in a user's install; a 2-run sweep fills the caches first.

Run:  .venv/bin/python benchmarks/bench_sweep.py [--workers 2] [--file sweeps/bullet_cot.toml]
"""

from __future__ import annotations

import argparse
import csv
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]


def mujoco_copy(source: Path, target: Path, keep: int | None = None) -> Path:
    """``source`` with ``engine = "mujoco"`` in ``[fixed]`` (any other engine line dropped); ``keep``: only the
    first ``keep`` step frequencies and one stride (a short warm-up sweep)."""
    text = re.sub(r'(?m)^\s*"?engine"?\s*=.*\n', "", source.read_text())
    if keep is not None:
        text = re.sub(r'(?m)^("walker.step_frequency"\s*=\s*\[)([^\]]*)\]',
                      lambda m: m.group(1) + ", ".join(m.group(2).split(",")[:keep]) + "]", text)
        text = re.sub(r"(?m)^(stride_percent\s*=\s*\[)([^\]]*)\]",
                      lambda m: m.group(1) + m.group(2).split(",")[0] + "]", text)
        text = re.sub(r'(?m)^(robot\s*=\s*\[)([^\]]*)\]', lambda m: m.group(1) + m.group(2).split(",")[0] + "]", text)
        text = re.sub(r'(?m)^(gait\s*=\s*\[)([^\]]*)\]', lambda m: m.group(1) + m.group(2).split(",")[0] + "]", text)
    text = text.replace("[fixed]\n", '[fixed]\nengine = "mujoco"\n', 1)
    target.write_text(text)
    return target


def run(sweep: Path, out: Path, workers: int) -> tuple[float, float]:
    """(wall s, CPU s of the command and its workers)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    before = os.times()
    started = time.perf_counter()
    subprocess.run([sys.executable, "-m", "shc_cli.cli", "sweep", str(sweep), "--workers", str(workers), "--out",
                    str(out)], check=True, env=env, cwd=out.parent, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - started
    after = os.times()
    return wall, (after.children_user - before.children_user) + (after.children_system - before.children_system)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--file", type=Path, default=HERE / "sweeps" / "bullet_cot.toml")
    options = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        base = Path(folder)
        run(mujoco_copy(options.file, base / "warm.toml", keep=2), base / "warm", options.workers)
        sweep = mujoco_copy(options.file, base / "sweep.toml")
        load = os.getloadavg()[0]
        wall, cpu = run(sweep, base / "out", options.workers)
        with (base / "out" / "results.csv").open() as handle:
            rows = list(csv.DictReader(handle))
    print(f"{len(rows)} runs, {options.workers} workers, MuJoCo: {wall:.1f} s wall (goal ≤ 100 s), "
          f"{cpu:.1f} s CPU (÷ {options.workers} = {cpu / options.workers:.1f} s), load average {load:.1f} before, "
          f"{os.getloadavg()[0]:.1f} after")


if __name__ == "__main__":
    main()
