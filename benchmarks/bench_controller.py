"""Time one controller step: Bullet (30 DOF), tripod, walking forward at full throttle.

Run:  .venv/bin/python benchmarks/bench_controller.py [--steps 2000]

Starts the robot (direct start-up), walks 4 s to reach steady speed, then times each of ``--steps``
further steps with perf_counter and prints the median and p99 [µs]. OpenSHC's C++ ``loop()`` takes
115–120 µs per cycle on these machines (shared/reference/openshc-runs/insectoid_timing.txt).
"""

from __future__ import annotations

import argparse
import statistics
import time

from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.spec.loading import load_gait, load_robot


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=2000)
    args = parser.parse_args()
    robot = load_robot("bullet").robot
    gait = load_gait("tripod").gait
    assert robot is not None and gait is not None
    controller = Controller(robot, gait)
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    command = Command(velocity=(1.0, 0.0, 0.0))
    for _ in range(400):
        controller.step(command)
    samples = []
    for _ in range(args.steps):
        started = time.perf_counter()
        controller.step(command)
        samples.append(time.perf_counter() - started)
    samples.sort()
    print(f"controller step (bullet, tripod, full speed): median {statistics.median(samples) * 1e6:.0f} µs, "
          f"p99 {samples[int(0.99 * (len(samples) - 1))] * 1e6:.0f} µs (n = {args.steps})")


if __name__ == "__main__":
    main()
