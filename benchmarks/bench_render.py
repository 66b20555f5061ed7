"""``shc render`` of a simulated walk, and the offscreen renderers it could use, in one process.

Run:  .venv/bin/python benchmarks/bench_render.py RUN_DIR [--repeats 3] [--frames 20]

RUN_DIR is a ``shc simulate`` run, e.g. the 20 s walk of docs/performance.md
(``shc simulate bullet --duration 20 --no-plots --out runs/walk20``: 5 s start-up + 20 s at 100 Hz).
Prints the load average, then the median wall time of ``shc render RUN --out walk.mp4`` (25 fps, 960×540, the
whole run: 626 frames) as a subprocess, and the median time per 960×540 frame of the same scene drawn by MuJoCo
(OSMesa or EGL, what ``shc render`` uses) and by PyBullet's TinyRenderer (the alternative measured).
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np


def _cpu() -> float:
    """CPU time of this process and its threads (OSMesa's llvmpipe draws on several) [s]."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def _mujoco_frames(run_dir: Path, frames: int) -> tuple[list[float], float]:
    from shc_cli.record.runread import read_run
    from shc_cli.view import scene
    from shc_cli.view.render import Renderer

    run = read_run(run_dir)
    shape = scene.shapes(run.robot)
    rows = np.linspace(0, len(run.t) - 1, frames).astype(int)
    pose = scene.poses(shape, run.joints[rows], run.position[rows], run.rpy[rows])
    renderer = Renderer(shape, scene.terrain_shapes(run.summary), 960, 540)
    times = []
    cpu = _cpu()
    for i, row in enumerate(rows):
        started = time.perf_counter()
        renderer.place(pose, i, run.contact[row])
        renderer.look(run.position[row], 1.2, 120.0, -25.0)
        renderer.draw()
        times.append(time.perf_counter() - started)
    cpu = (_cpu() - cpu) / frames
    renderer.close()
    return times, cpu


def _tiny_frames(run_dir: Path, frames: int) -> tuple[list[float], float]:
    import pybullet as p

    from shc_cli.backends.pybullet_.terrain_bodies import build_terrain
    from shc_cli.backends.pybullet_.urdf import robot_urdf
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.record.runread import read_run

    run = read_run(run_dir)
    client = p.connect(p.DIRECT)
    build_terrain(client, parse_terrain(run.summary.terrain or "flat"), 0.9, 0.0, 0)
    with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as handle:
        handle.write(robot_urdf(run.robot))
    body = p.loadURDF(handle.name, physicsClientId=client)
    os.unlink(handle.name)
    names = {p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
             for j in range(p.getNumJoints(body, physicsClientId=client))}
    joints = [(i, k, names[f"{leg_id}_{name}_joint"]) for i, (leg_id, leg) in enumerate(run.robot.legs.items())
              for k, name in enumerate(leg.joints)]
    projection = p.computeProjectionMatrixFOV(45.0, 960 / 540, 0.01, 50.0)
    times = []
    cpu = _cpu()
    for row in np.linspace(0, len(run.t) - 1, frames).astype(int):
        started = time.perf_counter()
        p.resetBasePositionAndOrientation(body, run.position[row], p.getQuaternionFromEuler(run.rpy[row]),
                                          physicsClientId=client)
        for i, k, index in joints:
            p.resetJointState(body, index, float(run.joints[row, i, k]), physicsClientId=client)
        view = p.computeViewMatrix(run.position[row] + np.array([-0.6, -1.0, 0.6]), run.position[row], [0, 0, 1])
        p.getCameraImage(960, 540, view, projection, renderer=p.ER_TINY_RENDERER, shadow=0,
                         physicsClientId=client)
        times.append(time.perf_counter() - started)
    cpu = (_cpu() - cpu) / frames
    p.disconnect(client)
    return times, cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--frames", type=int, default=20)
    args = parser.parse_args()
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    walls, cpus = [], []
    with tempfile.TemporaryDirectory() as directory:
        for repeat in range(args.repeats):
            out = Path(directory) / f"walk{repeat}.mp4"
            children = resource.getrusage(resource.RUSAGE_CHILDREN)
            started = time.perf_counter()
            result = subprocess.run([sys.executable, "-m", "shc_cli.cli", "render", str(args.run), "--out", str(out)],
                                    check=True, capture_output=True, text=True)
            walls.append(time.perf_counter() - started)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpus.append(after.ru_utime + after.ru_stime - children.ru_utime - children.ru_stime)
            print(f"  render {repeat}: {walls[-1]:.1f} s wall, {cpus[-1]:.1f} s CPU (render and ffmpeg) "
                  f"({result.stdout.strip()}), {out.stat().st_size / 1e6:.1f} MB, load "
                  f"{os.getloadavg()[0]:.1f}", flush=True)
    mujoco, mujoco_cpu = _mujoco_frames(args.run, args.frames)
    tiny, tiny_cpu = _tiny_frames(args.run, args.frames)
    m, t = statistics.median(mujoco), statistics.median(tiny)
    print(f"shc render 25 fps 960x540: median {statistics.median(walls):.1f} s wall, "
          f"{statistics.median(cpus):.1f} s CPU over {args.repeats}")
    print(f"per 960x540 frame, wall (CPU): MuJoCo ({os.environ.get('MUJOCO_GL')}) {m * 1e3:.0f} ms "
          f"({mujoco_cpu * 1e3:.0f} ms), PyBullet TinyRenderer {t * 1e3:.0f} ms ({tiny_cpu * 1e3:.0f} ms); "
          f"TinyRenderer / MuJoCo ×{t / m:.1f} wall, ×{tiny_cpu / mujoco_cpu:.1f} CPU")
    print(f"load average after: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


if __name__ == "__main__":
    main()
