"""OpenSHC's sequence mode: pack/unpack, stepToPosition, start-up/shut-down sequences, state estimate (study §9.2–§9.3).

Expectations are derived by hand (iteration counts, Bernstein weights, geometry), not from the code under test.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import numpy as np
import pytest

from shc_cli.control.pose import Pose
from shc_cli.control.sequence import (
    GENERATING,
    PROGRESS_COMPLETE,
    TRANSITION_STEP_THRESHOLD,
    Configuration,
    PackDirection,
    PackTransition,
    Sequence,
    SequenceError,
    SequenceKind,
    StepToPosition,
    estimate_state,
    joint_configurations,
    legs_bearing_load,
)
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.ik import ik_step
from shc_cli.spec.robot import Robot

DT = 0.01
F_BULLET = 1.1
PACK_CYCLES = 182  # round((2.0 / 1.1) / 0.01) = round(181.818…)


# -- helpers ---------------------------------------------------------------------------------------------------------


@dataclass
class Legs:
    """The model state a controller would own: desired joints, velocities, FK tips; one IK step per active leg."""

    robot: Robot
    chains: Chains
    q: FloatArray
    qd: FloatArray = field(init=False)
    tips: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        self.qd = np.zeros_like(self.q)
        self.tips = self.chains.tips(self.q)

    def solve(self, targets: FloatArray, active: np.ndarray) -> FloatArray:
        step = ik_step(self.chains, self.q, self.qd, self.tips, targets, self.robot.time_delta,
                       clamp_velocities=self.robot.ik.clamp_joint_velocities)
        keep = active[:, None]
        self.q = np.where(keep, step.q, self.q)
        self.qd = np.where(keep, step.qd, self.qd)
        self.tips = np.where(keep, step.tip, self.tips)
        return step.result


@dataclass
class Trace:
    progress: list[int] = field(default_factory=list)
    active: list[np.ndarray] = field(default_factory=list)
    targets: list[FloatArray] = field(default_factory=list)
    steps: list[int] = field(default_factory=list)
    """Transition step at the start of each cycle."""


def run(sequence: Sequence, kind: SequenceKind, legs: Legs, default: FloatArray, limit: int = 5000) -> Trace:
    """Run ``kind`` to completion as the controller would (one iteration per cycle) and record each cycle."""
    trace = Trace()
    robot = legs.robot
    for _ in range(limit):
        trace.steps.append(sequence.transition_step)  # the transition this cycle belongs to
        plan = sequence.begin(kind, legs.tips, default, F_BULLET, robot.walker.swing_height.default)
        progress = sequence.finish(legs.solve(plan.targets, plan.active))
        trace.progress.append(progress)
        trace.active.append(plan.active)
        trace.targets.append(plan.targets)
        if progress == PROGRESS_COMPLETE:
            return trace
    raise AssertionError("sequence did not finish")


def stance(robot: Robot) -> FloatArray:
    """Default tips in base_link at start-up: (x_s, y_s, −body_clearance)."""
    clearance = robot.walker.body_clearance
    return np.array([[leg.stance.x, leg.stance.y, -clearance] for leg in robot.legs.values()])


@pytest.fixture(scope="module")
def bullet_legs(bullet: Robot) -> tuple[Chains, FloatArray, FloatArray]:
    chains = Chains.from_robot(bullet)
    packed, unpacked = joint_configurations(bullet, chains.joints)
    return chains, packed, unpacked


@pytest.fixture(scope="module")
def discovered(bullet: Robot, bullet_legs: tuple[Chains, FloatArray, FloatArray]) -> tuple[Sequence, Legs, Trace]:
    """The first START_UP of Bullet from its unpacked joints (discovery)."""
    chains, _, unpacked = bullet_legs
    legs = Legs(bullet, chains, unpacked.copy())
    sequence = Sequence(len(bullet.legs), bullet.time_delta)
    trace = run(sequence, SequenceKind.START_UP, legs, stance(bullet))
    return sequence, legs, trace


# -- joint configurations and pack / unpack --------------------------------------------------------------------------


def test_bullet_configurations_are_read_per_step(bullet_legs: tuple[Chains, FloatArray, FloatArray]) -> None:
    _, packed, unpacked = bullet_legs
    assert packed.shape == (2, 6, 5)
    np.testing.assert_array_equal(packed[1, 0], [-1.493, -2.390, 0.278, 1.390, 1.532])  # AR packed_1
    np.testing.assert_array_equal(packed[1, 5], [1.493, 2.390, 0.278, 1.390, 1.532])  # AL mirrors coxa/coxat
    np.testing.assert_array_equal(unpacked[0], [0.0, 0.0, 1.088, -0.765, -1.212])


def test_pack_visits_packed_0_then_packed_1_in_2_over_fp_seconds_each(
        bullet_legs: tuple[Chains, FloatArray, FloatArray]) -> None:
    _, packed, unpacked = bullet_legs
    packer = PackTransition(packed, unpacked, DT)
    q = unpacked.copy()
    history = []
    for _ in range(2 * PACK_CYCLES):
        cycle = packer.step(PackDirection.PACK, q, F_BULLET)
        q = cycle.joints
        history.append((cycle.progress, q.copy()))
    # End of the first sub-transition: exactly packed_0, reported as 0 % (an intermediate step).
    assert history[PACK_CYCLES - 1][0] == 0
    np.testing.assert_array_equal(history[PACK_CYCLES - 1][1], packed[0])
    assert all(p < PROGRESS_COMPLETE for p, _ in history[:-1])
    # End: exactly packed_1 (outside the joint limits: no clamping, quirk 17) and 100 %.
    assert history[-1][0] == PROGRESS_COMPLETE
    np.testing.assert_array_equal(history[-1][1], packed[1])
    assert packed[1, 0, 3] > 0.001  # tibia packed beyond its max
    # Cubic profile at the first cycle: τ = 1/n, q = o + (t − o)(3τ² − 2τ³).
    tau = 1.0 / PACK_CYCLES
    expected = unpacked + (packed[0] - unpacked) * (3 * tau**2 - 2 * tau**3)
    np.testing.assert_allclose(history[0][1], expected, rtol=0, atol=1e-15)
    assert history[0][0] == 1  # progress clamped to at least 1 %
    assert history[91][0] == 50  # cycle 92: int(91/182 · 100)
    # The second sub-transition starts from packed_0 on the very next cycle, again at τ = 1/n.
    expected = packed[0] + (packed[1] - packed[0]) * (3 * tau**2 - 2 * tau**3)
    np.testing.assert_allclose(history[PACK_CYCLES][1], expected, rtol=0, atol=1e-15)


def test_unpack_after_pack_retraces_then_reaches_unpacked(bullet_legs: tuple[Chains, FloatArray, FloatArray]) -> None:
    _, packed, unpacked = bullet_legs
    packer = PackTransition(packed, unpacked, DT)
    q = unpacked.copy()
    for _ in range(2 * PACK_CYCLES):
        q = packer.step(PackDirection.PACK, q, F_BULLET).joints
    progress = []
    for count in range(1, 2 * PACK_CYCLES + 1):
        cycle = packer.step(PackDirection.UNPACK, q, F_BULLET)
        q = cycle.joints
        progress.append(cycle.progress)
        if count == PACK_CYCLES:
            np.testing.assert_array_equal(q, packed[0])
    assert progress[PACK_CYCLES - 1] == 0 and progress[-1] == PROGRESS_COMPLETE
    np.testing.assert_array_equal(q, unpacked)
    assert packer.pack_step == 0


def test_fresh_unpack_goes_straight_to_unpacked_quirk_10(bullet_legs: tuple[Chains, FloatArray, FloatArray]) -> None:
    _, packed, unpacked = bullet_legs
    packer = PackTransition(packed, unpacked, DT)  # robot found packed at start-up: pack_step is 0
    q = packed[-1].copy()
    for count in range(1, PACK_CYCLES + 1):
        cycle = packer.step(PackDirection.UNPACK, q, F_BULLET)
        q = cycle.joints
        assert (cycle.progress == PROGRESS_COMPLETE) == (count == PACK_CYCLES)
    np.testing.assert_array_equal(q, unpacked)
    # The fix: start at the last pack step and the unpack retraces packed_0 first.
    fixed = PackTransition(packed, unpacked, DT, pack_step=len(packed) - 1)
    q = packed[-1].copy()
    for _ in range(PACK_CYCLES):
        q = fixed.step(PackDirection.UNPACK, q, F_BULLET).joints
    np.testing.assert_array_equal(q, packed[0])


# -- stepToPosition --------------------------------------------------------------------------------------------------


def _bernstein4(nodes: np.ndarray, t: float) -> np.ndarray:
    weights = [(1 - t) ** 4, 4 * t * (1 - t) ** 3, 6 * t**2 * (1 - t) ** 2, 4 * t**3 * (1 - t), t**4]
    return sum(w * n for w, n in zip(weights, nodes, strict=True))  # type: ignore[no-any-return]


def test_step_to_position_endpoints_apex_and_first_iteration() -> None:
    origin = np.array([[0.20, -0.40, -0.10]])
    target = np.array([[0.30, -0.35, -0.10]])
    lift, n = 0.05, 100  # T = 1 s at dt = 0.01
    stepper = StepToPosition(1, DT)
    active = np.array([True])
    tips, progress = [], []
    for _ in range(n):
        progress.append(int(stepper.step(origin, target, lift, 1.0, active)[0]))
        tips.append(stepper.current[0].copy())
    tips_arr = np.array(tips)
    # First iteration: τ = 2/n on the primary curve [o, o, o+h, t + ¾(o−t) + h, t + ½(o−t) + h].
    o, t, h = origin[0], target[0], np.array([0.0, 0.0, lift])
    primary = np.array([o, o, o + h, t + 0.75 * (o - t) + h, t + 0.5 * (o - t) + h])
    np.testing.assert_allclose(tips_arr[0], _bernstein4(primary, 2.0 / n), atol=1e-15)
    # Middle (iteration n/2, τ = 1): the midpoint lifted by h, the highest point of the path.
    np.testing.assert_allclose(tips_arr[n // 2 - 1], (o + t) / 2 + h, atol=1e-15)
    assert tips_arr[:, 2].max() == pytest.approx(o[2] + lift, abs=1e-15)
    # End: exactly on the target, 100 % only on the last iteration.
    np.testing.assert_allclose(tips_arr[-1], t, atol=1e-15)
    assert progress[0] == 0 and progress[n // 2] == 50 and progress[-1] == PROGRESS_COMPLETE
    assert PROGRESS_COMPLETE not in progress[:-1]
    # Horizontal projection is the straight segment o → t (both curves' xy nodes lie on it).
    direction = (t - o)[:2] / np.linalg.norm((t - o)[:2])
    offsets = tips_arr[:, :2] - o[:2]
    np.testing.assert_allclose(offsets[:, 0] * direction[1] - offsets[:, 1] * direction[0], 0.0, atol=1e-15)


def test_step_to_position_applies_the_body_pose_by_smooth_step() -> None:
    origin = np.array([[0.3, -0.35, 0.0]])
    target = np.array([[0.3, -0.35, 0.0]]) + np.array([[0.0, 0.05, 0.0]])
    body = Pose(np.array([0.0, 0.0, 0.1]))
    n = 50
    stepper = StepToPosition(1, DT)
    for _ in range(n):
        stepper.step(origin, target, 0.0, 0.5, np.array([True]), body)
    # Last iteration: body share smoothStep((n−1)/n) = 1 − 10/n³ + O(n⁻⁴), tip = t − share·(0, 0, 0.1).
    x = (n - 1) / n
    share = 6 * x**5 - 15 * x**4 + 10 * x**3
    np.testing.assert_allclose(stepper.current[0], target[0] - np.array([0.0, 0.0, 0.1 * share]), atol=1e-15)


def test_step_to_position_near_target_without_lift_finishes_at_once() -> None:
    tip = np.array([[0.3, -0.35, -0.25]])
    stepper = StepToPosition(1, DT)
    progress = stepper.step(tip, tip + 0.005, 0.0, 1.0, np.array([True]))
    assert progress[0] == PROGRESS_COMPLETE
    np.testing.assert_array_equal(stepper.current[0], tip[0])  # it holds its own tip
    # With a lift the same leg does step.
    assert stepper.step(tip, tip + 0.005, 0.02, 1.0, np.array([True]))[0] == 0


def test_step_to_position_odd_iteration_count_still_lands() -> None:
    """n = 545 (Bullet's discovery lowering): the last τ is 546/545 but the curve is flat there."""
    origin, target = np.array([[0.2, -0.47, -0.006]]), np.array([[0.2, -0.47, -0.25]])
    stepper = StepToPosition(1, DT)
    for _ in range(545):
        stepper.step(origin, target, 0.0, 2 * 3.0 / F_BULLET, np.array([True]))
    assert np.abs(stepper.current[0] - target[0]).max() < 1e-7


# -- start-up discovery, replays, shut-down --------------------------------------------------------------------------


def test_bullet_start_up_discovery_ends_at_the_default_stance(
        bullet: Robot, discovered: tuple[Sequence, Legs, Trace]) -> None:
    sequence, legs, trace = discovered
    assert np.abs(legs.tips - stance(bullet)).max() < 1e-3
    assert set(trace.progress[:-1]) == {GENERATING} and trace.progress[-1] == PROGRESS_COMPLETE
    assert not sequence.discovering
    # Stored poses: index 0 is the start tip, the last one the target stance; each leg has one per transition.
    # Step 0 raises a proximity alert, step 1 (lowering) is clean, so step 2 is the last: three transitions.
    count = sequence.transition_step_count
    assert count == 3 and sequence.transition_step == count
    for leg, poses in enumerate(sequence.transition_poses):
        assert len(poses) == count + 1
        np.testing.assert_array_equal(poses[0], sequence.transition_poses[leg][0])
        # xy exactly the stance; z the height kept from the lowering (IK lag ≈ 2e-5 m).
        np.testing.assert_allclose(poses[-1][:2], stance(bullet)[leg][:2], atol=1e-12)
        assert poses[-1][2] == pytest.approx(-bullet.walker.body_clearance, abs=1e-4)


def test_bullet_discovery_transitions_alternate_and_use_groups(
        bullet: Robot, discovered: tuple[Sequence, Legs, Trace]) -> None:
    """Unpacked tips hang 6 mm below the body (not bearing load): the first horizontal step moves all legs without
    lift; after the lowering (2·3/f_p s = 545 cycles) the legs bear the load and step in groups id % 2, group 0
    first, each with the swing-height lift, over 2·1/f_p s = 182 cycles."""
    sequence, _, trace = discovered
    steps = np.array(trace.steps)
    active = np.array(trace.active)
    starts = np.flatnonzero(np.diff(np.concatenate([[0], steps])) != 0)  # cycles where a transition ended
    lowering = np.flatnonzero(steps == 1)
    assert len(lowering) == 545  # vertical transition 1 → 2, all legs
    assert active[lowering].all()
    # Step 0 (horizontal, not bearing load): all legs start at once, without lift (heights kept); each leg stops
    # on its own when its limit proximity drops below 0.15.
    first = np.flatnonzero(steps == 0)
    assert active[first[0]].all()
    targets = np.array(trace.targets)
    heights = targets[first][:, :, 2][active[first]]
    np.testing.assert_allclose(heights, sequence.transition_poses[0][0][2], atol=1e-12)
    # Last horizontal step (bearing load): group 0 (AR, CR, BL) for 182 cycles, then group 1 (BR, CL, AL).
    final = np.flatnonzero(steps == sequence.transition_step_count - 1)
    assert len(final) == 2 * 182
    group0, group1 = final[:182], final[182:]
    assert (active[group0] == [True, False, True, False, True, False]).all()
    assert (active[group1] == [False, True, False, True, False, True]).all()
    apex = targets[group0][:, 0, 2].max()
    kept_height = sequence.transition_poses[0][-1][2]
    assert apex == pytest.approx(kept_height + bullet.walker.swing_height.default, abs=1e-12)
    assert len(starts) >= 2


def test_bullet_shut_down_replays_the_sequence_backwards(
        bullet: Robot, bullet_legs: tuple[Chains, FloatArray, FloatArray],
        discovered: tuple[Sequence, Legs, Trace]) -> None:
    sequence, legs, _ = discovered
    chains, _, unpacked = bullet_legs
    replay = Legs(bullet, chains, legs.q.copy())
    count = sequence.transition_step_count
    trace = run(sequence, SequenceKind.SHUT_DOWN, replay, stance(bullet))
    # Transition steps count down count → 0, progress rises 0..99 then 100.
    steps = [*trace.steps, sequence.transition_step]
    assert steps[0] == count and steps[-1] == 0
    assert all(b in (a, a - 1) for a, b in itertools.pairwise(steps))
    assert trace.progress[-1] == PROGRESS_COMPLETE
    assert all(0 <= p < PROGRESS_COMPLETE for p in trace.progress[:-1])
    assert trace.progress[:-1] == sorted(trace.progress[:-1])
    # The robot ends at the start tips (transition pose 0), i.e. the unpacked tips.
    np.testing.assert_allclose(replay.tips, chains.tips(unpacked), atol=1e-3)
    # Nominal times: lowering undone in 3/f_p s (273 cycles); last step (not bearing load) all legs in 1/f_p s.
    # Steps 3 → 2 (horizontal, bearing load: two groups of 1/f_p s = 91 cycles), 2 → 1 (raise, 3/f_p s = 273 cycles),
    # 1 → 0 (horizontal, tips back near the body underside: all legs at once, 91 cycles).
    assert [trace.steps.count(k) for k in (3, 2, 1)] == [2 * 91, 273, 91]
    assert np.array(trace.active)[:91].tolist() == [[True, False, True, False, True, False]] * 91
    # A second START_UP replays forwards back to the stance, without discovery.
    again = run(sequence, SequenceKind.START_UP, replay, stance(bullet))
    assert GENERATING not in again.progress
    assert np.abs(replay.tips - stance(bullet)).max() < 1e-3


def test_discovery_that_never_settles_raises() -> None:
    """Every IK step reports a limit hit: every transition stops early and the sequence never completes."""
    legs = 6
    tips = np.array([[0.3, -0.3, -0.2]] * legs)
    default = tips + np.array([0.05, 0.0, -0.05])
    sequence = Sequence(legs, DT)
    with pytest.raises(SequenceError, match="transitions"):
        for _ in range(1000):
            sequence.step(SequenceKind.START_UP, tips, default, 1.0, 0.05, lambda t, a: np.zeros(legs))
    assert sequence.transition_step == TRANSITION_STEP_THRESHOLD + 1


def test_shut_down_needs_a_start_up_first() -> None:
    tips = np.zeros((6, 3))
    with pytest.raises(SequenceError, match="start-up"):
        Sequence(6, DT).begin(SequenceKind.SHUT_DOWN, tips, tips, 1.0, 0.05)


def test_legs_bear_load_below_half_body_depth() -> None:
    assert not legs_bearing_load(np.array([[0.0, 0.0, -0.05]]))  # strict: exactly −0.05 is not bearing
    assert legs_bearing_load(np.array([[0.0, 0.0, -0.0500001]]))
    assert not legs_bearing_load(np.array([[0.0, 0.0, -0.09], [0.0, 0.0, 0.0]]))  # mean −0.045


# -- state estimation ------------------------------------------------------------------------------------------------


def test_state_estimate_from_packed_and_unpacked_joints(bullet_legs: tuple[Chains, FloatArray, FloatArray]) -> None:
    _, packed, unpacked = bullet_legs
    last = packed[-1]
    exact_packed = estimate_state(last, last, unpacked, sequence_mode=True)
    assert exact_packed.configuration is Configuration.PACKED and not exact_packed.ready
    assert "undefined" in exact_packed.messages[-1]  # the source's else-branch also fires
    assert estimate_state(last + 0.009, last, unpacked, True).configuration is Configuration.PACKED
    exact_ready = estimate_state(unpacked, last, unpacked, sequence_mode=True)
    assert exact_ready.configuration is Configuration.READY and exact_ready.ready
    perturbed = unpacked.copy()
    perturbed[3, 2] += 0.0099
    assert estimate_state(perturbed, last, unpacked, True).ready
    perturbed[3, 2] += 0.0002  # 0.0101 rad off on one joint of one leg
    off = estimate_state(perturbed, last, unpacked, True)
    assert off.configuration is Configuration.UNDEFINED and not off.ready
    # Direct mode never ends READY.
    assert not estimate_state(unpacked, last, unpacked, sequence_mode=False).ready
    assert not estimate_state(packed[0], last, unpacked, sequence_mode=False).ready
