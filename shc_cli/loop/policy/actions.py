"""The three action spaces of ``shc/Walk-v0``, each a Box of −1…1 mapped onto what the controller takes.

- ``gait``: step frequency, swing height, stance span modifier (OpenSHC's dynamic parameters, each within its
  ``{min, max}`` of the robot file, 0 = the default, sent as ``Command.parameters`` once a step cycle) and a scale of
  the commanded velocity (0.5…1.5, 0 = 1).
- ``residual``: tip offsets in base_link added to the controller's tip targets, at most :attr:`ResidualAction.limit`
  metres on each axis, turned into joint offsets through each leg's Jacobian (one damped least-squares step) and
  clipped to the joint limits; zero offsets leave the controller's joint targets untouched.
- ``joints``: raw joint position targets, −1…1 onto each joint's ``[min, max]`` (the controller still runs: its
  targets are replaced).
"""

from __future__ import annotations

from dataclasses import replace
from typing import Literal

import numpy as np
from gymnasium import spaces

from shc_cli.control.controller import Command, CycleOutput
from shc_cli.model.chains import Chains, JointSlots
from shc_cli.spec.robot import Robot

ActionName = Literal["gait", "residual", "joints"]
ACTIONS: tuple[ActionName, ...] = ("gait", "residual", "joints")
GAIT_PARAMETERS = ("step_frequency", "swing_height", "stance_span_modifier")
"""The dynamic parameters a gait action sets, in action order (then the velocity scale)."""
VELOCITY_SCALE = (0.5, 1.5)
"""The range of the gait action's velocity scale (0 in the action = 1)."""
RESIDUAL_LIMIT = 0.02
"""Default bound of the residual tip offsets [m]."""
DAMPING = 1e-4
"""Damping of the residual's least-squares step [m²]."""


def unit_box(size: int) -> spaces.Box:
    return spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)


def around(a: float, low: float, default: float, high: float) -> float:
    """−1…0…1 onto low…default…high (piecewise linear, clipped)."""
    a = min(max(a, -1.0), 1.0)
    return default + a * (default - low) if a < 0 else default + a * (high - default)


class GaitAction:
    """Gait parameters per step cycle (see the module)."""

    def __init__(self, robot: Robot) -> None:
        self.specs = [getattr(robot.walker, name) for name in GAIT_PARAMETERS]
        self.space = unit_box(len(GAIT_PARAMETERS) + 1)
        self.throttle = robot.walker.velocity_input_mode == "throttle"
        self.values = {name: spec.default for name, spec in zip(GAIT_PARAMETERS, self.specs, strict=True)}
        self.scale = 1.0

    def set(self, action: np.ndarray) -> None:
        a = [float(x) for x in action]
        for name, spec, value in zip(GAIT_PARAMETERS, self.specs, a, strict=False):
            self.values[name] = around(value, spec.min, spec.default, spec.max)
        self.scale = around(a[-1], VELOCITY_SCALE[0], 1.0, VELOCITY_SCALE[1])

    def command(self, command: Command, current: dict[str, float], new_step_cycle: bool) -> Command:
        """``command`` with the velocity scaled and, at a new step cycle, the parameters that changed by at least
        half their adjustment step."""
        changes: dict[str, float] = {}
        if new_step_cycle:
            for name, spec in zip(GAIT_PARAMETERS, self.specs, strict=True):
                value = self.values[name]
                if abs(value - current[name]) >= max(spec.step / 2, 1e-9):
                    changes[name] = value
        if self.scale == 1.0 and not changes:
            return command
        velocity = tuple(v * self.scale for v in command.velocity)
        if self.throttle:
            velocity = tuple(min(max(v, -1.0), 1.0) for v in velocity)
        vx, vy, wz = velocity
        return replace(command, velocity=(vx, vy, wz), parameters={**command.parameters, **changes})


class ResidualAction:
    """Residual tip offsets (see the module)."""

    def __init__(self, robot: Robot, limit: float = RESIDUAL_LIMIT) -> None:
        self.chains = Chains.from_robot(robot)
        self.limit = limit
        self.legs = len(robot.legs)
        self.space = unit_box(3 * self.legs)
        self.offsets = np.zeros((self.legs, 3))
        self.rotation = self.chains.base[:, :3, :3]

    def set(self, action: np.ndarray) -> None:
        self.offsets = np.clip(np.asarray(action, dtype=float), -1.0, 1.0).reshape(self.legs, 3) * self.limit

    def adjust(self, out: CycleOutput) -> CycleOutput:
        if not self.offsets.any():
            return out
        chains = self.chains
        jacobians = np.matmul(self.rotation, chains.jacobians(out.joints))  # (L, 3, n) in base_link
        jt = np.swapaxes(jacobians, 1, 2)
        gram = np.matmul(jacobians, jt) + DAMPING * np.eye(3)
        dq = np.matmul(jt, np.linalg.solve(gram, self.offsets[:, :, None]))[:, :, 0]
        joints = np.clip(out.joints + dq, chains.lower, chains.upper)
        return replace(out, joints=joints)


class JointAction:
    """Raw joint targets (see the module)."""

    def __init__(self, robot: Robot) -> None:
        chains = Chains.from_robot(robot)
        self.slots = JointSlots.of(robot)
        self.lower, self.upper = chains.lower, chains.upper
        self.rows, self.cols = self.slots.rows, self.slots.cols
        self.space = unit_box(len(self.rows))
        self.targets: np.ndarray | None = None

    def set(self, action: np.ndarray) -> None:
        a = np.clip(np.asarray(action, dtype=float), -1.0, 1.0)
        low, high = self.lower[self.rows, self.cols], self.upper[self.rows, self.cols]
        targets = np.zeros_like(self.lower)
        targets[self.rows, self.cols] = low + (a + 1.0) / 2.0 * (high - low)
        self.targets = targets

    def adjust(self, out: CycleOutput) -> CycleOutput:
        if self.targets is None:
            return out
        return replace(out, joints=self.targets.copy())
