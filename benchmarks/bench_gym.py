"""Throughput of ``shc/Walk-v0``: environment steps per second (one step = one control cycle), one environment
in this process and two in gymnasium's ``AsyncVectorEnv`` (two processes).

Run:  .venv/bin/python benchmarks/bench_gym.py [--steps 3000] [--action residual] [--engine mujoco] [--profile]

Each measurement resets (start-up to RUNNING, not timed), then times ``--steps`` steps of zero actions while the
Bullet walks at full throttle (episodes long enough not to end). The vector figure counts the steps of both
environments (``--steps`` vector steps = 2 × ``--steps`` environment steps). Prints one line per measurement and
the speed-up of two environments over one. ``--profile`` instead profiles ``--steps`` steps of one environment
(cProfile) and prints each part's share of a step's own time: the physics and the reading (``backends``), the
controller (``control``, ``model``), the run loop, the environment (observation, rewards: ``gym``,
``loop/policy``) and the rest (numpy's and Python's built-ins called from them).
"""

from __future__ import annotations

import argparse
import time
from typing import Any

import gymnasium
import numpy as np

import shc_cli.gym

Env = gymnasium.Env[np.ndarray, np.ndarray]
VectorEnv = gymnasium.vector.VectorEnv[np.ndarray, np.ndarray, np.ndarray]


def env_action_shape(env: Env | VectorEnv) -> tuple[int, ...]:
    """One environment's action shape."""
    space = env.single_action_space if isinstance(env, gymnasium.vector.VectorEnv) else env.action_space
    shape = space.shape
    assert shape is not None
    return tuple(shape)


def one(steps: int, action: str, engine: str) -> float:
    env = gymnasium.make(shc_cli.gym.ENV_ID, action=action, engine=engine, duration=steps * 0.01 + 10)
    env.reset(seed=0)
    zero = np.zeros(env_action_shape(env), dtype=np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        env.step(zero)
    rate = steps / (time.perf_counter() - start)
    env.close()
    return rate


def vector(steps: int, action: str, engine: str, count: int = 2) -> float:
    kwargs: dict[str, Any] = {"action": action, "engine": engine, "duration": steps * 0.01 + 10}
    envs = gymnasium.vector.AsyncVectorEnv([lambda: gymnasium.make(shc_cli.gym.ENV_ID, **kwargs)] * count)
    envs.reset(seed=0)
    zero = np.zeros((count, *env_action_shape(envs)), dtype=np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        envs.step(zero)
    rate = count * steps / (time.perf_counter() - start)
    envs.close()
    return rate


PARTS = (("environment", ("/gym/", "/loop/policy/")), ("run loop", ("/loop/",)),
         ("physics and reading", ("/backends/",)), ("controller", ("/control/", "/model/")))


def profile(steps: int, action: str, engine: str) -> None:
    import cProfile
    import pstats

    env = gymnasium.make(shc_cli.gym.ENV_ID, action=action, engine=engine, duration=steps * 0.01 + 10)
    env.reset(seed=0)
    zero = np.zeros(env_action_shape(env), dtype=np.float32)
    for _ in range(100):
        env.step(zero)
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(steps):
        env.step(zero)
    profiler.disable()
    env.close()
    stats: Any = pstats.Stats(profiler)
    shares = dict.fromkeys([name for name, _ in PARTS] + ["built-ins and the rest"], 0.0)
    total = 0.0
    for (path, _, _), (_, _, own, _, _) in stats.stats.items():
        total += own
        part = next((name for name, marks in PARTS if any(mark in path for mark in marks)), "built-ins and the rest")
        shares[part] += own
    print(f"profile of {steps} steps ({action}, {engine}): {1e3 * total / steps:.3f} ms a step under cProfile")
    for name, own in sorted(shares.items(), key=lambda item: -item[1]):
        print(f"  {name}: {100 * own / total:.0f} %")
    stats.sort_stats("tottime").print_stats(8)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=3000, help="timed steps per measurement")
    parser.add_argument("--action", default="residual", choices=["gait", "residual", "joints"])
    parser.add_argument("--engine", default="mujoco", choices=["mujoco", "pybullet"])
    parser.add_argument("--profile", action="store_true", help="profile one environment's steps instead")
    args = parser.parse_args()
    if args.profile:
        profile(args.steps, args.action, args.engine)
        return
    single = one(args.steps, args.action, args.engine)
    print(f"one environment ({args.action}, {args.engine}): {single:.0f} steps/s")
    double = vector(args.steps, args.action, args.engine)
    print(f"two AsyncVectorEnv environments: {double:.0f} steps/s ({double / single:.2f}× one)")


if __name__ == "__main__":
    main()
