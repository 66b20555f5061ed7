"""Time OpenSHC's start-up computations for the Bullet hexapod (8 bearings, tripod).

Run:  .venv/bin/python benchmarks/bench_workspace.py [--repeats 50]

Prints medians and 90th percentiles of:
  workspace+walkspace+limits   the part OpenSHC does in its "generate workspaces" cycle (60–75 ms in C++ here)
  direct start-up plan         500 IK steps for 6 legs (OpenSHC spreads this over its first start-up cycle)
  whole `workspace` analysis   both, as `shc workspace` runs them
The first call (numba cache load) is excluded; machines here are noisy, so compare medians from one run.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from collections.abc import Callable

from shc_cli.analysis.workspace import analyse_workspace
from shc_cli.control.gait import step_cycle
from shc_cli.control.limits import generate_limits
from shc_cli.control.startup import plan_direct_startup
from shc_cli.model.chains import Chains
from shc_cli.model.workspace import search_workspaces, walkspace
from shc_cli.spec.loading import load_gait, load_robot


def measure(function: Callable[[], object], repeats: int) -> list[float]:
    function()
    samples = []
    for _ in range(repeats):
        started = time.perf_counter()
        function()
        samples.append(time.perf_counter() - started)
    return samples


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=50)
    args = parser.parse_args()
    robot = load_robot("bullet").robot
    gait = load_gait("tripod").gait
    chains = Chains.from_robot(robot)
    defaults = plan_direct_startup(robot, chains, chains.default_joints())
    identity = [[leg.stance.x, leg.stance.y, -robot.walker.body_clearance] for leg in robot.legs.values()]
    stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}

    def workspace_walkspace_limits() -> None:
        import numpy as np

        planes = search_workspaces(chains, defaults, np.array(identity), robot.time_delta).planes
        common = walkspace(planes, stance)
        cycle = step_cycle(gait, robot.walker.step_frequency.default, robot.time_delta)
        generate_limits(common, cycle, robot.time_delta, math.hypot(*stance["AR"]))

    cases = {
        "workspace+walkspace+limits": workspace_walkspace_limits,
        "direct start-up plan": lambda: plan_direct_startup(robot, chains, chains.default_joints()),
        "whole workspace analysis": lambda: analyse_workspace(robot, gait),
    }
    print(f"{'case':<30}{'median ms':>11}{'p90 ms':>9}   (n = {args.repeats})")
    for name, function in cases.items():
        samples = sorted(measure(function, args.repeats))
        p90 = samples[int(0.9 * (len(samples) - 1))]
        print(f"{name:<30}{statistics.median(samples) * 1e3:>11.2f}{p90 * 1e3:>9.2f}")


if __name__ == "__main__":
    main()
