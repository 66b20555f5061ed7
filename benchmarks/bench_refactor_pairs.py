"""Issue 25: controller step and simulate loop, before and after the domain-layer refactor, in same-run pairs.

Run:  .venv/bin/python benchmarks/bench_refactor_pairs.py --before /path/to/before-checkout
          [--after .] [--controller-pairs 7] [--simulate-pairs 3] [--duration 5] [--robot FILE]

The machine these figures come from is shared (2 cores, other jobs running): its speed drifts by tens of per
cent within minutes. So every figure is taken in pairs, one measurement of each tree right after the other
(the order alternating from pair to pair), and the verdict is the median of the paired after ÷ before ratios,
which the drift cancels out of, not a comparison of absolute numbers taken at different times.

Both trees run the same robot file (``--robot``; by default the before tree's ``robots/bullet.toml``, OpenSHC's
Bullet, arrangement B — the default robot changed between the two trees, and a different robot is different work).
Each measurement is a fresh subprocess of this interpreter with ``PYTHONPATH`` and the working directory set to
the tree measured, so each imports its own ``shc_cli``:

- controller: the code of ``benchmarks/bench_controller.py`` (that robot, tripod, full throttle; direct start-up,
  400 steps to steady speed, then ``--rounds`` × ``--steps`` steps each timed with ``perf_counter``): the median
  of the round medians [µs].
- simulate: ``shc simulate ROBOT --engine E --duration D --no-plots`` (the robot's gait, the engine named
  explicitly since the default may change) on ``pybullet`` and ``mujoco``: ``running_wall_time_s`` of the
  summary, the wall time of the simulation loop since the robot started walking [s]; the simulated time and
  distance of both trees are printed beside it to show both ran the same walk.

Both trees compile their numba kernels on first use: one untimed warm-up of each (controller and both engines)
runs first.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CONTROLLER = """
import json, statistics, sys, time
import shc_cli
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.spec.loading import load_gait, load_robot
steps, rounds = int(sys.argv[1]), int(sys.argv[2])
controller = Controller(load_robot(sys.argv[3]).robot, load_gait("tripod").gait)
while controller.state != RobotState.RUNNING:
    controller.step(Command(state_request=RobotState.RUNNING))
command = Command(velocity=(1.0, 0.0, 0.0))
for _ in range(400):
    controller.step(command)
medians = []
for _ in range(rounds):
    samples = []
    for _ in range(steps):
        started = time.perf_counter()
        controller.step(command)
        samples.append(time.perf_counter() - started)
    medians.append(statistics.median(samples))
print(json.dumps({"median_us": statistics.median(medians) * 1e6, "module": shc_cli.__file__}))
"""
"""The timed code of benchmarks/bench_controller.py, run inside the tree measured."""


def environment(tree: Path) -> dict[str, str]:
    """This process's environment with ``tree`` first on the import path."""
    return {**os.environ, "PYTHONPATH": str(tree)}


def controller_step(tree: Path, steps: int, rounds: int, robot: Path) -> float:
    """Median of the round medians of one controller step of ``robot`` in ``tree`` [µs]."""
    done = subprocess.run([sys.executable, "-c", CONTROLLER, str(steps), str(rounds), str(robot)], cwd=tree,
                          env=environment(tree), capture_output=True, text=True, check=True)
    result = json.loads(done.stdout.strip().splitlines()[-1])
    if not str(result["module"]).startswith(str(tree)):
        raise SystemExit(f"{tree}: imported shc_cli from {result['module']}, not from the tree")
    return float(result["median_us"])


def simulate(tree: Path, robot: Path, engine: str, duration: float, out: Path) -> dict[str, object]:
    """One ``shc simulate`` run of ``robot`` in ``tree``; returns its summary."""
    subprocess.run([sys.executable, "-m", "shc_cli.cli", "simulate", str(robot), "--engine", engine, "--duration",
                    f"{duration:g}", "--no-plots", "--out", str(out)], cwd=tree, env=environment(tree),
                   capture_output=True, text=True, check=True)
    summary: dict[str, object] = json.loads((out / "summary.json").read_text())
    return summary


def commit(tree: Path) -> str:
    return subprocess.run(["git", "-C", str(tree), "log", "-1", "--format=%h"], capture_output=True, text=True,
                          check=False).stdout.strip() or "?"


def uptime() -> str:
    return subprocess.run(["uptime"], capture_output=True, text=True, check=False).stdout.strip()


def report(name: str, unit: str, pairs: list[tuple[float, float]]) -> None:
    """Print the per-pair figures, the medians and the median after ÷ before ratio."""
    ratios = [after / before for before, after in pairs]
    print(f"{name}: before {', '.join(f'{b:.{unit}}' for b, _ in pairs)} (median "
          f"{statistics.median(b for b, _ in pairs):.{unit}}); after {', '.join(f'{a:.{unit}}' for _, a in pairs)} "
          f"(median {statistics.median(a for _, a in pairs):.{unit}}); after ÷ before per pair "
          f"{', '.join(f'{r:.3f}' for r in ratios)} → median {statistics.median(ratios):.3f}", flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, required=True, help="checkout of the tree before the refactor")
    parser.add_argument("--after", type=Path, default=ROOT, help="tree after the refactor (default: this one)")
    parser.add_argument("--controller-pairs", type=int, default=7)
    parser.add_argument("--steps", type=int, default=2000, help="timed controller steps per round")
    parser.add_argument("--rounds", type=int, default=5, help="controller rounds per measurement")
    parser.add_argument("--simulate-pairs", type=int, default=3, help="pairs per engine")
    parser.add_argument("--duration", type=float, default=5.0, help="simulate --duration [s] of walking")
    parser.add_argument("--robot", type=Path, help="robot file both trees run (default: the before tree's "
                        "robots/bullet.toml, OpenSHC's Bullet, which is robots/bullet_openshc.toml after)")
    args = parser.parse_args()
    trees = {"before": args.before.resolve(), "after": args.after.resolve()}
    robot = (args.robot or trees["before"] / "robots" / "bullet.toml").resolve()
    print(f"before: {trees['before']} ({commit(trees['before'])}); after: {trees['after']} "
          f"({commit(trees['after'])}); robot file {robot}; python {sys.version.split()[0]}")
    print(f"load before: {uptime()}", flush=True)
    engines = ("pybullet", "mujoco")
    with tempfile.TemporaryDirectory() as folder:
        for label, tree in trees.items():  # numba compiles (or loads its cache) on first use: not timed
            controller_step(tree, 100, 1, robot)
            for engine in engines:
                simulate(tree, robot, engine, 1.0, Path(folder) / f"warm-{label}-{engine}")
        print("warmed up", flush=True)

        controller: list[tuple[float, float]] = []
        for pair in range(args.controller_pairs):
            order = ("before", "after") if pair % 2 == 0 else ("after", "before")
            got = {label: controller_step(trees[label], args.steps, args.rounds, robot) for label in order}
            controller.append((got["before"], got["after"]))
            print(f"  controller pair {pair}: before {got['before']:.1f} µs, after {got['after']:.1f} µs "
                  f"(ran {order[0]} first)", flush=True)

        loops: dict[str, list[tuple[float, float]]] = {engine: [] for engine in engines}
        for pair in range(args.simulate_pairs):
            for engine in engines:
                order = ("before", "after") if pair % 2 == 0 else ("after", "before")
                summaries = {label: simulate(trees[label], robot, engine, args.duration,
                                             Path(folder) / f"{label}-{engine}-{pair}") for label in order}
                wall = {label: float(s["running_wall_time_s"]) for label, s in summaries.items()}  # type: ignore[arg-type]
                loops[engine].append((wall["before"], wall["after"]))
                same = ", ".join(f"{label} {float(s['sim_time_s']):.2f} s simulated, "  # type: ignore[arg-type]
                                 f"{float(s['distance_m']):.4f} m" for label, s in summaries.items())  # type: ignore[arg-type]
                print(f"  simulate {engine:8s} pair {pair}: loop before {wall['before']:.2f} s, after "
                      f"{wall['after']:.2f} s (ran {order[0]} first; {same})", flush=True)
    print(f"load after:  {uptime()}")
    report(f"controller step [µs] ({args.rounds} × {args.steps} steps per measurement)", "1f", controller)
    for engine in engines:
        report(f"simulate --engine {engine} --duration {args.duration:g}, running_wall_time_s [s]", "2f",
               loops[engine])


if __name__ == "__main__":
    main()
