"""Playing a policy file (:class:`~shc_cli.loop.policy.file.Policy`) through ``shc/Walk-v0`` into a run directory,
and exporting a stable-baselines3 (or sbx) PPO model into one.

``shc simulate --policy FILE`` runs the same file through the same loop (:mod:`shc_cli.loop.policy.drive`); the
environment's :func:`play` is the reference it is tested against.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.gym.env import WalkEnv
from shc_cli.loop.policy.actions import RESIDUAL_LIMIT
from shc_cli.loop.policy.file import Activation, Policy

__all__ = ["Policy", "export_sb3", "play"]


def play(policy: Policy, out: Path, robot: str = "bullet", command: str = "1,0,0", duration: float = 10.0,
         seed: int = 0, engine: str = "mujoco", terrain: str = "flat") -> Path:
    """Walk one episode of ``policy`` (the keywords: :class:`~shc_cli.gym.env.WalkEnv`'s) and write it as the run
    directory ``out/episode-0001``; its path."""
    walk = WalkEnv(robot=robot, action=policy.action, engine=engine, terrain=terrain, command=command,
                   duration=duration, residual_limit=policy.residual_limit, out=out)
    expected = (walk.action_size, len(walk.names))
    if (policy.actions, policy.observations) != expected:
        walk.close()
        raise ValueError(f"policy: weights ({policy.actions}, {policy.observations}) do not fit this robot's "
                         f"{expected} (actions, observations)")
    observation, _ = walk.reset(seed=seed)
    while True:
        observation, _, terminated, truncated, _ = walk.step(policy(observation))
        if terminated or truncated:
            break
    walk.close()
    return walk.written[-1]


def export_sb3(model: Any, env: WalkEnv, normalize: Any = None) -> Policy:
    """The deterministic action of a stable-baselines3 (or sbx-free torch) ``PPO``/``A2C`` ``MlpPolicy`` ``model``
    trained on ``env`` as a policy file: its actor network (``mlp_extractor.policy_net`` then ``action_net``) and,
    when trained under ``VecNormalize`` (``normalize``), its observation statistics.

    Raises:
        ValueError: the model is not a torch MLP policy of Linear layers and one activation."""
    import torch  # type: ignore[import-not-found,unused-ignore]

    policy = model.policy
    modules = [*policy.mlp_extractor.policy_net, policy.action_net]
    layers: list[tuple[np.ndarray, np.ndarray]] = []
    activations: set[str] = set()
    for module in modules:
        if isinstance(module, torch.nn.Linear):
            layers.append((module.weight.detach().cpu().numpy().astype(np.float64),
                           module.bias.detach().cpu().numpy().astype(np.float64)))
        elif isinstance(module, torch.nn.Tanh | torch.nn.ReLU):
            activations.add("tanh" if isinstance(module, torch.nn.Tanh) else "relu")
        else:
            raise ValueError(f"export: cannot export a {type(module).__name__} layer (Linear, Tanh, ReLU only)")
    if len(activations) > 1:
        raise ValueError("export: the actor mixes activations")
    activation: Activation = "tanh" if "tanh" in activations else "relu" if activations else "identity"
    mean = std = None
    clip = 0.0
    if normalize is not None and getattr(normalize, "norm_obs", False):
        rms = normalize.obs_rms
        mean, std = np.asarray(rms.mean, dtype=np.float64), np.sqrt(np.asarray(rms.var) + normalize.epsilon)
        clip = float(normalize.clip_obs)
    limit = env.residual.limit if env.residual is not None else RESIDUAL_LIMIT
    return Policy(env.action_name, tuple(layers), activation, mean, std, clip, tuple(env.names), limit,
                  {"source": type(model).__name__, "robot": env.robot.name, "command": env.config.velocity})
