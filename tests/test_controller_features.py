"""Gait switching, cruise control and run-time parameter changes (study §4.3, §6, §9.6)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.gait import step_cycle
from shc_cli.control.walk import WalkState
from shc_cli.spec.loading import load_gait, load_robot


@pytest.fixture(scope="module")
def running() -> Controller:
    robot = load_robot("bullet_openshc").robot
    gait = load_gait("tripod").gait
    controller = Controller(robot, gait)
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    return controller


def _gait(name: str):  # type: ignore[no-untyped-def]
    gait = load_gait(name).gait
    return gait


@pytest.mark.parametrize("name", ["wave", "ripple", "amble", "bipod"])
def test_gait_switch_stops_then_walks_with_the_new_cycle(running: Controller, name: str) -> None:
    controller = copy.deepcopy(running)
    walk = Command(velocity=(1.0, 0.0, 0.0))
    for _ in range(300):
        controller.step(walk)
    assert controller.walker is not None and controller.walker.state == WalkState.MOVING
    states = [controller.step(Command(velocity=(1.0, 0.0, 0.0), gait=_gait(name))).walk_state]
    for _ in range(1500):
        states.append(controller.step(walk).walk_state)
        if controller.gait.name == name and states[-1] == WalkState.MOVING:
            break
    assert WalkState.STOPPED in states  # the switch happened through a controlled stop
    assert controller.gait.name == name
    expected = step_cycle(_gait(name), 1.1, 0.01)
    assert controller.cycle.period == expected.period
    offsets = controller.walker.legs.integers[:, 1].tolist()
    assert offsets == [expected.offsets[leg] for leg in controller.robot.legs]
    assert states[-1] == WalkState.MOVING


def test_bipod_walks_faster_than_tripod_at_full_throttle(running: Controller) -> None:
    """Paper eq. 16 with the walkspace limits: bipod 0.364 m/s vs tripod 0.232 m/s (study §14A)."""
    speeds = {}
    for name in ("tripod", "bipod"):
        controller = copy.deepcopy(running)
        controller.step(Command(gait=_gait(name)))
        for _ in range(600):
            out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
        speeds[name] = out.velocity[0]
    assert speeds["tripod"] == pytest.approx(0.231884, abs=1e-6)
    assert speeds["bipod"] == pytest.approx(0.364, abs=1e-3)


def test_cruise_control_holds_the_configured_velocity(running: Controller) -> None:
    controller = copy.deepcopy(running)
    controller.step(Command(cruise=True))
    for _ in range(400):
        out = controller.step(Command())  # no input: cruise drives
    assert out.velocity[0] == pytest.approx(0.231884, abs=1e-6)  # bullet cruise = throttle (1, 0)
    controller.step(Command(cruise=False))
    for _ in range(400):
        out = controller.step(Command())
    assert out.velocity[0] == 0.0


def test_cruise_time_limit_ends_the_override(running: Controller) -> None:
    controller = copy.deepcopy(running)
    cruise = controller.robot.cruise.model_copy(update={"time_limit": 1.0})
    controller.robot = controller.robot.model_copy(update={"cruise": cruise})
    controller.step(Command(cruise=True))
    velocities = [controller.step(Command()).velocity[0] for _ in range(400)]
    assert max(velocities) > 0.05
    assert velocities[-1] == 0.0  # after 1 s the (zero) inputs take over again


def test_step_frequency_change_waits_for_safe_speed_and_rephases(running: Controller) -> None:
    controller = copy.deepcopy(running)
    walk = Command(velocity=(1.0, 0.0, 0.0))
    for _ in range(400):
        controller.step(walk)
    walker = controller.walker
    assert walker is not None
    progress_before = walker.legs.floats[:, 2].copy()
    controller.step(Command(velocity=(1.0, 0.0, 0.0), parameters={"step_frequency": 0.8}))
    applied_after = None
    for cycle in range(1000):
        controller.step(walk)
        if controller.parameters["step_frequency"] == 0.8:
            applied_after = cycle
            break
    assert applied_after is not None and applied_after > 10  # it slowed down to the new limits first
    assert controller.cycle.period == step_cycle(controller.gait, 0.8, 0.01).period
    assert controller.cycle.period > 184
    assert progress_before.shape == (6,)
    for _ in range(500):
        out = controller.step(walk)
    assert out.walk_state == WalkState.MOVING
    assert out.velocity[0] < 0.2318  # slower steps, smaller speed limit


def test_swing_height_change_raises_the_apex(running: Controller) -> None:
    controller = copy.deepcopy(running)
    controller.step(Command(parameters={"swing_height": 0.15}))
    heights = []
    for _ in range(600):
        out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
        heights.append(out.walker_tips[:, 2].max())
    assert controller.parameters["swing_height"] == 0.15
    assert 0.145 < max(heights) <= 0.15


def test_parameters_are_clamped_to_their_range(running: Controller) -> None:
    controller = copy.deepcopy(running)
    controller.step(Command(parameters={"swing_height": 9.0}))
    assert controller.parameters["swing_height"] == 0.18


def test_stance_span_modifier_widens_the_stance_after_a_stop(running: Controller) -> None:
    controller = copy.deepcopy(running)
    controller.step(Command(parameters={"stance_span_modifier": 0.5}))
    for _ in range(300):
        controller.step(Command(velocity=(1.0, 0.0, 0.0)))
    for _ in range(600):
        out = controller.step(Command())
    assert out.walk_state == WalkState.STOPPED
    walker = controller.walker
    assert walker is not None
    defaults = walker.legs.vectors[:, 1]
    identity = np.array([[leg.stance.x, leg.stance.y] for leg in controller.robot.legs.values()])
    widened = np.abs(defaults[:, 1]) - np.abs(identity[:, 1])
    lateral = [controller.planes[leg][90 if leg.endswith("L") else 270] for leg in controller.robot.legs]
    np.testing.assert_allclose(widened, 0.5 * np.array(lateral), atol=1e-9)
    np.testing.assert_allclose(defaults[:, 0], identity[:, 0], atol=1e-12)


def test_auto_posing_moves_the_body_with_the_gait_and_lets_it_stop(tmp_path) -> None:  # type: ignore[no-untyped-def]
    """Bullet's tripod set lifts the body 0.01 m and rolls it ±0.05 rad each half cycle (poses/tripod.toml)."""
    from shc_cli.spec.autopose import load_auto_pose_set

    robot_file = tmp_path / "posing.toml"
    robot_file.write_text('extends = "bullet_openshc"\nname = "bullet_posing"\n[pose]\nauto = true\n')
    robot = load_robot(robot_file).robot
    gait = _gait("tripod")
    pose_set = load_auto_pose_set("auto", gait).pose_set
    controller = Controller(robot, gait, pose_sets={"tripod": pose_set})
    while controller.state != RobotState.RUNNING:
        controller.step(Command(state_request=RobotState.RUNNING))
    heights, rolls = [], []
    for _ in range(800):
        out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
        heights.append(out.pose[2])
        rolls.append(out.pose[3])
    assert max(heights) == pytest.approx(0.25 + 0.01, abs=1e-9)
    assert max(abs(r) for r in rolls) == pytest.approx(0.05, abs=1e-9)
    for _ in range(800):
        out = controller.step(Command())
    assert out.walk_state == WalkState.STOPPED
    assert out.pose[2] == pytest.approx(0.25, abs=1e-12)


def test_a_leg_is_lifted_for_manipulation_moved_and_returned(running: Controller) -> None:
    """Toggle AR to manual: all legs step (1/f_p s each), AR rises to swing height above the body-origin
    plane; tip velocity moves it at max_translation_velocity; toggling back puts it on its default tip."""
    from shc_cli.control.controller import LegMode

    controller = copy.deepcopy(running)
    robot = controller.robot
    controller.step(Command(leg_toggle="AR"))
    for _ in range(400):
        controller.step(Command())
        if controller.leg_modes[0] == LegMode.MANUAL:
            break
    assert controller.leg_modes[0] == LegMode.MANUAL
    stance = robot.legs["AR"].stance
    np.testing.assert_allclose(controller.model.tips[0], [stance.x, stance.y, 0.09], atol=1e-3)
    start = controller.model.tips[0].copy()
    for _ in range(100):  # 1 s at input (0, 0, 1): +0.05 m in z
        controller.step(Command(tip_velocity={"AR": (0.0, 0.0, 1.0)}))
    assert controller.model.tips[0][2] - start[2] == pytest.approx(0.05, abs=2e-3)
    out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
    assert out.walk_state == WalkState.STOPPED  # no walking while a leg is manual
    controller.step(Command(leg_toggle="AR"))
    for _ in range(400):
        controller.step(Command())
        if controller.leg_modes[0] == LegMode.WALKING:
            break
    assert controller.leg_modes[0] == LegMode.WALKING
    np.testing.assert_allclose(controller.model.tips[0], [stance.x, stance.y, -0.25], atol=1e-3)
    for _ in range(300):
        out = controller.step(Command(velocity=(1.0, 0.0, 0.0)))
    assert out.walk_state == WalkState.MOVING


def test_at_most_two_legs_can_be_manual(running: Controller) -> None:
    from shc_cli.control.controller import LegMode

    controller = copy.deepcopy(running)
    for leg in ("AR", "AL", "BR"):
        controller.step(Command(leg_toggle=leg))
        for _ in range(400):
            controller.step(Command())
            if controller.pending_toggle is None:
                break
    modes = [LegMode(m) for m in controller.leg_modes]
    assert modes.count(LegMode.MANUAL) == 2
    assert modes[list(controller.robot.legs).index("BR")] == LegMode.WALKING


def test_manual_posing_stops_at_the_limits_and_resets(running: Controller) -> None:
    """Bullet: max_translation z 0.2 m at 0.05 m/s, max_rotation roll 0.5 rad at 0.2 rad/s (study §7.2)."""
    from shc_cli.control.pose import PoseReset

    controller = copy.deepcopy(running)
    for _ in range(500):  # 5 s: z would reach 0.25 m and roll 1.0 rad without limits
        out = controller.step(Command(pose_velocity=(0.0, 0.0, 1.0, 1.0, 0.0, 0.0)))
    assert out.pose[2] == pytest.approx(0.25 + 0.2, abs=1e-12)
    assert out.pose[3] == pytest.approx(0.5, abs=1e-9)
    assert np.all(out.joints >= controller.model.chains.lower) and np.all(out.joints <= controller.model.chains.upper)
    for _ in range(300):  # z returns at 0.05 m/s (4 s), roll at 0.2 rad/s (2.5 s)
        out = controller.step(Command(pose_reset=PoseReset.ALL))
    assert out.pose[2] == pytest.approx(0.25 + 0.2 - 0.15, abs=1e-9)
    assert out.pose[3] == pytest.approx(0.0, abs=1e-12)
    out = controller.step(Command(pose_reset=PoseReset.IMMEDIATE_ALL))
    out = controller.step(Command())
    assert out.pose[2] == pytest.approx(0.25, abs=1e-12) and out.pose[3] == 0.0
