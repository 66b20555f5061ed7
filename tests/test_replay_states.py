"""Property: a run of shc's own controller, recorded as OpenSHC's recorder records (inputs seen one cycle before
they act), replays with no difference at all — whatever the timing of its state changes. This checks the replay's
plumbing (joint and leg mapping, input latency, state inference) on runs the golden recordings do not cover: a long
READY plateau before RUNNING (a stall), and the start-up *sequence* with a shut-down requested at the end."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.control.sequence import joint_configurations
from shc_cli.replay import replay
from shc_cli.replay.compare import joint_names
from shc_cli.replay.source import Recorded
from shc_cli.spec.gait import Gait
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Robot


def record(robot: Robot, gait: Gait, joints: np.ndarray | None, velocity: np.ndarray,
           requests: list[RobotState | None], remote: np.ndarray) -> tuple[Recorded, list[CycleOutput]]:
    """Run the controller with ``velocity[c]`` and ``requests[c]`` in cycle ``c`` (``remote[c]``: the robot state
    the remote asks for then); record what the recorder would see: the inputs received before cycle ``c``'s output
    are those that act in cycle ``c + 1``. The controller runs OpenSHC's IK step (``ik.limit_avoidance_cap`` 0), as
    the replay does: the run stands in for a recording of OpenSHC."""
    openshc = robot.model_copy(update={"ik": robot.ik.model_copy(update={"limit_avoidance_cap": 0.0})})
    controller = Controller(openshc, gait, joints=joints)
    outputs = [controller.step(Command(velocity=tuple(v), state_request=r))
               for v, r in zip(velocity, requests, strict=True)]
    n = len(outputs)
    seen = np.vstack([velocity[1:], velocity[-1:]])
    stack = np.stack
    recorded = Recorded(
        source=Path("emulated"), kind="recording", t=np.arange(n) * robot.time_delta, joint_names=joint_names(robot),
        joints=stack([o.joints.ravel() for o in outputs]), command=seen,
        robot_state=np.append(remote[1:], remote[-1]), legs=list(robot.legs),
        tips={"walker": stack([o.walker_tips for o in outputs]), "poser": stack([o.poser_tips for o in outputs]),
              "model": stack([o.model_tips for o in outputs])},
        progress=stack([np.column_stack([o.stance_progress, o.swing_progress]) for o in outputs]),
        velocity=np.array([o.velocity for o in outputs]), pose=np.array([o.pose for o in outputs]))
    return recorded, outputs


def exact(recorded: Recorded, robot: Robot, gait: Gait) -> dict[str, float]:
    return replay(recorded, robot, gait).comparison.worst


def test_a_long_stall_before_running_replays_exactly(bullet: Robot, tripod: Gait) -> None:
    n, start, running = 1000, 5, 537  # READY reached at 504; RUNNING 32 cycles later
    velocity = np.zeros((n, 3))
    velocity[600:900] = (0.8, 0.0, 0.2)
    requests: list[RobotState | None] = [RobotState.RUNNING] + [None] * (start - 1) + \
        [RobotState.READY] * (running - start) + [RobotState.RUNNING] * (n - running)
    recorded, outputs = record(bullet, tripod, None, velocity, requests, np.full(n, 2.0))
    assert outputs[running - 1].robot_state == RobotState.READY and outputs[running].robot_state == RobotState.RUNNING
    result = replay(recorded, bullet, tripod)
    assert (result.plan.first_motion, result.plan.running) == (start, running)
    assert max(result.comparison.worst.values()) == 0.0
    assert result.comparison.skipped["poser_tip_m"] == running * 18  # unposed (2147483647) until RUNNING


@pytest.fixture(scope="module")
def sequence_robot(tmp_path_factory: pytest.TempPathFactory) -> Robot:
    robot_file = tmp_path_factory.mktemp("robot") / "sequence.toml"
    robot_file.write_text('extends = "bullet_openshc"\nname = "bullet_sequence"\n[start_up]\nsequence = true\n')
    robot = load_robot(robot_file).robot
    return robot


def test_the_start_up_sequence_and_a_later_shut_down_replay_exactly(sequence_robot: Robot, tripod: Gait) -> None:
    n, walk, down = 3000, (1200, 1500), 2200  # RUNNING from 1153, READY again at ~2745
    velocity = np.zeros((n, 3))
    velocity[walk[0]:walk[1]] = (1.0, 0.0, 0.0)
    requests: list[RobotState | None] = [*[RobotState.RUNNING] * down, *[RobotState.READY] * (n - down)]
    remote = np.array([2.0] * down + [1.0] * (n - down))  # the remote's request acting in each cycle
    packed, _ = joint_configurations(sequence_robot)
    recorded, outputs = record(sequence_robot, tripod, packed[-1].copy(), velocity, requests, remote)
    states = [o.robot_state for o in outputs]
    assert RobotState.RUNNING in states[:walk[0]] and states[-1] == RobotState.READY  # started, walked, shut down
    result = replay(recorded, sequence_robot, tripod)
    assert result.plan.later == [(down, RobotState.READY)]
    assert max(result.comparison.worst.values()) == 0.0
    assert result.robot_states == states
