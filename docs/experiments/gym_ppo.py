"""PPO (stable-baselines3, torch on the CPU) learning a gait-parameter policy for the default Bullet through
``shc/Walk-v0`` that lowers the cost of transport at the speed the controller's defaults walk.

Needs the ``rl`` extra (``pip install -e '.[rl]'``, with torch's CPU wheel installed first: docs/gym.md).

Run:  nice -n 10 .venv/bin/python docs/experiments/gym_ppo.py [--timesteps 320] [--mode episode|second]
      [--duration 6] [--seed 0] [--save F]

``--mode episode`` (the default): one PPO step is a whole training episode of one ``gait`` action (its input is
zeros: a bandit), rewarded with minus the episode's second-half cost of transport (:func:`evaluate`: the servo
model's mean power over m·g·the mean planar body speed), less a penalty when the mean speed leaves the defaults' by
more than :data:`SPEED_TOLERANCE`, −10 for a fall. ``--mode second``: one PPO step holds the action for
:data:`CHUNK` control cycles and the policy sees the observation, rewarded the same way for that second. The
defaults' speed is measured first (zero action, same seed). After training, the actor is exported to a policy
file (:func:`shc_cli.gym.policy.export_sb3`; in ``episode`` mode its first layer's weights are zeroed: they only
ever met zeros) and that file — acting every control cycle, as ``shc simulate --policy`` runs it — is evaluated
with docs/experiments/gym_gait_search.py's measure (a 6 s episode's second half) against the defaults, same seed.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path
from typing import Any, SupportsFloat

import gymnasium
import numpy as np

from shc_cli.gym.env import WalkEnv
from shc_cli.gym.policy import export_sb3

CHUNK = 100
"""Control cycles per PPO step (1 s at the Bullet's 100 Hz)."""
SPEED_TOLERANCE = 0.05
"""Equal speed: within this share of the defaults' mean speed."""
SPEED_PENALTY = 50.0
"""Reward lost per unit of relative speed error beyond the tolerance."""
WEIGHTS = {"tracking": 0.0, "cot": 0.0, "stability": 0.0, "fall": 10.0, "joint_limits": 0.0}
COMMAND = (0.5, 0.0, 0.0)
DURATION = 6.0


class Chunked(gymnasium.Wrapper[np.ndarray, np.ndarray, np.ndarray, np.ndarray]):
    """One step = :data:`CHUNK` cycles of one action; the reward is the chunk's CoT at the target speed."""

    def __init__(self, env: WalkEnv, target_speed: float) -> None:
        super().__init__(env)
        self.walk, self.target = env, target_speed

    def step(self, action: np.ndarray) -> tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]:
        power, speed, total = 0.0, 0.0, 0.0
        n = 0
        obs = np.zeros(len(self.walk.names), dtype=np.float32)
        terminated = truncated = False
        for _ in range(CHUNK):
            obs, reward, terminated, truncated, info = self.walk.step(action)
            total += float(reward)  # the fall term only
            if "power_w" in info:
                power, speed, n = power + info["power_w"], speed + info["speed_mps"], n + 1
            if terminated or truncated:
                break
        if n:
            mean_speed = speed / n
            cot = power / n / (self.walk.rewards.weight_mg * max(mean_speed, 0.05))
            error = max(0.0, abs(mean_speed / self.target - 1.0) - SPEED_TOLERANCE)
            total += -cot - SPEED_PENALTY * error
        return obs, total, terminated, truncated, {}


class OneGait(gymnasium.Wrapper[np.ndarray, np.ndarray, np.ndarray, np.ndarray]):
    """One step = one whole episode of one ``gait`` action (a contextual bandit without context: the observation
    is zeros); the reward is minus the episode's second-half CoT (:func:`evaluate`), less the speed penalty."""

    def __init__(self, env: WalkEnv, target_speed: float, seed: int) -> None:
        super().__init__(env)
        self.walk, self.target, self.seed_ = env, target_speed, seed
        self.zeros = np.zeros(len(env.names), dtype=np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        return self.zeros, {}

    def step(self, action: np.ndarray) -> tuple[np.ndarray, SupportsFloat, bool, bool, dict[str, Any]]:
        clipped = np.clip(action, -1.0, 1.0).astype(np.float32)
        cot, speed, fell = evaluate(self.walk, lambda _: clipped, self.seed_)
        error = max(0.0, abs(speed / self.target - 1.0) - SPEED_TOLERANCE)
        return self.zeros, -cot - SPEED_PENALTY * error - (10.0 if fell else 0.0), True, False, {}


def evaluate(env: WalkEnv, act: Any, seed: int) -> tuple[float, float, bool]:
    """(CoT, mean speed [m/s], fell) of one episode's second half, ``act(observation)`` every cycle."""
    obs, _ = env.reset(seed=seed)
    power, speed, fell = [], [], False
    while True:
        obs, _, terminated, truncated, info = env.step(act(obs))
        if "power_w" in info:
            power.append(info["power_w"])
            speed.append(info["speed_mps"])
        fell = fell or terminated
        if terminated or truncated:
            break
    half = len(power) // 2
    mean_speed = float(np.mean(speed[half:]))
    return float(np.mean(power[half:])) / (env.rewards.weight_mg * max(mean_speed, 1e-6)), mean_speed, fell


def main() -> None:
    import torch
    from stable_baselines3 import PPO

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=320, help="PPO steps (each CHUNK control cycles)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--save", type=Path, help="write the policy as a policy file (shc simulate --policy)")
    parser.add_argument("--mode", choices=["episode", "second"], default="episode",
                        help="one PPO step: a whole episode of one gait (its inputs zeros), or one second")
    parser.add_argument("--duration", type=float, default=DURATION, help="walking per training episode [s]")
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    env = WalkEnv(action="gait", command=COMMAND, reward=WEIGHTS, duration=DURATION)
    zero = np.zeros(env.action_size, dtype=np.float32)
    base_cot, base_speed, base_fell = evaluate(env, lambda _: zero, args.seed)
    print(f"defaults: CoT {base_cot:.3f} at {base_speed:.4f} m/s, fell {base_fell}")
    train = WalkEnv(action="gait", command=COMMAND, reward=WEIGHTS, duration=args.duration)
    if args.mode == "episode":
        _, train_speed, _ = evaluate(train, lambda _: zero, args.seed)
        wrapped: gymnasium.Env[np.ndarray, np.ndarray] = OneGait(train, train_speed, args.seed)
        settings: dict[str, Any] = {"n_steps": 32, "batch_size": 16, "n_epochs": 10, "learning_rate": 5e-3}
        log_std = -0.5
    else:
        wrapped = Chunked(train, base_speed)
        settings = {"n_steps": 60, "batch_size": 30, "n_epochs": 10, "learning_rate": 1e-3, "gamma": 0.9}
        log_std = -1.0
    model = PPO("MlpPolicy", wrapped, ent_coef=0.0, seed=args.seed, device="cpu", verbose=0,
                policy_kwargs={"net_arch": [32, 32], "log_std_init": log_std}, **settings)
    model.learn(total_timesteps=args.timesteps)
    trained = time.perf_counter() - start
    train.close()
    policy = export_sb3(model, env)
    obs, _ = env.reset(seed=args.seed)
    seen = np.zeros_like(obs) if args.mode == "episode" else obs
    predicted, _ = model.predict(seen, deterministic=True)
    assert np.allclose(policy(seen), predicted, atol=1e-5), (policy(seen), predicted)  # the export acts as SB3 does
    if args.mode == "episode":  # its only input was zeros: the first layer's weights never acted (exact there)
        (w0, b0), *rest = policy.layers
        policy = replace(policy, layers=((np.zeros_like(w0), b0), *rest))
    if args.save is not None:
        policy.save(args.save)
    cot, speed, fell = evaluate(env, policy, args.seed)
    env.close()
    same = abs(speed / base_speed - 1.0) <= SPEED_TOLERANCE
    print(f"ppo: CoT {cot:.3f} against {base_cot:.3f} of the defaults ({100 * (1 - cot / base_cot):.1f} % lower) at "
          f"{speed:.4f} m/s against {base_speed:.4f} m/s (equal speed: {same}), fell {fell}; "
          f"{args.timesteps} PPO steps ({args.mode}) in {trained:.0f} s; "
          f"action {np.round(policy(obs), 3).tolist()}")


if __name__ == "__main__":
    main()
