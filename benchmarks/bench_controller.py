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
    parser.add_argument("--steps", type=int, default=2000, help="timed steps per round")
    parser.add_argument("--rounds", type=int, default=5, help="rounds (the machine is noisy: medians per round)")
    args = parser.parse_args()
    robot = load_robot("bullet").robot
    gait = load_gait("tripod").gait
    controller = Controller(robot, gait)
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    command = Command(velocity=(1.0, 0.0, 0.0))
    for _ in range(400):
        controller.step(command)
    medians, everything = [], []
    for _ in range(args.rounds):
        samples = []
        for _ in range(args.steps):
            started = time.perf_counter()
            controller.step(command)
            samples.append(time.perf_counter() - started)
        medians.append(statistics.median(samples))
        everything += samples
    everything.sort()
    rounds = ", ".join(f"{m * 1e6:.0f}" for m in medians)
    print(f"controller step (bullet, tripod, full speed): median of round medians "
          f"{statistics.median(medians) * 1e6:.0f} µs, best round {min(medians) * 1e6:.0f} µs, "
          f"p99 {everything[int(0.99 * (len(everything) - 1))] * 1e6:.0f} µs (rounds: {rounds}; "
          f"{args.rounds} × {args.steps} steps)")


if __name__ == "__main__":
    main()
