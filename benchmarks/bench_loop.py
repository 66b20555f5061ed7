"""Real-time factors of the default walk in MuJoCo (issue 26): the simulation loop and the whole command.

Each repeat runs ``shc simulate --duration 60 --out DIR`` (the default robot, engine and servo model, plots on) in
a fresh process and reads its ``summary.json``:

* **loop** — the analysed (RUNNING) simulated time over its wall time (``running_wall_time_s``; goal ≥ 50×);
* **loop ÷ mj_step** — ``running_wall_time_s`` over ``running_physics_time_s`` (MuJoCo's ``mj_step`` alone, timed
  around each C call inside the compiled control period, :mod:`shc_cli.backends.mujoco_.substeps`; before it, around
  each call of the Python binding's ``mj_step``, which also counted the binding's ≈ 0.55 µs a call, ≈ 3 %): the
  loop's overhead as a ratio that load changes far less than the factors themselves;
* **whole command** — the 60 s walked over the process's wall time: imports, robot checks, model, start-up, log,
  summary and plots (goal ≥ 25×), and over its CPU time (user + system, ``os.wait4``), which is what it would take on
  an idle core.

Python's bytecode cache is on for the runs (``PYTHONDONTWRITEBYTECODE`` removed: a user's install writes ``.pyc``
files on the first run) and one untimed run per source tree fills it and numba's cache first.

With ``--compare TREE`` (another checkout of shc, e.g. ``git worktree add /tmp/before main~3``) the runs alternate
between that tree and this one (``PYTHONPATH``), and the same-run ratios are printed: this is how a change is
measured on a loaded machine. With ``--with "FLAGS"`` the runs alternate between plain ``shc simulate`` and the
same with FLAGS (e.g. ``--with "--perception rays"``: the depth sensor's cost in the loop, issue 40).

Run:  .venv/bin/python benchmarks/bench_loop.py [--repeats 5] [--duration 60] [--compare TREE | --with FLAGS] [ROBOT]
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]


@dataclass
class Figures:
    """One source tree's runs."""

    tree: Path
    extra: list[str] = field(default_factory=list)
    loop: list[float] = field(default_factory=list)
    overhead: list[float] = field(default_factory=list)
    command: list[float] = field(default_factory=list)
    command_cpu: list[float] = field(default_factory=list)


def run_once(tree: Path, out: Path, robot: str | None, duration: float,
             extra: list[str] | None = None) -> tuple[float, float, dict[str, float]]:
    """One ``shc simulate`` of ``tree``: (wall s, CPU s, summary)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = str(tree)
    command = [sys.executable, "-m", "shc_cli.cli", "simulate", *([robot] if robot else []), "--duration",
               str(duration), "--out", str(out), *(extra or [])]
    started = time.perf_counter()
    process = subprocess.Popen(command, env=env, cwd=out.parent, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(process.pid, 0)
    wall = time.perf_counter() - started
    if os.waitstatus_to_exitcode(status) != 0:
        raise SystemExit(f"{' '.join(command)} failed: {process.stderr.read().decode() if process.stderr else ''}")
    return wall, usage.ru_utime + usage.ru_stime, json.loads((out / "summary.json").read_text())


def median(values: list[float]) -> str:
    return f"{statistics.median(values):.2f} ({', '.join(f'{v:.2f}' for v in values)})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default=None, help="robot (default: shc's default robot)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--duration", type=float, default=60.0)
    parser.add_argument("--compare", type=Path, default=None, help="another shc source tree, run alternately")
    parser.add_argument("--with", dest="extra", default=None, help="simulate flags, run alternately with plain runs")
    options = parser.parse_args()
    trees = [Figures(options.compare.resolve()), Figures(HERE)] if options.compare else [Figures(HERE)]
    if options.extra:
        trees = [Figures(HERE), Figures(HERE, shlex.split(options.extra))]
    with tempfile.TemporaryDirectory() as folder:
        for number, figures in enumerate(trees):  # untimed: bytecode and numba caches
            run_once(figures.tree, Path(folder) / f"warm{number}", options.robot, 2.0, figures.extra)
        for repeat in range(options.repeats):
            for number, figures in enumerate(trees):
                out = Path(folder) / f"walk{repeat}-{number}"
                wall, cpu, summary = run_once(figures.tree, out, options.robot, options.duration, figures.extra)
                figures.loop.append(summary["analysed_time_s"] / summary["running_wall_time_s"])
                figures.overhead.append(summary["running_wall_time_s"] / summary["running_physics_time_s"])
                figures.command.append(options.duration / wall)
                figures.command_cpu.append(options.duration / cpu)
    print(f"load average {os.getloadavg()[0]:.1f} at the end; {options.repeats} runs per tree, "
          f"{options.duration:g} s walks")
    for figures in trees:
        print(f"{figures.tree}{' ' + ' '.join(figures.extra) if figures.extra else ''}:")
        print(f"  loop: median {median(figures.loop)} x real time")
        print(f"  loop wall / mj_step wall: median {median(figures.overhead)}")
        print(f"  whole command: median {median(figures.command)} x real time on the wall clock, "
              f"{median(figures.command_cpu)} x on its CPU time")
    if len(trees) == 2:
        before, after = trees
        print("same-run speed-ups, this tree over the compared one (pairs in run order):")
        for name, b_values, a_values in (("loop x real time", before.loop, after.loop),
                                         ("loop overhead (wall / mj_step)", after.overhead, before.overhead),
                                         ("whole command on the wall clock", before.command, after.command),
                                         ("whole command on CPU time", before.command_cpu, after.command_cpu)):
            print(f"  {name}: {median([a / b for b, a in zip(b_values, a_values, strict=True)])}")

if __name__ == "__main__":
    main()
