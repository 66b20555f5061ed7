"""A policy file for ``shc/Walk-v0`` and playing it through the one loop into a run directory.

A policy file is a ``.npz`` of ``weights`` ``(A, O)``, ``bias`` ``(A,)`` and ``action`` (the action space's name):
the action is ``clip(weights · observation + bias, −1, 1)`` — a constant action when the weights are zero (what
docs/experiments/gym_gait_search.py finds), or a linear policy. :func:`play` walks it in an episode written as a
run directory of ``shc simulate``'s form (the base of a later ``shc simulate --policy FILE``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shc_cli.gym.actions import ACTIONS, ActionName
from shc_cli.gym.env import WalkEnv


@dataclass(frozen=True)
class LinearPolicy:
    """``action = clip(weights · observation + bias, −1, 1)`` for one action space."""

    action: ActionName
    weights: np.ndarray
    bias: np.ndarray

    @classmethod
    def constant(cls, action: ActionName, values: np.ndarray, observations: int) -> LinearPolicy:
        bias = np.asarray(values, dtype=np.float64)
        return cls(action, np.zeros((len(bias), observations)), bias)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        return np.asarray(np.clip(self.weights @ observation + self.bias, -1.0, 1.0), dtype=np.float32)

    def save(self, path: Path) -> None:
        with path.open("wb") as handle:
            np.savez(handle, weights=self.weights, bias=self.bias, action=np.array(self.action))

    @classmethod
    def load(cls, path: Path) -> LinearPolicy:
        with np.load(path) as data:
            name = str(data["action"])
            action = next((known for known in ACTIONS if known == name), None)
            if action is None:
                raise ValueError(f"{path}: action '{name}' is not one of {', '.join(ACTIONS)}")
            weights, bias = np.asarray(data["weights"], dtype=float), np.asarray(data["bias"], dtype=float)
        if weights.ndim != 2 or bias.shape != (weights.shape[0],):
            raise ValueError(f"{path}: weights {weights.shape} and bias {bias.shape} do not fit (A, O) and (A,)")
        return cls(action, weights, bias)


def play(policy: LinearPolicy, out: Path, robot: str = "bullet", command: str = "1,0,0", duration: float = 10.0,
         seed: int = 0, engine: str = "mujoco", terrain: str = "flat") -> Path:
    """Walk one episode of ``policy`` (the keywords: :class:`~shc_cli.gym.env.WalkEnv`'s) and write it as the run
    directory ``out/episode-0001``; its path."""
    walk = WalkEnv(robot=robot, action=policy.action, engine=engine, terrain=terrain, command=command,
                   duration=duration, out=out)
    expected = (walk.action_size, len(walk.names))
    if policy.weights.shape != expected:
        walk.close()
        raise ValueError(f"policy: weights {policy.weights.shape} do not fit this robot's {expected} "
                         "(actions, observations)")
    observation, _ = walk.reset(seed=seed)
    while True:
        observation, _, terminated, truncated, _ = walk.step(policy(observation))
        if terminated or truncated:
            break
    walk.close()
    return walk.written[-1]
