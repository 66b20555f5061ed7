"""One MuJoCo control period (``MujocoWorld.step``: 4 physics steps, the servo law, the means and the power) in the
compiled kernel (:mod:`shc_cli.backends.mujoco_.substeps`) against the Python loop it replaced, in one process.

Two worlds of the robot stand on flat ground; blocks of 500 periods alternate between them (``--blocks`` each) and
the medians per period are printed: the wall time of ``step()``, the time inside ``mj_step`` as the world counts
it (``physics_time``: the C call in the kernel, the binding's call in the Python loop) and their difference, the
Python around MuJoCo. At the end both worlds must hold the same state to the last bit.

Run:  .venv/bin/python benchmarks/bench_mujoco_period.py [ROBOT] [--control pd|position|dynamixel] [--blocks 5]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np


def main() -> None:
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.simulated import open_world
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.spec.loading import load_robot

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default="bullet")
    parser.add_argument("--control", default=None, help="override the robot's [servo] control")
    parser.add_argument("--blocks", type=int, default=5)
    options = parser.parse_args()
    robot = load_robot(options.robot).robot
    assert robot is not None
    if options.control:
        robot = robot.model_copy(update={"servo": robot.servo.model_copy(update={"control": options.control})})
    worlds = {}
    for mode in ("python loop", "compiled"):
        world = open_world(robot, EngineOptions(parse_terrain("flat"), 4, False, engine="mujoco"))
        if mode == "python loop":
            world._pointers = None  # the physics steps from Python, as before the kernel
        worlds[mode] = world
    figures: dict[str, list[tuple[float, float]]] = {mode: [] for mode in worlds}
    periods = 500
    for _ in range(options.blocks):
        for mode, world in worlds.items():
            physics, started = world.physics_time, time.perf_counter()
            for _ in range(periods):
                world.step()
            wall = time.perf_counter() - started
            figures[mode].append((wall / periods * 1e6, (world.physics_time - physics) / periods * 1e6))
    for mode, values in figures.items():
        wall = statistics.median(v[0] for v in values)
        inside = statistics.median(v[1] for v in values)
        print(f"{mode:12s} step {wall:6.1f} µs/period, mj_step {inside:6.1f} µs, around it {wall - inside:5.1f} µs")
    a, b = worlds.values()
    same = np.array_equal(a.data.qpos, b.data.qpos) and np.array_equal(a.read().servo_power, b.read().servo_power)
    print("same state:", same)


if __name__ == "__main__":
    main()
