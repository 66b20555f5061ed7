"""Why a plan's leg odometry cannot equal an ideal body path to 1e-9 m (issue 29; docs/odometry.md, "Plan"): the
feet OpenSHC's kinematic robot stands on are not a rigid set. Computed here independently of the estimator: the
least-squares rigid motion of the standing feet between two cycles (2-D Kabsch, numpy) and what it leaves."""

from __future__ import annotations

import numpy as np


def _rigid_residual(before: np.ndarray, after: np.ndarray) -> float:
    """Largest distance [m] a foot is left from the best rigid planar motion taking ``after`` (N, 2) to ``before``."""
    p, q = before - before.mean(0), after - after.mean(0)
    angle = np.arctan2(np.sum(q[:, 0] * p[:, 1] - q[:, 1] * p[:, 0]), np.sum(q * p))
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    return float(np.abs(p - q @ rotation.T).max())


def _residuals(velocity: tuple[float, float, float], cycles: int = 2000) -> tuple[np.ndarray, np.ndarray]:
    """Bullet's tripod walked kinematically (as ``shc plan``): per MOVING cycle, the residual of the standing feet
    (standing in both cycles) as the joints put them (forward kinematics of the commanded joints, what the odometry
    reads) and as the walker commanded them (its tip targets, walk-plane frame) [m]."""
    from shc_cli.api import load_gait, load_robot
    from shc_cli.control.controller import Command, Controller, RobotState

    controller = Controller(load_robot("bullet"), load_gait("tripod"))
    joints_feet, walker_feet = [], []
    previous = None
    for _ in range(cycles):
        running = controller.state == RobotState.RUNNING
        out = controller.step(Command(velocity=velocity if running else (0.0, 0.0, 0.0),
                                      state_request=RobotState.RUNNING), None)
        now = (out.model_tips[:, :2].copy(), out.walker_tips[:, :2].copy(), out.stance_progress >= 0.0,
               controller.walker is not None and controller.walker.state.name == "MOVING")
        if previous is not None and now[3] and previous[3]:
            standing = now[2] & previous[2]
            if standing.sum() < 2:
                continue
            joints_feet.append(_rigid_residual(previous[0][standing], now[0][standing]))
            walker_feet.append(_rigid_residual(previous[1][standing], now[1][standing]))
        previous = now
    assert len(joints_feet) > 600  # it walked
    return np.array(joints_feet), np.array(walker_feet)


def test_the_standing_feet_of_a_plan_are_not_rigid_to_1e_9_m() -> None:
    """Straight ahead the walker's tip targets move as one rigid body (≤ 1e-12 m), but the feet of the commanded
    joints — one damped-least-squares IK step per cycle, as OpenSHC — are each left a different residual: no body
    pose keeps all standing feet still to better than 1e-8 m in any cycle (0.9 µm typically), so no kinematic truth
    exists to 1e-9 m. In a turn the walker's own targets are not rigid either (each foot moves along a chord)."""
    joints_feet, walker_feet = _residuals((1.0, 0.0, 0.0))
    assert walker_feet.max() < 1e-12
    assert joints_feet.min() > 1e-8 and np.median(joints_feet) < 1e-5  # [m] in every cycle; ~0.9 µm typically
    _, turning = _residuals((1.0, 0.0, 0.3))
    assert np.median(turning) > 1e-7
