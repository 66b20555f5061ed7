"""The path follower: waypoints → body velocity commands within the walkspace's limits (pure: no I/O, no clock).

A **holonomic** go-to-pose controller (docs/path-following.md says why not pure pursuit): a legged robot walks
sideways as well as ahead, so it need not face where it goes. For each waypoint in turn the follower

1. **walks** along the segment from the previous waypoint (where it started for the first) to this one, holding
   the heading it had when the segment began: the velocity along the segment is the smallest of the speed limit
   (a share of the walkspace's speed in that body direction), ``sqrt(2·a·d)`` (it can still brake to a stop in the
   remaining distance ``d`` at a share of the acceleration limit ``a``) and ``k·d``; across the segment it is
   ``−k·e`` (``e`` the signed cross-track distance), so the body is pulled back onto the line;
2. **turns** on the spot to the waypoint's heading when it has one (yaw rate ``min(ω_max, sqrt(2·α·|Δψ|),
   k_ψ·|Δψ|)``), holding its place;
3. moves on once within :attr:`FollowerOptions.arrive_m` (and the heading within
   :attr:`FollowerOptions.arrive_rad`), and stops at the last waypoint.

Walking and turning are not mixed: OpenSHC's walker scales the linear speed by ``1 − |ω|/ω_max``, so a turn while
walking costs speed and bends the path; the small heading hold while walking is the only overlap, and the speed
limit is reduced by that share. A waypoint is **reached** when the pose estimate came within
:attr:`FollowerOptions.tolerance_m` of it (and its heading within :attr:`FollowerOptions.heading_tolerance_rad`
when it had one) before the follower moved on; it is **missed** when :attr:`FollowerOptions.timeout_s` passed
first (the follower then goes on to the next).

The feedback is the robot's own pose estimate (the controller's leg odometry: what a real robot has), in the
odometry frame (the start pose is the origin). Velocities are body-frame m/s and rad/s; the input source turns them
into the robot's velocity input (:func:`velocity_input`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from shc_cli.spec.path import Waypoint

Pose2D = tuple[float, float, float]
"""x [m], y [m], yaw [rad] in the odometry frame."""
Velocity = tuple[float, float, float]
"""Body-frame x, y velocity [m/s] and yaw rate [rad/s]."""


@dataclass(frozen=True)
class FollowerLimits:
    """The walker's limits for a body direction of travel (:class:`shc_cli.control.limits.BearingLimit`).

    Attributes:
        speed: largest body speed [m/s].
        yaw_rate: largest yaw rate [rad/s].
        acceleration: largest body acceleration [m/s²].
        yaw_acceleration: largest yaw acceleration [rad/s²].
    """

    speed: float
    yaw_rate: float
    acceleration: float
    yaw_acceleration: float


LimitsFor = Callable[[float, float, float], FollowerLimits]
"""The limits for a body-frame direction of motion (x, y, yaw rate; only the direction counts)."""


@dataclass(frozen=True)
class FollowerOptions:
    """How the follower walks a path (defaults are the documented ones: docs/path-following.md).

    Attributes:
        tolerance_m: a waypoint is reached when the estimate comes this close [m].
        heading_tolerance_rad: ... and its heading, when it has one, this close [rad].
        arrive_m: the follower moves on to the next waypoint this close [m] (below ``tolerance_m``: it settles).
        arrive_rad: ... with the heading this close [rad].
        speed_share: share of the walkspace's speed and yaw-rate limits the follower asks for [ratio].
        brake_share: share of the acceleration limits it plans its braking with [ratio].
        gain: position gain along and across the segment [1/s].
        heading_gain: heading gain [1/s].
        timeout_s: time allowed per waypoint before it counts as missed and the follower moves on [s].
        turn_while_walking: a waypoint's heading is the heading of *arrival*: along each segment the heading goes
            from the one the segment began with to the waypoint's in proportion to the distance walked (a yaw rate
            of the heading change × the speed along ÷ the segment's length, plus ``heading_gain`` × the error), so
            the robot turns as it walks, as an RViz goal sequence asks; the turn on the spot only settles what is
            left. Off (the default): walk holding the heading, then turn on the spot.
    """

    tolerance_m: float = 0.05
    heading_tolerance_rad: float = math.radians(3.0)
    arrive_m: float = 0.01
    arrive_rad: float = math.radians(1.0)
    speed_share: float = 1.0
    brake_share: float = 0.5
    gain: float = 1.5
    heading_gain: float = 2.0
    timeout_s: float = 60.0
    turn_while_walking: bool = False

    def __post_init__(self) -> None:
        if not 0.0 < self.arrive_m <= self.tolerance_m:
            raise ValueError("arrive_m must be in (0, tolerance_m]")
        if not 0.0 < self.arrive_rad <= self.heading_tolerance_rad:
            raise ValueError("arrive_rad must be in (0, heading_tolerance_rad]")
        if not (0.0 < self.speed_share <= 1.0 and 0.0 < self.brake_share <= 1.0):
            raise ValueError("speed_share and brake_share are in (0, 1]")


@dataclass
class WaypointResult:
    """How one waypoint went.

    Attributes:
        index: its place in the path (0 first).
        waypoint: the waypoint.
        reached: the estimate came within the tolerances before the follower moved on.
        closest_m: the estimate's closest distance to it [m] (``inf`` before it became the target).
        reached_s: time of reaching it (within the tolerances), from the follower's first cycle [s].
        left_s: time the follower moved on from it (arrived and settled, or timed out) [s].
        heading_error_rad: heading error when the follower moved on [rad] (``None``: no heading given).
        position_error_m: distance from it when the follower moved on [m].
    """

    index: int
    waypoint: Waypoint
    reached: bool = False
    closest_m: float = math.inf
    reached_s: float | None = None
    left_s: float | None = None
    heading_error_rad: float | None = None
    position_error_m: float | None = None


def wrap(angle: float) -> float:
    """``angle`` in (−π, π] [rad]."""
    return math.atan2(math.sin(angle), math.cos(angle))


def _profile(distance: float, cap: float, acceleration: float, gain: float) -> float:
    """Speed towards a goal ``distance`` away: capped, able to brake in time, proportional near it."""
    return min(cap, math.sqrt(2.0 * acceleration * distance), gain * distance)


@dataclass
class PathFollower:
    """Walks a list of waypoints: :meth:`update` once per control cycle with the pose estimate.

    Args:
        waypoints: the path (at least one).
        options: tolerances, gains, shares.
    """

    waypoints: Sequence[Waypoint]
    options: FollowerOptions = field(default_factory=FollowerOptions)

    def __post_init__(self) -> None:
        if not self.waypoints:
            raise ValueError("a path needs at least one waypoint")
        self.results = [WaypointResult(i, w) for i, w in enumerate(self.waypoints)]
        self.index = 0
        """The waypoint being walked to (``len(waypoints)`` when done)."""
        self.turning = False
        """Walking to the waypoint (False) or turning to its heading there (True)."""
        self.time_s = 0.0
        self._segment_start_s = 0.0
        self._hold_yaw: float | None = None
        self._from: tuple[float, float] | None = None
        """Where the segment being walked begins: the first pose seen, then each waypoint left."""

    @property
    def done(self) -> bool:
        """Every waypoint was reached or missed: the follower now commands a stop."""
        return self.index >= len(self.waypoints)

    @property
    def reached(self) -> int:
        """Waypoints reached so far."""
        return sum(r.reached for r in self.results)

    def update(self, pose: Pose2D, limits_for: LimitsFor, dt: float) -> Velocity:
        """This cycle's body velocity for the pose estimate ``pose``; zero once :attr:`done`.

        Args:
            pose: x, y [m], yaw [rad] in the odometry frame.
            limits_for: the walker's limits for a body direction of motion.
            dt: control period [s].
        """
        x, y, yaw = pose
        if self._hold_yaw is None:
            self._hold_yaw = yaw
        if self._from is None:
            self._from = (x, y)
        o = self.options
        while not self.done:
            target = self.waypoints[self.index]
            result = self.results[self.index]
            distance = math.hypot(target.x - x, target.y - y)
            result.closest_m = min(result.closest_m, distance)
            heading_error = wrap(target.yaw - yaw) if target.yaw is not None else 0.0
            if not result.reached and distance <= o.tolerance_m and abs(heading_error) <= o.heading_tolerance_rad:
                result.reached, result.reached_s = True, self.time_s
            if not self.turning and distance <= o.arrive_m:
                self.turning = target.yaw is not None
            arrived = distance <= o.arrive_m and abs(heading_error) <= o.arrive_rad
            if not (arrived or self.time_s - self._segment_start_s > o.timeout_s):
                break
            self._leave(result, distance, heading_error, yaw)
        self.time_s += dt
        if self.done:
            return 0.0, 0.0, 0.0
        target = self.waypoints[self.index]
        if self.turning:
            return self._turn(target, pose, wrap((target.yaw or 0.0) - yaw), limits_for)
        return self._walk(target, pose, limits_for)

    def _leave(self, result: WaypointResult, distance: float, heading_error: float, yaw: float) -> None:
        """Move on to the next waypoint (the heading to hold is the one reached here)."""
        target = result.waypoint
        result.left_s, result.position_error_m = self.time_s, distance
        result.heading_error_rad = heading_error if target.yaw is not None else None
        self._from = (target.x, target.y)
        self._hold_yaw = target.yaw if target.yaw is not None else yaw
        self._segment_start_s = self.time_s
        self.turning = False
        self.index += 1

    def _walk(self, target: Waypoint, pose: Pose2D, limits_for: LimitsFor) -> Velocity:
        """Along the segment towards ``target``, pulled onto it, heading held."""
        x, y, yaw = pose
        o = self.options
        assert self._from is not None
        ax, ay = self._from
        sx, sy = target.x - ax, target.y - ay
        length = math.hypot(sx, sy)
        if length < 1e-9:  # no segment: straight to the point
            sx, sy, length = target.x - x, target.y - y, max(math.hypot(target.x - x, target.y - y), 1e-12)
        tx, ty = sx / length, sy / length
        along = (target.x - x) * tx + (target.y - y) * ty
        across = (x - ax) * -ty + (y - ay) * tx
        assert self._hold_yaw is not None
        turn = wrap(target.yaw - self._hold_yaw) if o.turn_while_walking and target.yaw is not None else 0.0
        progress = min(max(1.0 - along / length, 0.0), 1.0) if turn else 0.0
        yaw_error = wrap(self._hold_yaw + turn * progress - yaw)
        # the limits in the body direction of the intended motion
        wx, wy = tx * along - ty * across, ty * along + tx * across
        c, s = math.cos(yaw), math.sin(yaw)
        limits = limits_for(c * wx + s * wy, -s * wx + c * wy, 0.0)
        w_cap = o.speed_share * limits.yaw_rate
        brake = o.brake_share * limits.acceleration
        wz = math.copysign(_profile(abs(yaw_error), w_cap, o.brake_share * limits.yaw_acceleration,
                                    o.heading_gain), yaw_error)
        if turn:  # turning while walking: the walker gives up 1 − |ω|/ω_max of the speed for the yaw rate
            share = abs(turn) / length * o.speed_share * limits.speed  # yaw rate at full speed along
            scale = 1.0 / (1.0 + share / limits.yaw_rate) if limits.yaw_rate > 0 else 1.0
            speed = _profile(abs(along), o.speed_share * limits.speed * scale, brake, o.gain)
            wz = max(-w_cap, min(w_cap, math.copysign(abs(turn) / length * speed, turn * along)
                                 + o.heading_gain * yaw_error))
        cap = o.speed_share * limits.speed * (1.0 - abs(wz) / limits.yaw_rate if limits.yaw_rate > 0 else 1.0)
        v_along = math.copysign(_profile(abs(along), cap, brake, o.gain), along)
        v_across = max(-cap, min(cap, -o.gain * across))
        vx_w, vy_w = tx * v_along - ty * v_across, ty * v_along + tx * v_across
        size = math.hypot(vx_w, vy_w)
        if size > cap > 0.0:
            vx_w, vy_w = vx_w * cap / size, vy_w * cap / size
        return c * vx_w + s * vy_w, -s * vx_w + c * vy_w, wz

    def _turn(self, target: Waypoint, pose: Pose2D, heading_error: float, limits_for: LimitsFor) -> Velocity:
        """On the spot to the waypoint's heading, holding the place."""
        x, y, yaw = pose
        o = self.options
        limits = limits_for(0.0, 0.0, math.copysign(1.0, heading_error))
        w_cap = o.speed_share * limits.yaw_rate
        wz = math.copysign(_profile(abs(heading_error), w_cap, o.brake_share * limits.yaw_acceleration,
                                    o.heading_gain), heading_error)
        cap = o.speed_share * limits.speed * (1.0 - abs(wz) / limits.yaw_rate if limits.yaw_rate > 0 else 1.0)
        dx, dy = target.x - x, target.y - y
        vx_w, vy_w = o.gain * dx, o.gain * dy
        size = math.hypot(vx_w, vy_w)
        if size > cap:
            vx_w, vy_w = (vx_w * cap / size, vy_w * cap / size) if size > 0 else (0.0, 0.0)
        c, s = math.cos(yaw), math.sin(yaw)
        return c * vx_w + s * vy_w, -s * vx_w + c * vy_w, wz


def velocity_input(velocity: Velocity, limits: FollowerLimits, throttle: bool) -> Velocity:
    """The walker's velocity input that makes it walk at ``velocity`` (body m/s, rad/s).

    OpenSHC's walker (:func:`shc_cli.control.stepping.walk_update`) gives a throttle input ``(tx, ty, tω)`` the
    velocity ``(tx, ty)·v_max·(1 − |tω|)`` and yaw rate ``tω·ω_max`` (inputs in m/s and rad/s the same with
    ``tω = ω/ω_max``): this is its inverse, in throttle fractions or in m/s and rad/s.
    """
    vx, vy, wz = velocity
    share = abs(wz) / limits.yaw_rate if limits.yaw_rate > 0 else 0.0
    scale = max(1.0 - share, 1e-6)
    if throttle:
        speed = limits.speed * scale
        return ((vx / speed, vy / speed) if speed > 0 else (0.0, 0.0)) + (
            wz / limits.yaw_rate if limits.yaw_rate > 0 else 0.0,)
    return vx / scale, vy / scale, wz
