"""Replaying a recorded run: the controller on the recorded inputs through the one run loop, compared cycle by
cycle (:func:`replay`); the package's text says how the parts fit."""


from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.control.walk import WalkState
from shc_cli.replay.compare import Comparer, Comparison
from shc_cli.replay.recorded_inputs import ReplayInputs, retime_changes
from shc_cli.replay.source import Recorded, usable
from shc_cli.replay.states import StatePlan, infer_states
from shc_cli.spec.autopose import AutoPoseSet
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot


@dataclass
class Replay:
    """A finished replay: the comparison, the inferred states and the controller's state in each cycle."""

    recorded: Recorded
    plan: StatePlan
    comparison: Comparison
    robot_states: list[RobotState]
    walk_states: list[WalkState]
    retimed: list[tuple[int, int]]
    """Velocity changes moved from the latency's cycle to the one the data shows: (cycle, shift)."""


def initial_joints(recorded: Recorded, comparer: Comparer, robot: Robot) -> np.ndarray | None:
    """The recorded joints of the first cycle ``(L, n)`` [rad] (OpenSHC starts from them), or ``None`` (the
    controller's default) if any is unusable."""
    first = comparer.joints[0] if recorded.cycles else np.zeros(0)
    if len(first) == 0 or not usable(first).all():
        return None
    return first.reshape(len(robot.legs), -1)


def replay(recorded: Recorded, robot: Robot, gait: Gait, pose_sets: dict[str, AutoPoseSet] | None = None,
           plan: StatePlan | None = None) -> Replay:
    """Run the controller on the recorded inputs, cycle by cycle, and compare its outputs with the recorded ones;
    ``plan`` replaces the state requests inferred from the data (:func:`~shc_cli.replay.states.infer_states`).

    The controller runs OpenSHC's IK step (``ik.limit_avoidance_cap`` 0, whatever the robot file says): the
    recording's redundant legs carry OpenSHC's every-cycle null-space alternation (docs/deviations.md)."""
    robot = robot.model_copy(update={"ik": robot.ik.model_copy(update={"limit_avoidance_cap": 0.0})})
    comparer = Comparer(recorded, robot)
    plan = plan or infer_states(recorded, robot)
    inputs = ReplayInputs(recorded, plan)
    start = initial_joints(recorded, comparer, robot)
    retime_changes(inputs, Controller(robot, gait, joints=start, pose_sets=pose_sets), comparer.joints)
    controller = Controller(robot, gait, joints=start, pose_sets=pose_sets)
    robot_states: list[RobotState] = []
    walk_states: list[WalkState] = []

    def observe(cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        comparer.add(cycle, out)
        robot_states.append(out.robot_state)
        walk_states.append(out.walk_state)
        return None

    from shc_cli.backends.kinematic import KinematicBackend
    from shc_cli.loop.assembly import RunSpec, assemble
    from shc_cli.loop.run_loop import NullRecorder, SequenceInput

    commands = SequenceInput(inputs.command(cycle) for cycle in range(recorded.cycles))
    assemble(lambda _: RunSpec(controller, KinematicBackend(), commands, NullRecorder(), start_up=None,
                               observers=[observe]))  # no run directory: compared, not recorded
    return Replay(recorded, plan, comparer.result(), robot_states, walk_states, inputs.retimed)
