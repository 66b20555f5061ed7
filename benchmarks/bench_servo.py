"""Cost of the servo model in PyBullet: a control period with the stiff position motor against the servo and gearbox
model (``[servo] control = "dynamixel"``: numpy torque law + TORQUE_CONTROL every physics step, rotor links).

Run:  .venv/bin/python benchmarks/bench_servo.py [--periods 400] [--repeats 3]

Builds Bullet insectoid B (the paper's robot) held in the air at 400 Hz, swings every joint sinusoidally (0.2 rad,
1 Hz) for ``--periods`` control periods and prints, per servo model, the median over ``--repeats`` of the wall time
per control period [µs] and of the share of it spent inside ``stepSimulation``, and the same-run ratio.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from shc_cli.backends.engine import EngineOptions
from shc_cli.backends.pybullet_.world import World
from shc_cli.backends.terrain import TerrainSpec
from shc_cli.spec.loading import load_robot


def run(control: str, periods: int) -> tuple[float, float]:
    robot = load_robot("bullet_insectoid_b").robot
    robot = robot.model_copy(update={"servo": robot.servo.model_copy(update={"control": control})})
    base = np.tile([0.0, 0.0, 1.088, -0.765, -1.212], (6, 1))
    world = World(robot, EngineOptions(TerrainSpec(kind="flat"), 4, True), base)
    try:
        started = time.perf_counter()
        for k in range(periods):
            world.command(base + 0.2 * np.sin(2 * np.pi * k * robot.time_delta))
            world.step()
            world.read()
        wall = time.perf_counter() - started
        return wall / periods * 1e6, world.physics_time / wall
    finally:
        world.close()


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--periods", type=int, default=400)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    results: dict[str, list[tuple[float, float]]] = {"position": [], "dynamixel": []}
    for _ in range(args.repeats):
        for control in results:
            results[control].append(run(control, args.periods))
    medians = {c: (statistics.median(r[0] for r in rs), statistics.median(r[1] for r in rs))
               for c, rs in results.items()}
    for control, (period, share) in medians.items():
        print(f"{control:10s} {period:8.0f} µs per control period, {share:.0%} in stepSimulation")
    print(f"ratio dynamixel / position: {medians['dynamixel'][0] / medians['position'][0]:.2f}")


if __name__ == "__main__":
    main()
