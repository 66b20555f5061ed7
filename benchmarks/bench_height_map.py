"""The simulated depth sensor's cost: µs per scan (the engine's ray casts, then the map update) and per control cycle.

    .venv/bin/python benchmarks/bench_height_map.py [--robot bullet] [--repeat 30] [--resolution 16,12] [--rate 10]

For each engine and terrain the robot is held in the air at the origin (its sensor sees the terrain ahead); one
scan is the robot file's ``[perception]`` rays (default 32 × 24) cast at once (MuJoCo ``mj_multiRay``, PyBullet
``rayTestBatch``), the points made from them and fused into the height map. Per cycle = per scan × the sensor's
rate × the control period (a scan every 1/rate s, not every cycle). Last, the controller's side with
``--perception rays`` (:mod:`shc_cli.control.step_plane`): µs per cycle to turn the map into the walker's step-plane
input, and per scan to find the map's level cells.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial.transform import Rotation

from shc_cli.backends.engine import EngineOptions
from shc_cli.backends.engine_registry import open_engine
from shc_cli.backends.height_map import DepthSensor, HeightMap
from shc_cli.backends.terrain import parse_terrain
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot, resolve
from shc_cli.spec.robot import Perception


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robot", default="bullet")
    parser.add_argument("--repeat", type=int, default=30)
    parser.add_argument("--resolution", help="rays across,down instead of the robot file's, e.g. 16,12")
    parser.add_argument("--rate", type=float, help="scans per second instead of the robot file's")
    args = parser.parse_args()
    robot = load_robot(resolve("robots", args.robot)).robot
    spec = robot.perception or Perception()
    if args.resolution:
        columns, rows = (int(n) for n in args.resolution.split(","))
        spec = spec.model_copy(update={"resolution": (columns, rows)})
    if args.rate:
        spec = spec.model_copy(update={"rate": args.rate})
    sensor = DepthSensor(spec)
    joints = Chains.from_robot(robot).default_joints()
    print(f"{args.robot}: {sensor.count} rays a scan at {spec.rate:g} Hz, control period {robot.time_delta:g} s")
    print("engine    terrain           cast µs/scan  map µs/scan  µs/cycle")
    for engine in ("mujoco", "pybullet"):
        for text in ("flat", "stairs:0.05,0.3", "blocks"):
            world = open_engine(robot, EngineOptions(parse_terrain(text), 4, True, seed=5, engine=engine), joints)
            reading = world.read()
            origin, directions = sensor.rays(reading.position, Rotation.from_euler("xyz", reading.rpy).as_matrix())
            grid, rng = HeightMap.of(spec), np.random.default_rng(0)
            cast = fuse = 0.0
            for _ in range(args.repeat):
                started = time.perf_counter()
                distances = world.cast_rays(origin, directions, spec.range[1])  # type: ignore[attr-defined]
                middle = time.perf_counter()
                grid.update(sensor.points(origin, directions, distances, rng), reading.position[0],
                            reading.position[1])
                ended = time.perf_counter()
                cast, fuse = cast + middle - started, fuse + ended - middle
            world.close()
            per_scan = (cast + fuse) / args.repeat * 1e6
            per_cycle = per_scan * spec.rate * robot.time_delta
            print(f"{engine:9} {text:17} {cast / args.repeat * 1e6:12.0f} {fuse / args.repeat * 1e6:12.0f} "
                  f"{per_cycle:9.0f}")
            if engine == "mujoco" and text.startswith("stairs"):
                step_plane_cost(grid, reading.position, args.repeat)


def step_plane_cost(grid: HeightMap, position: np.ndarray, repeat: int) -> None:
    """The controller's per-cycle step-plane input and per-scan level cells on this map (after compiling), in CPU
    time (``time.process_time``: what the loop pays on an idle core, less inflated by a loaded machine)."""
    from shc_cli.control.step_plane import StepPlanes, StepPlaneSettings, TerrainMap

    legs = 6
    targets = np.column_stack([np.linspace(-0.3, 0.4, legs), np.tile([-0.35, 0.35], legs // 2), np.zeros(legs)])
    planes = StepPlanes(legs, StepPlaneSettings(body_length=0.5, body_width=0.28))
    progress = np.where(np.arange(legs) % 2 == 0, 0.3, -1.0)
    body = np.array([0.0, 0.0, 0.2])
    rounds = max(repeat, 1) * 100
    TerrainMap(grid.heights, grid.cell, grid.centre, np.asarray(position), np.eye(3)).levels(1)  # compiled
    started = time.process_time()
    for _ in range(rounds):
        TerrainMap(grid.heights, grid.cell, grid.centre, np.asarray(position), np.eye(3)).levels(1)
    levels = (time.process_time() - started) / rounds
    terrain = TerrainMap(grid.heights, grid.cell, grid.centre, np.asarray(position), np.eye(3))
    planes.update(terrain, targets, targets, body, np.eye(3), progress, 0.15, (0.19, 0.0), 0.25)  # compiled
    started = time.process_time()
    for _ in range(rounds):
        planes.update(terrain, targets, targets, body, np.eye(3), progress, 0.15, (0.19, 0.0), 0.25)
    update = (time.process_time() - started) / rounds
    print(f"  step-plane input (controller): {update * 1e6:.1f} µs CPU per cycle; level cells "
          f"{levels * 1e6:.0f} µs CPU per scan ({grid.size}² cells)")


if __name__ == "__main__":
    main()
