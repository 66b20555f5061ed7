"""A gait-parameter policy for the default Bullet found through ``shc/Walk-v0``: the cross-entropy method over a
constant ``gait`` action (step frequency, swing height, stance span, velocity scale), lowering the cost of
transport at the speed the defaults walk. numpy only: the learning libraries on the package index (stable-baselines3
and its JAX port sbx-rl alike) pull torch with its GPU wheels (docs/gym.md).

Run:  .venv/bin/python docs/experiments/gym_gait_search.py [--iterations 4] [--population 6] [--seed 0] [--save F]

Each candidate walks one episode (seeded: the same world each time) at throttle 0.5 forward; its cost of transport
over the episode's second half is the servo model's mean power over m·g·the mean planar body speed (``info``'s
``power_w`` and ``speed_mps``), counted only if the robot walked as fast as with the controller's defaults (within
:data:`SPEED_TOLERANCE`) and did not fall. Prints the defaults' CoT and speed, each iteration's best and the
parameters found.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from shc_cli.gym.env import WalkEnv
from shc_cli.loop.policy.actions import GAIT_PARAMETERS, VELOCITY_SCALE, around
from shc_cli.loop.policy.file import Policy

SPEED_TOLERANCE = 0.05
"""A candidate's mean speed must lie within this share of the defaults' (equal speed)."""
SIZE = 4
"""The gait action: three dynamic parameters and the velocity scale."""
WEIGHTS = {"tracking": 0.0, "cot": 1.0, "stability": 0.0, "fall": 0.0, "joint_limits": 0.0}


def evaluate(env: WalkEnv, gait: np.ndarray, seed: int) -> tuple[float, float, bool]:
    """(CoT, mean speed [m/s], fell) of one episode's second half with the constant gait action ``gait``."""
    env.reset(seed=seed)
    action = np.clip(gait, -1.0, 1.0).astype(np.float32)
    power, speed = [], []
    fell = False
    while True:
        _, _, terminated, truncated, info = env.step(action)
        power.append(info["power_w"])
        speed.append(info["speed_mps"])
        if terminated:
            fell = True
        if terminated or truncated:
            break
    half = len(power) // 2
    mean_speed = float(np.mean(speed[half:]))
    return float(np.mean(power[half:])) / (env.rewards.weight_mg * max(mean_speed, 1e-6)), mean_speed, fell


def parameters(env: WalkEnv, gait: np.ndarray) -> str:
    a = np.clip(gait, -1, 1)
    values = [around(float(x), spec.min, spec.default, spec.max)
              for x, spec in zip(a, env.gait.specs if env.gait else [], strict=False)]
    text = ", ".join(f"{name} {value:.3g}" for name, value in zip(GAIT_PARAMETERS, values, strict=True))
    return f"{text}, velocity scale {around(float(a[-1]), *VELOCITY_SCALE[:1], 1.0, VELOCITY_SCALE[1]):.3g}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--iterations", type=int, default=4)
    parser.add_argument("--population", type=int, default=6)
    parser.add_argument("--elites", type=int, default=2)
    parser.add_argument("--duration", type=float, default=6.0, help="walking per episode [s]")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--save", type=Path, help="write the gait found as a policy file (shc_cli.gym.policy)")
    args = parser.parse_args()
    start = time.perf_counter()
    env = WalkEnv(action="gait", command=(0.5, 0.0, 0.0), reward=WEIGHTS, duration=args.duration)
    rng = np.random.default_rng(args.seed)
    default = np.zeros(SIZE)
    base_cot, base_speed, base_fell = evaluate(env, default, args.seed)
    print(f"defaults: CoT {base_cot:.3f} at {base_speed:.4f} m/s, fell {base_fell} ({parameters(env, default)})")
    mean, sigma = default.copy(), np.full(SIZE, 0.5)
    best, best_cot, best_speed = default, base_cot, base_speed
    episodes = 1
    for iteration in range(args.iterations):
        candidates = np.clip(mean + sigma * rng.standard_normal((args.population, SIZE)), -1.0, 1.0)
        scores = []
        for candidate in candidates:
            cot, speed, fell = evaluate(env, candidate, args.seed)
            episodes += 1
            ok = not fell and abs(speed / base_speed - 1.0) <= SPEED_TOLERANCE
            scores.append(cot if ok else np.inf)
            if ok and cot < best_cot:
                best, best_cot, best_speed = candidate, cot, speed
        order = np.argsort(scores)[: args.elites]
        mean = candidates[order].mean(axis=0)
        sigma = np.maximum(candidates[order].std(axis=0), 0.1)
        print(f"iteration {iteration + 1}: best CoT so far {best_cot:.3f}")
    env.close()
    if args.save is not None:
        Policy.constant("gait", best, len(env.names)).save(args.save)
    wall = time.perf_counter() - start
    print(f"found: CoT {best_cot:.3f} against {base_cot:.3f} of the defaults ({100 * (1 - best_cot / base_cot):.0f} % "
          f"lower) at {best_speed:.4f} m/s with {parameters(env, best)}; {episodes} episodes in {wall:.0f} s")


if __name__ == "__main__":
    main()
