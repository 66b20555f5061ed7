"""OpenSHC's direct start-up (study §9.2): plan the default stance by IK, then move in joint space.

The plan walks a copy of each leg from its start joints to the stance position along OpenSHC's
``stepToPosition`` path (two quartic Bézier halves, no lift) while the body rises from the ground
plane to ``body_clearance``, one IK step per control period. The joints it ends with are the
robot's *default configuration*: the workspace search starts there, and the real joints are then
moved to it by a cubic joint-space transition.
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.control.bezier import cubic, quartic, smooth_step
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.ik import ik_step
from shc_cli.spec.robot import Robot

TIP_TOLERANCE = 0.01
"""A tip this close to its target [m] needs no start-up path."""


def iterations(duration: float, time_delta: float) -> int:
    """Control cycles of a transition lasting ``duration`` [s]: ``max(1, round(duration/dt))``."""
    ratio = duration / time_delta
    rounded = int(ratio + 0.5) if ratio >= 0 else -int(0.5 - ratio)
    return max(1, rounded)


CUBIC_PEAK_RATE = 1.5
"""Largest slope of OpenSHC's cubic transition ``3s² − 2s³`` (at s = ½): its fastest cycle moves a joint at most
1.5·|Δq|/n."""


def transition_iterations(origin: FloatArray, target: FloatArray, max_vel: FloatArray, duration: float,
                          time_delta: float) -> int:
    """Cycles of a joint-space transition from ``origin`` to ``target``: OpenSHC's ``round(duration/dt)``, or more
    where that would move a joint faster than its ``max_vel`` (an shc addition, docs/deviations.md: no start-up or
    shut-down commands a joint beyond its speed limit; a longer transition rather than a guard-limited one that
    ends short of its target)."""
    n = iterations(duration, time_delta)
    travel = np.abs(np.asarray(target, dtype=float) - np.asarray(origin, dtype=float))
    needed = float(np.max(CUBIC_PEAK_RATE * travel / (np.asarray(max_vel, dtype=float) * time_delta), initial=0.0))
    return max(n, math.ceil(needed - 1e-9))


def stance_targets(robot: Robot) -> FloatArray:
    """Default tip positions in the walk plane, ``(L, 3)``: ``(x_s, y_s, 0)`` [m]."""
    return np.array([[leg.stance.x, leg.stance.y, 0.0] for leg in robot.legs.values()])


def plan_direct_startup(robot: Robot, chains: Chains, start_joints: FloatArray) -> FloatArray:
    """Joint positions reached by simulating OpenSHC's direct start-up path, ``(L, n)`` [rad].

    Args:
        robot: the robot (body clearance, control period, time to start).
        chains: its legs.
        start_joints: joints the simulation starts from (OpenSHC: the joint defaults, ``clamp(0, min, max)``).
    """
    dt = robot.time_delta
    height = robot.walker.body_clearance
    n = iterations(robot.start_up.time_to_start, dt)
    half = n // 2
    step_t = 1.0 / n
    q = np.array(start_joints, dtype=float)
    qd = np.zeros_like(q)
    tip = chains.tips(q)
    origin = tip.copy()
    stance = stance_targets(robot)
    body_final = np.array([0.0, 0.0, height])
    done = np.linalg.norm(origin - (stance - body_final), axis=1) <= TIP_TOLERANCE
    offset = origin - stance
    primary = np.stack([origin, origin, origin, stance + 0.75 * offset, stance + 0.5 * offset])
    secondary = np.stack([stance + 0.5 * offset, stance + 0.25 * offset, stance, stance, stance])
    for count in range(1, n + 1):
        c = smooth_step((count - 1) / n)
        body = c * body_final + (1.0 - c) * np.zeros(3)
        if count <= half:
            point = quartic(primary, count * step_t * 2.0)
        else:
            point = quartic(secondary, (count - half) * step_t * 2.0)
        target = np.where(done[:, None], origin, (-body) + point)
        step = ik_step(chains, q, qd, tip, target, dt, clamp_velocities=False)
        moving = ~done[:, None] | (count == 1)
        q, qd = np.where(moving, step.q, q), np.where(moving, step.qd, qd)
        tip = np.where(moving, step.tip, tip)
        if done.all():
            break
    return q


def joint_transition(origin: FloatArray, target: FloatArray, duration: float, time_delta: float) -> list[FloatArray]:
    """Joint positions of each cycle of OpenSHC's cubic joint-space transition (``transitionConfiguration``).

    The first cycle is already at τ = 1/n and the last lands exactly on ``target``.
    """
    n = iterations(duration, time_delta)
    step_t = 1.0 / n
    nodes = np.stack([origin, origin, target, target])
    return [cubic(nodes, count * step_t) for count in range(1, n + 1)]
