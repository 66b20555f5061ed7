"""Leg odometry (shc_cli/control/odometry.py): properties of the estimator and its place in the controller."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control.odometry import (
    BIAS_TIME_CONSTANT,
    RATE_TIME_CONSTANT,
    STEADY_YAW_RATE,
    YAW_TIME_CONSTANT,
    LegOdometry,
    euler_yaw_rate,
    level,
    quaternion_yaw,
    rigid_increment,
)

finite = st.floats(-0.5, 0.5, allow_nan=False)
turns = st.floats(-0.3, 0.3, allow_nan=False)


def body_frame(world: np.ndarray, x: float, y: float, yaw: float) -> np.ndarray:
    """World points ``(K, 2|3)`` seen from a body at (x, y, yaw): ``R(yaw)ᵀ·(w − t)`` (written out here)."""
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = world[:, 0] - x, world[:, 1] - y
    out = world.copy()
    out[:, 0], out[:, 1] = c * dx + s * dy, -s * dx + c * dy
    return out


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(finite, finite), min_size=2, max_size=6, unique=True), finite, finite, turns)
def test_rigid_motion_of_the_feet_gives_the_opposite_body_motion(points: list[tuple[float, float]], dx: float,
                                                                 dy: float, dyaw: float) -> None:
    feet = np.array(points)
    if np.ptp(feet, axis=0).max() < 1e-3:  # feet on one spot carry no rotation
        return
    after = body_frame(feet, dx, dy, dyaw)  # the body moved by (dx, dy, dyaw): the feet move the other way
    got = rigid_increment(feet, after)
    assert np.allclose(got, (dx, dy, dyaw), atol=1e-12)


def test_a_foot_without_load_does_not_count() -> None:
    """Three planted feet and one sliding foot with no load: the weighted fit gives the planted feet's motion."""
    before = np.array([[0.2, 0.2], [0.2, -0.2], [-0.2, 0.0], [0.0, 0.25]])
    after = body_frame(before, 0.01, -0.004, 0.02)
    after[3] += [0.05, 0.03]  # the fourth foot slides
    got = rigid_increment(before, after, np.array([30.0, 25.0, 40.0, 0.0]))
    assert np.allclose(got, (0.01, -0.004, 0.02), atol=1e-12)
    assert not np.allclose(rigid_increment(before, after), (0.01, -0.004, 0.02), atol=1e-3)


@settings(max_examples=100, deadline=None)
@given(finite, finite)
def test_one_foot_gives_the_translation(dx: float, dy: float) -> None:
    foot = np.array([[0.2, 0.1]])
    assert np.allclose(rigid_increment(foot, foot - [dx, dy]), (dx, dy, 0.0), atol=1e-15)


def test_a_pure_translation_of_the_stance_feet_moves_the_body_back() -> None:
    odometry = LegOdometry(0.02)
    feet = np.array([[0.2, 0.15, -0.1], [0.2, -0.15, -0.1], [-0.2, 0.15, -0.1], [-0.2, -0.15, -0.1]])
    stance = np.ones(4, dtype=bool)
    odometry.update(feet, stance)
    for k in range(1, 51):
        pose = odometry.update(feet + np.array([0.001 * k, -0.002 * k, 0.0]), stance)
    assert np.allclose(pose, (-0.05, 0.1, 0.0), atol=1e-12)


def test_a_walked_trajectory_with_changing_stance_is_recovered() -> None:
    """A body walking a curve over world-fixed footholds, three of six feet in stance at a time (tripod-like), each
    foot re-planted when it swings: the odometry ends at the true pose to 1e-9 m."""
    rng = np.random.default_rng(3)
    dt, steps = 0.01, 600
    t = np.arange(steps + 1) * dt
    xs, ys, yaws = 0.3 * t + 0.05 * np.sin(t), 0.1 * t ** 2, 0.4 * np.sin(0.5 * t)
    nominal = np.array([[0.25, 0.2], [0.0, 0.28], [-0.25, 0.2], [0.25, -0.2], [0.0, -0.28], [-0.25, -0.2]])
    world = np.zeros((6, 2))
    odometry = LegOdometry(dt)
    for k in range(steps + 1):
        group = (k // 25) % 2  # legs 0, 2, 4 or 1, 3, 5 in stance
        stance = np.array([(leg % 2) == group for leg in range(6)])
        c, s = math.cos(yaws[k]), math.sin(yaws[k])
        for leg in range(6):
            if k == 0 or not stance[leg]:  # swinging: the foot lands where the nominal stance is now (with some noise)
                local = nominal[leg] + rng.normal(0.0, 0.01, 2)
                world[leg] = [xs[k] + c * local[0] - s * local[1], ys[k] + s * local[0] + c * local[1]]
        feet = np.column_stack([body_frame(world, xs[k], ys[k], yaws[k]), np.full(6, -0.1)])
        pose = odometry.update(feet, stance)
    assert abs(pose[0] - xs[-1]) < 1e-9 and abs(pose[1] - ys[-1]) < 1e-9 and abs(pose[2] - yaws[-1]) < 1e-9


def test_the_gyro_carries_the_yaw_when_the_legs_slip() -> None:
    """Feet that slip (no motion seen) under a body the gait turns: with a gyro the heading is the gyro's, and stays
    (the legs' turn is not trusted while the body turns); without one it stays at the legs'. Standing still
    afterwards, the legs (no turn) and the gyro (no turn) agree: nothing moves, no bias is learned."""
    dt = 0.01
    feet = np.array([[0.2, 0.1, -0.1], [-0.2, 0.1, -0.1], [0.0, -0.2, -0.1]])
    stance = np.ones(3, dtype=bool)
    fused, legs_only = LegOdometry(dt, yaw_time_constant=1.0), LegOdometry(dt)
    for _ in range(10):
        fused.cycle(feet, 0.0, 0.0, stance, 1.0 * dt, commanded_turn_rate=1.0)
        legs_only.update(feet, stance)
    assert legs_only.yaw == 0.0
    assert fused.yaw == pytest.approx(0.1, abs=1e-12) and fused.reference_yaw == pytest.approx(0.1, abs=1e-12)
    for _ in range(2000):
        fused.update(feet, stance, turn=0.0)
    assert fused.yaw == pytest.approx(0.1, abs=1e-12) and fused.gyro_bias == 0.0


def test_a_turn_the_gait_did_not_ask_for_is_seen_by_the_gyro() -> None:
    """The body turned by something else (pushed, slipping) at 1 rad/s while the gait walks straight: the smoothed
    gyro rate passes :data:`STEADY_YAW_RATE` within a few cycles, and from then on the gyro carries the turn. The
    legs, which see none, are trusted only in those first cycles (a 1 mrad share of the 1 rad turn)."""
    dt = 0.01
    feet = np.array([[0.2, 0.1, -0.1], [-0.2, 0.1, -0.1], [0.0, -0.2, -0.1]])
    fused = LegOdometry(dt)
    for _ in range(100):
        fused.update(feet, np.ones(3, dtype=bool), turn=1.0 * dt)
    assert 0.99 < fused.yaw < 1.0 and fused.reference_yaw > 0.97


def test_levelling_and_euler_yaw_rate() -> None:
    foot = np.array([[0.0, 0.0, -0.2]])
    pitched = level(foot, 0.0, 0.1)  # nose down by 0.1: a foot below the body is ahead of it in the level frame
    assert np.allclose(pitched, [[-0.2 * math.sin(0.1), 0.0, -0.2 * math.cos(0.1)]])
    assert euler_yaw_rate(0.0, 0.0, np.array([0.3, 0.2, 0.5])) == 0.5
    assert math.isclose(euler_yaw_rate(0.2, 0.0, np.array([0.0, 1.0, 0.0])), math.sin(0.2))


def _walk(cycles: int, velocity: tuple[float, float, float],
          measured: bool = False) -> list[tuple[float, float, float]]:
    """Plan-like run of bullet's tripod (no backend): the odometry of every cycle; with ``measured`` the controller
    reads back last cycle's commanded joints as measured joints (an ideal servo one cycle behind)."""
    from shc_cli.api import load_gait, load_robot
    from shc_cli.control.controller import Command, Controller, RobotState
    from shc_cli.control.sensing import Sensors

    robot = load_robot("bullet")
    controller = Controller(robot, load_gait("tripod"))
    poses, sensors = [], None
    for _ in range(cycles):
        running = controller.state == RobotState.RUNNING
        out = controller.step(Command(velocity=velocity if running else (0.0, 0.0, 0.0),
                                      state_request=RobotState.RUNNING), sensors)
        sensors = Sensors(joints=out.joints) if measured else None
        poses.append(out.odometry)
    walker = controller.walker
    assert walker is not None
    ideal = (*walker.odometry_position[:2], walker.odometry_yaw)
    assert math.dist(poses[-1][:2], ideal[:2]) < 2e-3 and abs(poses[-1][2] - ideal[2]) < 2e-3, (poses[-1], ideal)
    return poses


def test_plan_odometry_follows_the_commanded_walk_and_measured_joints_give_the_same() -> None:
    """Kinematic walk with a turn: the stance feet's odometry ends within 2 mm and 2 mrad of the walker's ideal
    odometry (the integrated command; the residual is OpenSHC's stance curve, not the estimator — the rigid-motion
    tests above are exact); read back as measured joints one cycle late, the same poses one cycle later."""
    commanded = _walk(900, (1.0, 0.0, 0.3))
    assert math.hypot(*commanded[-1][:2]) > 0.3  # it walked
    measured = _walk(900, (1.0, 0.0, 0.3), measured=True)
    assert np.allclose(np.array(measured[1:]), np.array(commanded[:-1]), atol=1e-9)


@pytest.mark.slow
def test_simulate_logs_odometry_and_analyze_measures_its_drift(tmp_path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """End to end on MuJoCo: a short turning walk logs ``odom_*``, its summary has the final odometry and true poses,
    and ``shc analyze --json`` gives the drift measures, small on flat ground; ``--out`` draws trajectory.png."""
    import json

    from .test_cli import run

    out = tmp_path / "walk"
    code, _, err = run(["simulate", "--duration", "6", "--velocity", "1,0,0.3", "--out", str(out)], capsys,
                       monkeypatch)
    assert code == 0, err
    header = (out / "log.csv").read_text().splitlines()[0].split(",")
    assert {"odom_x", "odom_y", "odom_yaw"} <= set(header)
    summary = json.loads((out / "summary.json").read_text())
    odometry, truth = summary["odometry_pose"], summary["true_pose"]
    assert math.hypot(truth[0], truth[1]) > 0.25 and truth[2] > 0.2  # it walked (0.30 m) and turned
    assert math.dist(odometry[:2], truth[:2]) < 0.05 and abs(odometry[2] - truth[2]) < 0.05
    code, stdout, err = run(["analyze", str(out), "--json", "--out", str(tmp_path / "analysis")], capsys, monkeypatch)
    assert code == 0, err
    result = json.loads(stdout)
    assert 0.0 <= result["odometry_drift_percent"] < 5.0 and 0.0 <= result["odometry_heading_error_deg"] < 3.0
    assert (tmp_path / "analysis" / "trajectory.png").stat().st_size > 10_000
    code, _, err = run(["export", "bag", str(out), "--out", str(tmp_path / "bag")], capsys, monkeypatch)
    assert code == 0, err
    from shc_cli.interop.bag import read_topics

    topics = read_topics(tmp_path / "bag")
    last = topics["/odom"][-1][1].pose.pose.position  # /odom is the estimate, /ground_truth/odom the truth
    assert math.isclose(last.x, odometry[0], abs_tol=1e-5) and math.isclose(last.y, odometry[1], abs_tol=1e-5)
    assert topics["/ground_truth/odom"][-1][1].header.frame_id == "world"
    code, stdout, err = run(["analyze", str(tmp_path / "bag"), "--json"], capsys, monkeypatch)
    from_bag = json.loads(stdout)
    for key in ("odometry_drift_percent", "odometry_heading_error_deg"):
        assert math.isclose(from_bag[key], result[key], rel_tol=1e-6, abs_tol=1e-6), key


def test_a_plan_run_has_odometry_columns_and_its_drift_is_small(tmp_path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import json

    from .test_cli import run

    out = tmp_path / "plan"
    code, _, err = run(["plan", "--duration", "4", "--velocity", "1,0,0.3", "--no-plots", "--out", str(out)], capsys,
                       monkeypatch)
    assert code == 0, err
    assert "odom_yaw" in (out / "body.csv").read_text().splitlines()[0].split(",")
    code, stdout, err = run(["analyze", str(out), "--json"], capsys, monkeypatch)
    result = json.loads(stdout)
    assert result["odometry_drift_percent"] < 0.5 and result["odometry_heading_error_deg"] < 0.2


def _numpy_increment(before: np.ndarray, after: np.ndarray) -> tuple[float, float, float]:
    """The NumPy form of the rigid fit (means, centred sums, atan2): what the list form must equal to the bit."""
    p_mean, q_mean = before.mean(axis=0), after.mean(axis=0)
    turn = 0.0
    if len(before) > 1:
        p, q = before - p_mean, after - q_mean
        turn = math.atan2(float(np.sum(q[:, 0] * p[:, 1] - q[:, 1] * p[:, 0])),
                          float(np.sum(q[:, 0] * p[:, 0] + q[:, 1] * p[:, 1])))
    c, s = math.cos(turn), math.sin(turn)
    return (float(p_mean[0] - (c * q_mean[0] - s * q_mean[1])), float(p_mean[1] - (s * q_mean[0] + c * q_mean[1])),
            turn)


def test_rigid_increment_equals_the_numpy_form_to_the_bit() -> None:
    """1 … 10 feet (the list form below 8, NumPy's pairwise sums from 8), random motions and magnitudes; and the
    odometry's per-cycle path (indices of the stance feet) gives the same pose as the NumPy form."""
    rng = np.random.default_rng(11)
    for count in range(1, 11):
        for _ in range(2000):
            before = rng.normal(size=(count, 2)) * 10.0 ** rng.integers(-3, 1)
            after = before + rng.normal(size=(count, 2)) * 10.0 ** rng.integers(-6, -1)
            assert rigid_increment(before, after) == _numpy_increment(before, after)
    odometry = LegOdometry(0.01)
    feet = rng.normal(size=(6, 3))
    pose = np.zeros(3)
    odometry.update(feet, np.ones(6, dtype=bool))
    for _ in range(500):
        moved = feet + rng.normal(size=(6, 3)) * 1e-3
        stance = rng.random(6) < 0.6
        if stance.any():
            dx, dy, turn = _numpy_increment(feet[stance, :2], moved[stance, :2])
        else:
            dx = dy = turn = 0.0
        heading = pose[2]
        pose = np.array([pose[0] + (math.cos(heading) * dx - math.sin(heading) * dy),
                         pose[1] + (math.sin(heading) * dx + math.cos(heading) * dy), heading + turn])
        assert odometry.update(moved, stance) == tuple(pose.tolist())
        feet = moved


def test_quaternion_yaw_is_the_matrix_yaw() -> None:
    from shc_cli.control.pose import euler_from_matrix
    from shc_cli.control.sensing import quaternion_matrix

    rng = np.random.default_rng(5)
    for q in rng.normal(size=(200, 4)):
        q /= np.linalg.norm(q)
        assert math.isclose(quaternion_yaw(q), euler_from_matrix(quaternion_matrix(q))[2], abs_tol=1e-12)


def test_the_compiled_cycle_equals_the_reference_forms() -> None:
    """LegOdometry's compiled cycle (shc_cli/control/odometry_kernels.py) against the reference forms written with
    NumPy: feet levelled by :func:`level` (a matrix product: the kernel writes it out, so to 1e-12 m, not to the
    bit), the force-weighted fit :func:`rigid_increment` (1e-12), the IMU's roll, pitch and heading change from its
    orientation (:func:`quaternion_roll_pitch`, :func:`quaternion_yaw`), the complementary filter, the contact mask
    (a foot counts only when touching at both readings) and the composition of the pose."""
    from shc_cli.control.sensing import quaternion_roll_pitch

    rng = np.random.default_rng(23)
    dt = 0.01
    odometry = LegOdometry(dt)
    gain, bias_gain, rate_gain, steady = odometry.gain, odometry.bias_gain, odometry.rate_gain, STEADY_YAW_RATE
    assert (gain, bias_gain, rate_gain) == (dt / YAW_TIME_CONSTANT, dt / BIAS_TIME_CONSTANT, dt / RATE_TIME_CONSTANT)
    x = y = yaw = leg_yaw = reference = bias = rate = 0.0
    steady_cycles = turning_cycles = 0
    imu_yaw = None
    levelled = None
    contact_before = None
    last, held = (0.0, 0.0), 0
    imu_heading = 0.0
    base = rng.normal(size=(6, 3)) * 0.2
    for k in range(600):
        feet = base + rng.normal(size=(6, 3)) * (0.2 if k % 7 == 0 else 0.001)  # mostly rigid: small leg turns
        tilt = np.array([*rng.normal(size=2) * 0.05, 0.0, 1.0])  # roll and pitch, and a heading that turns in
        imu_heading += 0.01 if k % 200 >= 170 else float(rng.normal(1e-4, 2e-4))  # some stretches, not in others
        c, s = math.cos(imu_heading / 2), math.sin(imu_heading / 2)  # (0, 0, s, c) ⊗ tilt
        q = np.array([c * tilt[0] - s * tilt[1], c * tilt[1] + s * tilt[0], s * tilt[3], c * tilt[3]])
        q /= np.linalg.norm(q)
        commanded = 0.3 if k % 200 < 20 else 0.01  # the gait turning, or walking straight
        stance = rng.random(6) < 0.7
        draw = rng.random()  # some cycles touch nowhere, some only with swinging feet: dropouts and not
        contact = rng.random(6) < 0.9 if draw < 0.7 else (~stance if draw < 0.85 else np.zeros(6, dtype=bool))
        forces = rng.normal(20.0, 15.0, size=6)  # some negative: they count as 0
        got = odometry.cycle(feet, 0.3, -0.2, stance, None, forces, q, contact,  # roll, pitch: the IMU's instead
                             commanded)
        roll, pitch = quaternion_roll_pitch(q)
        now = level(feet, roll, pitch)
        assert np.allclose(odometry._feet, now, rtol=0.0, atol=1e-12)  # type: ignore[arg-type]
        use = stance & contact & contact_before if contact_before is not None else stance
        contact_before = contact
        turn = None
        heading = quaternion_yaw(q)
        if imu_yaw is not None:
            turn = math.remainder(heading - imu_yaw, 2.0 * math.pi)
        imu_yaw = heading
        dx = dy = legs_turn = 0.0
        if levelled is not None and use.any():
            dx, dy, legs_turn = rigid_increment(levelled[use, :2], now[use, :2], np.maximum(forces[use], 0.0))
            last, held = (dx, dy), 0
        elif levelled is not None and stance.any() and not (contact & ~stance).any() and held < odometry.hold:
            # a contact dropout (no foot touching but the standing ones, and none of them at both readings)
            (dx, dy), held = last, held + 1  # with the IMU: its turn, none of the legs'
        levelled = now
        leg_yaw += legs_turn
        start = yaw
        if turn is None:
            yaw += legs_turn
            reference += legs_turn
        else:  # the bias-state filter: legs trusted while neither the gait nor the (smoothed) gyro turns
            corrected = turn - bias * dt
            rate += rate_gain * (corrected / dt - rate)
            if abs(rate) <= steady and abs(commanded) <= steady:
                reference += legs_turn
                steady_cycles += 1
                if use.sum() > 1:
                    bias += bias_gain * ((turn - legs_turn) / dt - bias)
            else:
                reference += corrected
                turning_cycles += 1
            yaw = yaw + corrected + gain * (reference - (yaw + corrected))
        x += math.cos(start) * dx - math.sin(start) * dy
        y += math.sin(start) * dx + math.cos(start) * dy
        assert np.allclose(got, (x, y, yaw), rtol=0.0, atol=1e-12), (got, (x, y, yaw))
        assert math.isclose(odometry.gyro_bias, bias, abs_tol=1e-9)
        assert math.isclose(odometry.reference_yaw, reference, abs_tol=1e-12)
    assert odometry.feet_used == int(use.sum())
    assert steady_cycles > 50 and turning_cycles > 50 and bias != 0.0


def steady_walk(odometry: LegOdometry, cycles: int, step: tuple[float, float, float], dropouts: set[int],
                imu: bool = False) -> tuple[float, float, float]:
    """Four world-fixed feet under a body moving ``step`` (dx, dy [m], dyaw [rad], in its own frame) each cycle,
    contact measured, none touching in the ``dropouts`` cycles; the IMU's orientation when ``imu``. Returns the true
    pose at the end."""
    world = np.array([[0.2, 0.15], [0.2, -0.15], [-0.2, 0.15], [-0.2, -0.15]])
    x = y = yaw = 0.0
    stance = np.ones(4, dtype=bool)
    for k in range(cycles + 1):
        if k > 0:
            c, s = math.cos(yaw), math.sin(yaw)
            x, y, yaw = x + c * step[0] - s * step[1], y + s * step[0] + c * step[1], yaw + step[2]
        feet = np.column_stack([body_frame(world, x, y, yaw), np.full(4, -0.1)])
        contact = np.full(4, k not in dropouts)
        orientation = np.array([0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]) if imu else None
        odometry.cycle(feet, 0.0, 0.0, stance, None, None, orientation, contact)
    return x, y, yaw


@settings(max_examples=60, deadline=None)
@given(finite, finite, turns, st.integers(5, 60), st.integers(1, 10), st.booleans())
def test_a_contact_dropout_in_a_steady_walk_continues_the_walk(dx: float, dy: float, dyaw: float, start: int,
                                                                length: int, imu: bool) -> None:
    """Feet standing by the gait but touching nowhere for up to HOLD_TIME (a light robot bouncing): the last
    measured motion is repeated — exact in a steady walk, with or without an IMU (which then gives the turn)."""
    odometry = LegOdometry(0.01)
    step = (dx * 0.01, dy * 0.01, dyaw * 0.01)
    assert odometry.hold == 10  # HOLD_TIME 0.1 s at 100 Hz
    # the cycle after a dropout has no contact at the earlier reading either: it is held too
    cycles, dt = 80, 0.01
    truth = steady_walk(odometry, cycles, step, set(range(start, start + length - 1)), imu)
    # With the IMU, a dropout early in the turn (before the 0.5 s smoothed gyro rate passes STEADY_YAW_RATE, so the
    # filter still takes the body for steady) hides the turn from the legs: for up to `length` cycles the bias state
    # learns the whole turn rate at dt/τ_b a cycle and keeps it, and the legs' reference pulls the heading at dt/τ a
    # cycle by at most the hidden turn. The heading error is bounded by both over the walk, the position's by that
    # angle over the distance walked.
    if imu:
        hidden = length * abs(step[2])
        bias = length * dt / BIAS_TIME_CONSTANT * abs(dyaw)
        heading = bias * cycles * dt + cycles * dt / YAW_TIME_CONSTANT * hidden
        walked = cycles * math.hypot(step[0], step[1])
        assert abs(odometry.yaw - truth[2]) <= heading + 1e-12
        assert math.hypot(odometry.x - truth[0], odometry.y - truth[1]) <= heading * walked + 1e-12
    else:
        assert np.allclose(odometry.pose, truth, atol=1e-9)
    if imu:
        assert abs(odometry.leg_yaw - truth[2]) <= abs(step[2]) * length + 1e-12


def test_a_long_dropout_or_no_standing_foot_holds_the_pose() -> None:
    """Beyond HOLD_TIME the pose stops (a robot lifted off the ground must not walk on in the estimate), and a
    dropout with no foot standing by the gait is not bridged."""
    odometry = LegOdometry(0.01)
    step = (0.001, 0.0, 0.0)
    steady_walk(odometry, 100, step, set(range(20, 60)))
    # 41 cycles without a foot (the 40, and the one after: no contact at its earlier reading), the first 10 held
    assert odometry.x == pytest.approx(0.001 * (100 - 41 + 10), abs=1e-9)
    airborne = LegOdometry(0.01)
    feet = np.array([[0.2, 0.1, -0.1], [-0.2, 0.1, -0.1], [0.0, -0.2, -0.1]])
    for k in range(20):
        airborne.cycle(feet - [0.001 * k, 0.0, 0.0], 0.0, 0.0, np.full(3, k < 10), contact=np.full(3, k < 10))
    assert airborne.x == pytest.approx(0.009, abs=1e-12)  # 9 measured increments, then nothing held


def test_a_dropout_with_a_swinging_foot_on_the_ground_holds_the_pose() -> None:
    """The standing feet lose contact while a foot the gait has lifted touches: the body may be resting or
    dragging on that moving foot (bullet_mammalian's bipod sinks onto its swinging feet), so its last motion is
    no guide and the pose holds."""
    feet = np.array([[0.2, 0.1, -0.1], [-0.2, 0.1, -0.1], [0.0, -0.2, -0.1], [0.1, -0.2, -0.1]])
    stance = np.array([True, True, True, False])
    odometry = LegOdometry(0.01)
    for k in range(20):
        contact = np.array([k < 10] * 3 + [k >= 10])  # from cycle 10 only the swinging fourth foot touches
        odometry.cycle(feet - [0.001 * k, 0.0, 0.0], 0.0, 0.0, stance, contact=contact)
    assert odometry.x == pytest.approx(0.009, abs=1e-12)


def square_walk(odometry: LegOdometry, bias_deg: float = 0.0, over_read: float = 0.0) -> tuple[float, float]:
    """A quadruped-like square, truth against estimate: 5 s standing, then four times 20 s straight ahead at 0.1
    m/s and a quarter turn on the spot in 3 s (the gait commanded to turn at π/6 rad/s), 5 s standing; four
    world-fixed feet under the body. The legs read every turn ``over_read`` too far (0.04: 4 % — the quadruped's
    quad_wave, docs/odometry.md), the IMU's orientation drifts in yaw by ``bias_deg`` [deg/s] (a gyro bias).
    Returns the heading error at the end and the largest on the way [rad]."""
    dt = odometry.dt
    world = np.array([[0.2, 0.15, -0.1], [0.2, -0.15, -0.1], [-0.2, 0.15, -0.1], [-0.2, -0.15, -0.1]])
    stance = np.ones(4, dtype=bool)
    segments = [(500, 0.0, 0.0)] + [(2000, 0.1, 0.0), (300, 0.0, math.pi / 6)] * 4 + [(500, 0.0, 0.0)]
    yaw = legs_x = legs_y = legs_yaw = 0.0  # the truth's heading, the pose the legs see
    k, worst = 0, 0.0
    for cycles, speed, rate in segments:
        for _ in range(cycles):
            k += 1
            yaw += rate * dt
            c, s = math.cos(legs_yaw), math.sin(legs_yaw)
            legs_x, legs_y, legs_yaw = legs_x + c * speed * dt, legs_y + s * speed * dt, legs_yaw + rate * dt * (
                1.0 + over_read)
            imu = yaw + math.radians(bias_deg) * k * dt
            orientation = np.array([0.0, 0.0, math.sin(imu / 2), math.cos(imu / 2)])
            odometry.cycle(body_frame(world, legs_x, legs_y, legs_yaw), 0.0, 0.0, stance,
                           orientation=orientation, commanded_turn_rate=rate)
            worst = max(worst, abs(math.remainder(odometry.yaw - yaw, 2 * math.pi)))
    return abs(math.remainder(odometry.yaw - yaw, 2 * math.pi)), worst


def test_a_gyro_bias_is_learned_and_the_heading_stays_bounded() -> None:
    """A 0.5°/s gyro yaw bias (a cheap MEMS gyro, uncalibrated): the IMU's heading alone is 51° off after the
    102 s square; the filter learns the bias from the legs while the body stands or walks straight and ends within
    0.5° (2° at worst on the way), with the bias estimated to 2 %."""
    raw = LegOdometry(0.01, yaw_time_constant=0.0, bias_time_constant=0.0)  # the IMU's heading change alone
    assert math.degrees(square_walk(raw, bias_deg=0.5)[0]) == pytest.approx(51.0, abs=0.1)
    fused = LegOdometry(0.01)
    end, worst = square_walk(fused, bias_deg=0.5)
    assert math.degrees(end) < 0.5 and math.degrees(worst) < 2.0
    assert math.degrees(fused.gyro_bias) == pytest.approx(0.5, rel=0.02)


def test_legs_that_over_read_turns_on_the_spot_do_not_pull_the_heading() -> None:
    """The legs over-read each quarter turn by 4 % (the quadruped, docs/odometry.md): their own heading ends 14.4°
    off, and the former filter (the legs' heading always trusted, τ = 60 s, no bias state) was pulled by it; now
    the gyro carries every turn and the heading stays exact."""
    fused = LegOdometry(0.01)
    _, worst = square_walk(fused, over_read=0.04)
    assert worst < 1e-9 and abs(fused.gyro_bias) < 1e-12
    assert math.degrees(fused.leg_yaw) - 360.0 == pytest.approx(14.4, abs=1e-6)
    former = LegOdometry(0.01, yaw_time_constant=60.0, bias_time_constant=0.0, steady_yaw_rate=math.inf)
    assert math.degrees(square_walk(former, over_read=0.04)[0]) > 4.0


@settings(max_examples=12, deadline=None)
@given(st.floats(-1.0, 1.0), st.floats(-0.1, 0.1))
def test_the_heading_stays_bounded_for_any_bias_and_turn_error(bias_deg: float, over_read: float) -> None:
    """Any gyro bias within ±1°/s and any legs' turn error within ±10 %: the heading ends within 1° and never
    strays beyond 4°, where the IMU alone would end up to 102° off and the legs alone up to 36°."""
    end, worst = square_walk(LegOdometry(0.01), bias_deg, over_read)
    assert math.degrees(end) < 1.0 and math.degrees(worst) < 4.0


def test_the_simulated_imu_reads_its_yaw_bias() -> None:
    """``Imu(yaw_bias=b)``: the rate has b about the world's vertical (in the body frame), the orientation's yaw
    drifts by b × the time since the first reading while its roll and pitch stay the body's; without a bias the
    readings are the true ones."""
    from scipy.spatial.transform import Rotation

    from shc_cli.backends.imu import Imu
    from shc_cli.control.sensing import quaternion_roll_pitch

    bias = math.radians(0.5)
    truth = Rotation.from_euler("ZYX", [0.7, 0.1, -0.2])
    rotation, quaternion = truth.as_matrix(), truth.as_quat()  # quaternion (x, y, z, w)
    omega = np.array([0.1, -0.2, 0.3])
    biased, plain = Imu(0.01, 0.0, 0, yaw_bias=bias), Imu(0.01, 0.0, 0)
    for _ in range(201):
        _, rate = biased.sense(rotation, np.zeros(3), omega)
        reported = biased.orientation(quaternion)
        _, plain_rate = plain.sense(rotation, np.zeros(3), omega)
        assert plain.orientation(quaternion) is quaternion
    assert np.allclose(rate - plain_rate, rotation.T @ [0.0, 0.0, bias], atol=1e-15)
    assert math.remainder(quaternion_yaw(reported) - 0.7, 2 * math.pi) == pytest.approx(bias * 200 * 0.01, abs=1e-12)
    assert np.allclose(quaternion_roll_pitch(reported), (-0.2, 0.1), atol=1e-12)


def test_an_imu_yaw_bias_is_checked_and_given_to_the_engine_in_radians() -> None:
    """``imu_yaw_bias`` [deg/s]: finite and within ±90 deg/s, else one SpecError naming ``--imu-yaw-bias``; the
    engine gets it in rad/s."""
    from shc_cli.api import load_robot
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.errors import ShcError

    robot = load_robot("bullet")
    assert SimulationConfig(imu_yaw_bias=0.5).engine_options(robot).imu_yaw_bias == pytest.approx(math.radians(0.5))
    assert SimulationConfig().engine_options(robot).imu_yaw_bias == 0.0
    for bad in (math.nan, math.inf, 91.0, -100.0):
        with pytest.raises(ShcError, match="--imu-yaw-bias"):
            SimulationConfig(imu_yaw_bias=bad)


@pytest.mark.slow
def test_simulate_with_a_gyro_bias_keeps_the_heading(tmp_path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """End to end on MuJoCo: ``--imu-yaw-bias 0.5`` makes the logged IMU orientation drift 0.5°/s from the truth,
    and the odometry, learning the bias from the legs, still ends within 1° of the true heading after a straight
    walk (analyze's window, the RUNNING cycles)."""
    import csv
    import json

    from .test_cli import run

    out = tmp_path / "walk"
    code, _, err = run(["simulate", "--duration", "12", "--velocity", "1,0,0", "--imu-yaw-bias", "0.5",
                        "--out", str(out), "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    rows = list(csv.DictReader((out / "log.csv").open()))
    first, last = rows[0], rows[-1]

    def drift(row: dict[str, str]) -> float:
        imu = quaternion_yaw(np.array([float(row[f"imu_q{a}"]) for a in "xyzw"]))
        return math.remainder(imu - float(row["yaw"]), 2 * math.pi)

    elapsed = float(last["t"]) - float(first["t"])
    assert math.degrees(drift(last) - drift(first)) == pytest.approx(0.5 * elapsed, abs=0.02)
    code, stdout, err = run(["analyze", str(out), "--json"], capsys, monkeypatch)
    assert code == 0, err
    result = json.loads(stdout)  # over the walk (RUNNING): the IMU alone would be 0.5°/s × window_s off
    assert 0.5 * result["window_s"] > 5.0 and result["odometry_heading_error_deg"] < 1.0
