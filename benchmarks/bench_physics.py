"""Physics step cost vs PyBullet solver iterations, and the per-cycle cost around it.

Run:  .venv/bin/python benchmarks/bench_physics.py [--cycles 1600] [--rate 400] [--iterations 50 30 20]
      .venv/bin/python benchmarks/bench_physics.py --floor [--cycles 1600]

For each iteration count, in one process (these machines are noisy: compare within a run): build the Bullet
insectoid on flat ground at ``--rate``, start it up, walk ``--cycles`` control cycles of tripod at throttle 1, and
print the mean physics step [µs], the distance walked [m] and the final body height [m]; then the medians of
the per-cycle costs outside physics (controller step, sensor read, sub-step sampling) [µs].

``--floor``: wall time ÷ physics time of the walking loop built up layer by layer — physics alone; + the
joint-state read after every physics step (the power model's torque samples); + the servo commands; + the
controller; + the sensor read; and the whole run loop (``domain.simulate.simulate``) with its log — so the cost
of each layer is a ratio measured in the same process.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from shc_cli.backends.engine import EngineOptions
from shc_cli.backends.pybullet_ import world as world_module
from shc_cli.backends.simulated import open_world
from shc_cli.backends.terrain import parse_terrain
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.domain.config import SimulationConfig
from shc_cli.domain.simulate import simulate
from shc_cli.validation import load_checked

LAYERS = ("physics", "+ joint-state samples", "+ servo commands", "+ controller", "+ sensor read")


class _Started:
    """A world and its controller."""

    def __init__(self, rate: float) -> None:
        self.robot, self.gait, _ = load_checked("bullet", "tripod")
        self.world = open_world(self.robot, EngineOptions(parse_terrain("flat"), round(rate * self.robot.time_delta)))
        self.controller = Controller(self.robot, self.gait, joints=self.world.read().joints)


def started_bullet(rate: float) -> tuple[_Started, Command]:
    """The Bullet insectoid on flat ground at ``rate`` [Hz], started up to RUNNING; and the full-speed command."""
    sim = _Started(rate)
    start = Command(state_request=RobotState.RUNNING)
    while sim.controller.state != RobotState.RUNNING:
        sim.world.command(sim.controller.step(start).joints)
        sim.world.step()
    return sim, Command(velocity=(1.0, 0.0, 0.0), state_request=RobotState.RUNNING)


def walk(iterations: int, cycles: int, rate: float) -> dict[str, float]:
    """One walk with ``iterations`` solver iterations at ``rate`` [Hz]; returns its figures."""
    world_module.SOLVER_ITERATIONS = iterations
    sim, go = started_bullet(rate)
    world, controller, p = sim.world, sim.controller, sim.world.p
    x0 = p.getBasePositionAndOrientation(world.body, physicsClientId=world.client)[0][0]
    physics0 = world.physics_time
    control, sampling, read = [], [], []
    for _ in range(cycles):
        t0 = time.perf_counter()
        out = controller.step(go)
        t1 = time.perf_counter()
        world.command(out.joints)
        before = world.physics_time
        t2 = time.perf_counter()
        world.step()
        t3 = time.perf_counter()
        world.read()
        t4 = time.perf_counter()
        control.append(t1 - t0)
        sampling.append((t3 - t2) - (world.physics_time - before))
        read.append(t4 - t3)
    position = p.getBasePositionAndOrientation(world.body, physicsClientId=world.client)[0]
    figures = {
        "physics_step_us": (world.physics_time - physics0) / (cycles * world.substeps) * 1e6,
        "distance_m": position[0] - x0,
        "body_z_m": position[2],
        "controller_us": float(np.median(control)) * 1e6,
        "substep_sampling_us": float(np.median(sampling)) * 1e6,
        "read_us": float(np.median(read)) * 1e6,
    }
    world.close()
    return figures


def floor(cycles: int) -> None:
    """Print wall ÷ physics for each layer of the loop, then for the whole logged loop."""
    sim, go = started_bullet(400.0)
    world, controller, p = sim.world, sim.controller, sim.world.p
    body, joints, client, clock = world.body, world.flat_joints, world.client, time.perf_counter
    out = controller.step(go)
    for level, name in enumerate(LAYERS):
        physics = 0.0
        began = clock()
        for _ in range(cycles // len(LAYERS)):
            if level >= 3:
                out = controller.step(go)
            if level >= 2:
                world.command(out.joints)
            for _ in range(world.substeps):
                started = clock()
                p.stepSimulation(physicsClientId=client)
                physics += clock() - started
                if level >= 1:
                    p.getJointStates(body, joints, physicsClientId=client)
            if level >= 4:
                world.read()
        print(f"{name:24s} wall/physics {(clock() - began) / physics:.3f}", flush=True)
    world.close()
    with tempfile.TemporaryDirectory() as directory:
        summary = simulate(SimulationConfig(duration=cycles * sim.robot.time_delta, out=Path(directory) / "run",
                                            plots=False)).summary
    wall, physics = summary.running_wall_time_s or 0.0, summary.running_physics_time_s or 1.0
    print(f"{'whole loop + log.csv':24s} wall/physics {wall / physics:.3f} (walking part of the run loop)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=1600, help="timed control cycles (0.01 s each)")
    parser.add_argument("--rate", type=float, default=400.0, help="physics rate [Hz]")
    parser.add_argument("--iterations", type=int, nargs="+", default=[50, 30, 20])
    parser.add_argument("--floor", action="store_true", help="wall ÷ physics layer by layer (30 iterations)")
    args = parser.parse_args()
    if args.floor:
        floor(args.cycles)
        return
    for iterations in args.iterations:
        figures = walk(iterations, args.cycles, args.rate)
        print(f"{iterations:3d} iterations: " + ", ".join(f"{k} {v:.4g}" for k, v in figures.items()), flush=True)


if __name__ == "__main__":
    main()
