"""The path follower (``shc_cli.control.path_follower``) on a model of OpenSHC's walker: it converges on every
waypoint, never asks for more than the walkspace's limits, stops at the last waypoint, and counts a waypoint it
cannot reach as missed."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control.path_follower import (
    FollowerLimits,
    FollowerOptions,
    PathFollower,
    velocity_input,
    wrap,
)
from shc_cli.spec.path import Waypoint

LIMITS = FollowerLimits(speed=0.2, yaw_rate=0.4, acceleration=0.08, yaw_acceleration=0.17)
"""The bullet's walkspace limits walking ahead in tripod (``Controller.walker.limits_for``), rounded."""
DT = 0.01


def _limits(vx: float, vy: float, wz: float) -> FollowerLimits:
    return LIMITS


class Walker:
    """OpenSHC's walker as a point (stepping.walk_update): a throttle input → a target velocity ``t·v_max·(1 − |tω|)``
    and yaw rate ``tω·ω_max``, the desired velocity ramped to it under the acceleration limits, the pose integrated
    in the world from the body-frame velocity."""

    def __init__(self, limits: FollowerLimits = LIMITS) -> None:
        self.limits = limits
        self.pose = np.zeros(3)
        self.velocity = np.zeros(3)

    def step(self, command: tuple[float, float, float]) -> None:
        tx, ty, tw = command
        size = math.hypot(tx, ty)
        if size > 1.0:
            tx, ty = tx / size, ty / size
        tw = max(-1.0, min(1.0, tw))
        scale = 1.0 - abs(tw)
        target = np.array([tx * self.limits.speed * scale, ty * self.limits.speed * scale, tw * self.limits.yaw_rate])
        change = target[:2] - self.velocity[:2]
        step = self.limits.acceleration * DT
        size = float(np.linalg.norm(change))
        self.velocity[:2] += change if size <= step else change / size * step
        turn = target[2] - self.velocity[2]
        self.velocity[2] += max(-self.limits.yaw_acceleration * DT, min(self.limits.yaw_acceleration * DT, turn))
        yaw = self.pose[2]
        c, s = math.cos(yaw), math.sin(yaw)
        vx, vy, wz = self.velocity
        self.pose += np.array([c * vx - s * vy, s * vx + c * vy, wz]) * DT


def _walk(waypoints: list[Waypoint], options: FollowerOptions | None = None, seconds: float = 200.0,
          walker: Walker | None = None) -> tuple[PathFollower, Walker, list[tuple[float, float, float]]]:
    follower = PathFollower(waypoints, options or FollowerOptions())
    walker = walker or Walker()
    asked = []
    for _ in range(round(seconds / DT)):
        velocity = follower.update((float(walker.pose[0]), float(walker.pose[1]), float(walker.pose[2])), _limits,
                                   DT)
        asked.append(velocity)
        walker.step(velocity_input(velocity, LIMITS, throttle=True))
        if follower.done and not walker.velocity.any():
            break
    return follower, walker, asked


SQUARE = [Waypoint(2.0, 0.0, math.pi / 2), Waypoint(2.0, 2.0, math.pi), Waypoint(0.0, 2.0, -math.pi / 2),
          Waypoint(0.0, 0.0, 0.0)]


def test_walks_the_square_reaches_every_waypoint_and_stops_at_the_last() -> None:
    follower, walker, asked = _walk(SQUARE)
    assert follower.done and follower.reached == 4
    options = follower.options
    for result in follower.results:
        assert result.reached and result.position_error_m is not None and result.position_error_m <= options.arrive_m
        assert result.heading_error_rad is not None and abs(result.heading_error_rad) <= options.arrive_rad
    # the walker ramps down after the follower's last zero: where it stops is still within the tolerance
    assert math.hypot(walker.pose[0], walker.pose[1]) <= options.tolerance_m
    assert abs(wrap(walker.pose[2])) <= options.heading_tolerance_rad
    assert asked[-1] == (0.0, 0.0, 0.0)
    times = [r.left_s for r in follower.results]
    assert all(a is not None and b is not None and a < b for a, b in itertools.pairwise(times))


def test_turning_while_walking_turns_along_each_side_in_proportion_to_the_distance_walked() -> None:
    """``turn_while_walking``: the heading of arrival is turned to along the segment — halfway along each side the
    heading is halfway between the two waypoints' (within 5°), the whole square is reached with no turn on the spot
    longer than a few seconds, and the yaw rate and speed stay within the walker's limits."""
    options = FollowerOptions(turn_while_walking=True)
    follower = PathFollower(SQUARE, options)
    walker = Walker()
    halfway: list[float] = []
    asked: list[tuple[float, float, float]] = []
    starts = [(0.0, 0.0, 0.0), *((w.x, w.y, w.yaw or 0.0) for w in SQUARE[:-1])]
    for _ in range(round(200.0 / DT)):
        x, y, yaw = (float(v) for v in walker.pose)
        velocity = follower.update((x, y, yaw), _limits, DT)
        asked.append(velocity)
        assert abs(velocity[2]) <= LIMITS.yaw_rate + 1e-9
        assert math.hypot(velocity[0], velocity[1]) <= LIMITS.speed + 1e-9
        if not follower.done and not follower.turning and len(halfway) == follower.index:
            ax, ay, ayaw = starts[follower.index]
            target = SQUARE[follower.index]
            if math.hypot(x - ax, y - ay) >= 1.0:  # halfway along the 2 m side
                halfway.append(math.degrees(wrap(yaw - (ayaw + wrap((target.yaw or 0.0) - ayaw) / 2.0))))
        walker.step(velocity_input(velocity, LIMITS, throttle=True))
        if follower.done and not walker.velocity.any():
            break
    assert follower.done and follower.reached == 4
    assert len(halfway) == 4 and max(abs(h) for h in halfway) <= 5.0, halfway
    # no turning on the spot (asked to turn faster than 0.05 rad/s while moving slower than 1 cm/s), where the
    # default follower turns on the spot at every corner
    _, _, plain = _walk(SQUARE)
    on_the_spot = [sum(abs(w) > 0.05 and math.hypot(vx, vy) < 0.01 for vx, vy, w in run) * DT for run in (asked, plain)]
    assert on_the_spot[0] < 0.5 and on_the_spot[1] > 10.0, on_the_spot


@settings(max_examples=25, deadline=None)
@given(st.lists(st.tuples(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.one_of(st.none(), st.floats(-3.1, 3.1))),
                min_size=1, max_size=3))
def test_converges_within_the_limits(points: list[tuple[float, float, float | None]]) -> None:
    """Any waypoints: every one reached, and no command beyond the walkspace's speed and yaw-rate limits (the
    linear speed shares the limit with the yaw rate as OpenSHC's walker does: |v|/v_max + |ω|/ω_max ≤ 1)."""
    follower, _, asked = _walk([Waypoint(*p) for p in points], seconds=400.0)
    assert follower.done and follower.reached == len(points), follower.results
    for vx, vy, wz in asked:
        assert math.hypot(vx, vy) / LIMITS.speed + abs(wz) / LIMITS.yaw_rate <= 1.0 + 1e-9
    commands = [velocity_input(v, LIMITS, throttle=True) for v in asked]
    assert max(math.hypot(c[0], c[1]) for c in commands) <= 1.0 + 1e-9  # inside the throttle range
    assert max(abs(c[2]) for c in commands) <= 1.0


def test_brakes_within_the_acceleration_limit() -> None:
    """Until the waypoint (within ``arrive_m``: then the last stop) the speed asked for never falls faster than the
    walker can brake, so it does not run past the waypoint."""
    follower, walker, asked = _walk([Waypoint(1.0, 0.0)])
    speeds = np.array([math.hypot(v[0], v[1]) for v in asked if any(v)])
    assert speeds.max() > 0.15 and (np.diff(speeds) >= -LIMITS.acceleration * DT - 1e-9).all()
    assert walker.pose[0] <= 1.0 + follower.options.tolerance_m


@pytest.mark.parametrize("throttle", [True, False])
def test_velocity_input_is_the_walkers_inverse(throttle: bool) -> None:
    for velocity in [(0.1, 0.05, 0.1), (-0.15, 0.0, -0.05), (0.0, 0.0, 0.3)]:
        tx, ty, tw = velocity_input(velocity, LIMITS, throttle)
        share = tw if throttle else tw / LIMITS.yaw_rate
        speed = LIMITS.speed if throttle else 1.0
        assert (tx * speed * (1 - abs(share)), ty * speed * (1 - abs(share))) == pytest.approx(velocity[:2])
        assert (tw * LIMITS.yaw_rate if throttle else tw) == pytest.approx(velocity[2])


def test_an_unreachable_waypoint_is_missed_and_the_follower_goes_on() -> None:
    """A walker that cannot move (zero speed limit) never reaches the first waypoint: after the timeout it is
    missed, the second (the start itself) is reached, and the follower stops."""
    stuck = Walker(FollowerLimits(0.0, 0.4, 0.0, 0.17))
    follower, _, _ = _walk([Waypoint(1.0, 0.0), Waypoint(0.0, 0.0)], FollowerOptions(timeout_s=3.0),
                           seconds=10.0, walker=stuck)
    first, second = follower.results
    assert not first.reached and first.left_s == pytest.approx(3.0, abs=0.02) and first.closest_m == 1.0
    assert second.reached and follower.done


def test_options_are_checked() -> None:
    with pytest.raises(ValueError, match="arrive_m"):
        FollowerOptions(tolerance_m=0.01, arrive_m=0.02)
    with pytest.raises(ValueError, match="at least one waypoint"):
        PathFollower([])


def test_segment_distance_is_to_the_nearest_point_of_the_segment() -> None:
    """``shc analyze``'s cross-track distance: perpendicular inside the segment, to the end beyond it."""
    from shc_cli.analysis.path_measures import segment_distance

    points = np.array([[1.0, 0.5], [1.0, -0.2], [-3.0, 4.0], [5.0, 0.0], [2.0, 0.0]])
    distances = segment_distance(points, np.array([0.0, 0.0]), np.array([2.0, 0.0]))
    assert distances == pytest.approx([0.5, 0.2, 5.0, 3.0, 0.0])
    assert segment_distance(points[:1], np.zeros(2), np.zeros(2)) == pytest.approx([math.hypot(1.0, 0.5)])
