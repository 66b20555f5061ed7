"""The controller as a Gymnasium environment: ``import shc_cli.gym`` registers ``shc/Walk-v0``.

``gymnasium.make("shc/Walk-v0", robot="bullet", action="gait", engine="mujoco", terrain="flat",
command=(1.0, 0.0, 0.0), reward={"tracking": 1.0, "cot": 0.1})`` drives the one controller on the physics backend of
``shc simulate`` through the one run loop (:meth:`shc_cli.loop.run_loop.RunLoop.step`), one control cycle per
environment step. :mod:`.env` is the environment, :mod:`shc_cli.loop.policy.actions` the three action spaces,
:mod:`shc_cli.loop.policy.observe` the observation and the reward terms, :mod:`.policy` playing and exporting a
policy file (docs/gym.md).
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

ENV_ID = "shc/Walk-v0"
"""The environment's Gymnasium id."""

if ENV_ID not in registry:
    register(id=ENV_ID, entry_point="shc_cli.gym.env:WalkEnv")
