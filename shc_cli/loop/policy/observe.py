"""The observation and the reward terms of ``shc/Walk-v0``.

The observation (float32, in this order; ``J`` joints in servo order, ``L`` legs in id order):
joint positions ``J`` [rad], joint velocities ``J`` [rad/s], body orientation quaternion (x, y, z, w) ``4``, body
angular rate in the body frame ``3`` [rad/s], foot contacts ``L`` (0/1), foot normal forces ``L`` [N], the
commanded body velocity (x, y [m/s], yaw rate [rad/s]) ``3``, the gait phase: each leg's stance progress ``L`` and
swing progress ``L`` (0…1, −1 outside that phase). :func:`observation_names` lists them.

The reward is a weighted sum of named terms (:data:`TERMS`), each computed from one cycle:

- ``tracking``: ``exp(−(|v − v*| / 0.1 m/s)²)`` of the body's planar velocity (body frame, ground truth) against the
  controller's desired velocity ``v*``, 0…1.
- ``cot``: minus the cost of transport of the cycle, ``P / (m·g·max(|v|, 0.05 m/s))``, from the servos' electrical
  power ``P`` (the servo model of ``shc simulate``) and the body's planar speed ``|v|`` (ground truth: against the
  controller's desired speed a policy would lower the cost by asking for a slower gait).
- ``stability``: the static stability margin [m]: the distance of the body origin's ground projection inside the
  support polygon of the feet in contact (negative outside it, −0.1 with fewer than three feet down).
- ``fall``: −1 on the cycle the robot falls (the fall of ``shc simulate``: tilt above
  :data:`~shc_cli.loop.physics_summary.FALL_TILT` or the body lower than
  :data:`~shc_cli.loop.physics_summary.FALL_HEIGHT_SHARE` of its clearance).
- ``joint_limits``: minus the share of joints whose target is within 5 % of its range from a limit.
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.backends.engine import Reading, tilt
from shc_cli.control.controller import CycleOutput
from shc_cli.loop.physics_summary import FALL_HEIGHT_SHARE, FALL_TILT
from shc_cli.model.chains import Chains, JointSlots
from shc_cli.spec.robot import Robot

TERMS = ("tracking", "cot", "stability", "fall", "joint_limits")
"""The reward terms, by name."""
DEFAULT_WEIGHTS = {"tracking": 1.0, "cot": 0.1, "stability": 0.0, "fall": 10.0, "joint_limits": 0.1}
"""The default weights of the reward terms."""
TRACKING_SCALE = 0.1
"""Velocity error at which the tracking term falls to 1/e [m/s]."""
MIN_SPEED = 0.05
"""The cost of transport's speed floor [m/s] (standing still would divide by zero)."""
LIMIT_SHARE = 0.05
"""A joint target within this share of its range from a limit counts for the ``joint_limits`` term."""
GRAVITY = 9.81


def observation_names(robot: Robot) -> list[str]:
    """The name of every observation entry, in order."""
    joints = [f"{leg}.{joint}" for leg, spec in robot.legs.items() for joint in spec.joints]
    legs = list(robot.legs)
    return ([f"q.{j}" for j in joints] + [f"dq.{j}" for j in joints] + ["qx", "qy", "qz", "qw", "wx", "wy", "wz"]
            + [f"contact.{leg}" for leg in legs] + [f"force.{leg}" for leg in legs] + ["cmd.vx", "cmd.vy", "cmd.wz"]
            + [f"stance.{leg}" for leg in legs] + [f"swing.{leg}" for leg in legs])


def observation_bounds(names: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of each entry (float32): the quaternion within ±1, contacts 0…1, the phase −1…1, the
    rest unbounded."""
    low = np.full(len(names), -np.inf, dtype=np.float32)
    high = np.full(len(names), np.inf, dtype=np.float32)
    for i, name in enumerate(names):
        if name in ("qx", "qy", "qz", "qw") or name.startswith(("stance.", "swing.")):
            low[i], high[i] = -1.0, 1.0
        elif name.startswith("contact."):
            low[i], high[i] = 0.0, 1.0
    return low, high


def observe(slots: JointSlots, reading: Reading, out: CycleOutput) -> np.ndarray:
    """The observation after one cycle (the module's order)."""
    order = slots.servo_order
    return np.concatenate((order(reading.joints), order(reading.joint_velocities), reading.orientation,
                           reading.angular_rate, reading.foot_contact, reading.foot_forces, out.velocity,
                           out.stance_progress, out.swing_progress)).astype(np.float32)


def fallen(robot: Robot, reading: Reading) -> bool:
    """The robot has fallen, by ``shc simulate``'s rule."""
    return tilt(reading.rpy) > FALL_TILT or reading.body_height < FALL_HEIGHT_SHARE * robot.walker.body_clearance


def support_margin(points: np.ndarray) -> float:
    """Signed distance of the origin inside the convex hull of planar ``points`` (−0.1 with fewer than three)."""
    if len(points) < 3:
        return -0.1
    pts = sorted(map(tuple, points.tolist()))
    hull: list[tuple[float, float]] = []
    for sweep in (pts, pts[::-1]):  # Andrew's monotone chain, counter-clockwise
        start = len(hull)
        for p in sweep:
            while len(hull) >= start + 2 and ((hull[-1][0] - hull[-2][0]) * (p[1] - hull[-2][1])
                                              - (hull[-1][1] - hull[-2][1]) * (p[0] - hull[-2][0])) <= 0:
                hull.pop()
            hull.append(p)
        hull.pop()
    if len(hull) < 3:
        return -0.1
    margin = math.inf
    for (x0, y0), (x1, y1) in zip(hull, hull[1:] + hull[:1], strict=True):
        length = math.hypot(x1 - x0, y1 - y0)
        margin = min(margin, ((x1 - x0) * (-y0) - (y1 - y0) * (-x0)) / length)  # > 0: left of the edge
    return margin


class Rewards:
    """The weighted reward terms of one robot (:data:`TERMS`); :meth:`terms` gives each term of a cycle."""

    def __init__(self, robot: Robot, weights: dict[str, float]) -> None:
        unknown = sorted(set(weights) - set(TERMS))
        if unknown:
            raise ValueError(f"reward: no term '{unknown[0]}' (terms: {', '.join(TERMS)})")
        self.robot = robot
        self.weights = {**DEFAULT_WEIGHTS, **weights}
        chains = Chains.from_robot(robot)
        slots = JointSlots.of(robot)
        self.rows, self.cols = slots.rows, slots.cols
        low, high = chains.lower[self.rows, self.cols], chains.upper[self.rows, self.cols]
        margin = LIMIT_SHARE * (high - low)
        self.near_low, self.near_high = low + margin, high - margin
        self.weight_mg = GRAVITY * robot.total_mass()

    def terms(self, out: CycleOutput, reading: Reading, fell: bool) -> dict[str, float]:
        w = self.weights
        vx, vy, _ = out.velocity
        terms = dict.fromkeys(TERMS, 0.0)
        if w["tracking"] or w["cot"]:
            yaw = float(reading.rpy[2])
            c, s = math.cos(yaw), math.sin(yaw)
            wx, wy = float(reading.linear_velocity[0]), float(reading.linear_velocity[1])
            error = math.hypot(c * wx + s * wy - vx, -s * wx + c * wy - vy)
            terms["tracking"] = math.exp(-((error / TRACKING_SCALE) ** 2))
            power = float(reading.servo_power.sum())
            terms["cot"] = -power / (self.weight_mg * max(math.hypot(wx, wy), MIN_SPEED))
        if w["stability"]:
            tips = out.model_tips[np.asarray(reading.foot_contact, dtype=bool), :2]
            terms["stability"] = support_margin(tips)
        terms["fall"] = -1.0 if fell else 0.0
        if w["joint_limits"]:
            q = out.joints[self.rows, self.cols]
            near = np.count_nonzero(q < self.near_low) + np.count_nonzero(q > self.near_high)
            terms["joint_limits"] = -near / len(q)
        return terms

    @staticmethod
    def measures(reading: Reading) -> dict[str, float]:
        """The cycle's servo power [W] and planar body speed [m/s] (ground truth), for ``info``."""
        v = reading.linear_velocity
        return {"power_w": float(reading.servo_power.sum()), "speed_mps": math.hypot(float(v[0]), float(v[1]))}

    def total(self, terms: dict[str, float]) -> float:
        w = self.weights
        return float(sum(w[name] * value for name, value in terms.items()))
