"""A policy file driving the one run loop (``shc simulate --policy FILE``, ``shc run-hw --policy FILE``).

The policy acts as it does in ``shc/Walk-v0``: once the robot is RUNNING and the input plays, after every cycle
the observation (:func:`~shc_cli.loop.policy.observe.observe`) gives the next cycle's action; a ``gait`` action
changes the input's commands (its parameters within their ranges, the velocity scale within the throttle), a
``residual`` or ``joints`` action the controller's joint targets (:data:`~shc_cli.loop.run_loop.Adjust`). Before
RUNNING and from a stop request or the input's end on (the controlled stop of ``run-hw``) the policy does nothing:
the controller alone starts up, stops and shuts down. Everything after the controller's output — the backend's
clamps to the joint limits and speed limits, ``run-hw``'s checks and fault handling — is unchanged.

On servos the reading has joint positions and velocities only: the rest of the observation (orientation, rates,
foot contacts and forces) is what a robot without those sensors gives: an upright body at rest, no contact.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.backends.base import FeedbackSource, InputSource
from shc_cli.control.controller import Command, CycleOutput
from shc_cli.control.states import RobotState
from shc_cli.errors import Issue, SpecError
from shc_cli.loop.policy.actions import GaitAction, JointAction, ResidualAction
from shc_cli.loop.policy.file import Policy, PolicyFileError
from shc_cli.loop.policy.observe import observation_names, observe
from shc_cli.loop.run_loop import RunLoop
from shc_cli.model.chains import JointSlots
from shc_cli.spec.robot import Robot


def _bad(what: str, fix: str) -> SpecError:
    return SpecError([Issue(None, None, "--policy", what, fix)])


class _Unmeasured:
    """A servo bus's reading as the observation reads it (:mod:`the module <shc_cli.loop.policy.drive>`)."""

    def __init__(self, reading: Any, legs: int) -> None:
        self.joints, self.joint_velocities = reading.positions, reading.velocities
        self.orientation = np.array([0.0, 0.0, 0.0, 1.0])
        self.angular_rate = np.zeros(3)
        self.foot_contact = self.foot_forces = np.zeros(legs)


class _Commands:
    """The input with the gait action applied (once a step cycle, as ``shc/Walk-v0`` does)."""

    def __init__(self, source: InputSource, drive: PolicyDrive) -> None:
        self.source, self.drive = source, drive
        if isinstance(source, FeedbackSource):  # a path follower still sees every output
            self.observe = source.observe

    def next(self) -> Command | None:
        command = self.source.next()
        return None if command is None else self.drive.gait_command(command)

    def close(self) -> None:
        self.source.close()


class PolicyDrive:
    """A policy on one robot's loop: :meth:`source` wraps the input, :meth:`adjust` and :meth:`join` gives the
    :class:`~shc_cli.loop.run_loop.RunLoop` its :meth:`adjust` and :meth:`observer`."""

    def __init__(self, policy: Policy, robot: Robot, source: str = "policy", hardware: bool = False) -> None:
        names = observation_names(robot)
        if (policy.names and list(policy.names) != names) or policy.observations != len(names):
            raise _bad(f"{source}: the policy takes {policy.observations} observations, {robot.name} gives "
                       f"{len(names)}", "use a policy trained on this robot (shc/Walk-v0 with robot=...)")
        if hardware and policy.action == "joints":
            raise _bad(f"{source}: a 'joints' policy replaces the controller's targets",
                       "on servos use a 'gait' or 'residual' policy (within the controller's ranges)")
        self.policy, self.robot, self.hardware = policy, robot, hardware
        self.slots = JointSlots.of(robot)
        self.gait = GaitAction(robot) if policy.action == "gait" else None
        self.residual = ResidualAction(robot, policy.residual_limit) if policy.action == "residual" else None
        self.joints = JointAction(robot) if policy.action == "joints" else None
        self.zero = np.zeros(policy.actions, dtype=np.float32)
        self.loop: RunLoop[Any] | None = None
        self.acting = False
        self.actions = 0
        """Cycles the policy chose the action of."""
        self._cycles_in_step, self._period = 0, 1
        self._set(self.zero)

    @classmethod
    def load(cls, path: Path, robot: Robot, hardware: bool = False) -> PolicyDrive:
        """The policy file at ``path`` on ``robot``; a one-line SpecError when it cannot be read or does not fit."""
        try:
            policy = Policy.load(path)
        except PolicyFileError as error:
            raise _bad(str(error), "give a policy file (.npz) of shc_cli.loop.policy.file") from None
        return cls(policy, robot, str(path), hardware)

    def _set(self, action: np.ndarray) -> None:
        if self.gait is not None:
            self.gait.set(action)
        elif self.residual is not None:
            self.residual.set(action)
        elif self.joints is not None:
            if action is self.zero:
                self.joints.targets = None
            else:
                self.joints.set(action)

    def source(self, source: InputSource) -> InputSource:
        """The input with the gait action (unchanged for the other actions)."""
        return _Commands(source, self) if self.gait is not None else source

    def gait_command(self, command: Command) -> Command:
        assert self.gait is not None and self.loop is not None
        controller = self.loop.controller
        self._cycles_in_step += 1
        new_cycle = self._cycles_in_step >= self._period
        if new_cycle:
            self._cycles_in_step, self._period = 0, controller.cycle.period
        return self.gait.command(command, controller.parameters, new_cycle)

    def adjust(self, out: CycleOutput) -> CycleOutput:
        """The controller's output with the residual or joint action (while the policy acts)."""
        if not self.acting:
            return out
        if self.residual is not None:
            return self.residual.adjust(out)
        if self.joints is not None:
            return self.joints.adjust(out)
        return out

    def observer(self, cycle: int, command: Command, out: CycleOutput, reading: Any) -> str | None:
        """After a cycle: the next cycle's action from this one's observation, while RUNNING and no stop is due."""
        loop = self.loop
        assert loop is not None
        if loop.controller.state != RobotState.RUNNING or loop.stop_reason is not None or loop.requested:
            if self.acting:
                self.acting = False
                self._set(self.zero)
            return None
        sensed: Any = _Unmeasured(reading, self.slots.legs) if self.hardware else reading
        self._set(self.policy(observe(self.slots, sensed, out)))
        self.acting = True
        self.actions += 1
        return None

    def join(self, loop: RunLoop[Any]) -> None:
        """Drive ``loop`` (built over :meth:`source`'s input): its adjust and an observer."""
        self.loop = loop
        loop.adjust = self.adjust
        loop.observers.append(self.observer)
