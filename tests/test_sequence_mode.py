"""OpenSHC's sequence mode through the controller: unpack, stepped start-up, walk, shut-down, pack (study §9.2–§9.3)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.sequence import joint_configurations
from shc_cli.control.walk import WalkState
from shc_cli.spec.loading import load_gait, load_robot


def _controller(tmp_path: Path, double: bool = False) -> Controller:
    robot_file = tmp_path / "sequence.toml"
    robot_file.write_text('extends = "bullet_openshc"\nname = "bullet_sequence"\n[start_up]\nsequence = true\n')
    robot = load_robot(robot_file).robot
    gait = load_gait("tripod").gait
    packed, _ = joint_configurations(robot)
    return Controller(robot, gait, joints=packed[-1].copy(), openshc_double_shutdown=double)


def _run_until(controller: Controller, state: RobotState, request: RobotState, limit: int = 5000) -> int:
    for cycle in range(limit):
        controller.step(Command(state_request=request))
        if controller.state == state:
            return cycle + 1
    raise AssertionError(f"{state.name} not reached in {limit} cycles")


def test_packed_robot_unpacks_starts_up_walks_and_packs_again(tmp_path: Path) -> None:
    controller = _controller(tmp_path)
    robot = controller.robot
    packed, unpacked = joint_configurations(robot)
    controller.step(Command(state_request=RobotState.RUNNING))
    assert controller.state == RobotState.PACKED  # estimated from the packed joints
    _run_until(controller, RobotState.READY, RobotState.RUNNING)
    np.testing.assert_array_equal(controller.model.joints, unpacked)  # a fresh unpack goes straight to unpacked
    _run_until(controller, RobotState.RUNNING, RobotState.RUNNING)
    stance = np.array([[leg.stance.x, leg.stance.y, -robot.walker.body_clearance] for leg in robot.legs.values()])
    assert np.abs(controller.model.tips - stance).max() < 1e-3  # the start-up sequence ends in the default stance
    for _ in range(300):
        out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
    assert out.walk_state == WalkState.MOVING
    _run_until(controller, RobotState.READY, RobotState.READY)
    assert controller.walker is not None and controller.walker.state == WalkState.STOPPED
    _run_until(controller, RobotState.PACKED, RobotState.PACKED)
    np.testing.assert_array_equal(controller.model.joints, packed[-1])


@pytest.mark.parametrize("double", [False, True])
def test_shut_down_takes_the_nominal_time_unless_openshc_speed_is_asked_for(tmp_path: Path, double: bool) -> None:
    """OpenSHC runs the shut-down two iterations per cycle (study §14 quirk 8); shc runs one by default."""
    controller = _controller(tmp_path, double)
    _run_until(controller, RobotState.RUNNING, RobotState.RUNNING)
    cycles = _run_until(controller, RobotState.READY, RobotState.READY)
    nominal = 2 * 91 + 273 + 91  # Bullet at 1.1 Hz: two group steps, the raise, the horizontal step
    expected = nominal // 2 if double else nominal
    assert abs(cycles - expected) <= 3


@pytest.mark.parametrize("direct_shutdown", [False, True])
def test_direct_mode_goes_back_down_only_when_asked_for(direct_shutdown: bool) -> None:
    """OpenSHC's direct mode only goes up; ``direct_shutdown`` (run-hw) stops walking and moves the joints back to
    where the robot started, in ``time_to_start``."""
    robot, gait = load_robot("bullet_openshc").robot, load_gait("tripod").gait
    assert robot is not None and gait is not None
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    rest = np.clip(np.full_like(chains.default_joints(), 0.3), chains.lower, chains.upper)  # "lying" joints
    controller = Controller(robot, gait, joints=rest.copy(), direct_shutdown=direct_shutdown)
    _run_until(controller, RobotState.RUNNING, RobotState.RUNNING)
    first_stance = controller.model.tips.copy()
    for _ in range(200):
        controller.step(Command(velocity=(1.0, 0.0, 0.0), state_request=RobotState.RUNNING))
    assert controller.walker is not None and controller.walker.state != WalkState.STOPPED  # walking
    if not direct_shutdown:
        for _ in range(100):
            controller.step(Command(state_request=RobotState.PACKED))
        assert controller.state == RobotState.RUNNING  # refused, as OpenSHC
        return
    _run_until(controller, RobotState.READY, RobotState.PACKED)
    assert controller.walker.state.name == "STOPPED"
    cycles = _run_until(controller, RobotState.PACKED, RobotState.PACKED)
    assert cycles == pytest.approx(robot.start_up.time_to_start / robot.time_delta, abs=2)
    np.testing.assert_allclose(controller.model.joints, rest, atol=1e-12)
    _run_until(controller, RobotState.RUNNING, RobotState.RUNNING)  # and up again, to the same stance
    np.testing.assert_allclose(controller.model.tips, first_stance, atol=1e-4)
