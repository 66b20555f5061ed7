"""Where a redundant (5-DOF) leg settles while its foot stands still.

OpenSHC's IK adds the null-space gradient of its joint-limit cost ``Φ_p = Σ (w (q_i − c_i)/Δq_i)²`` every cycle
(study §2.1, step 4) and keeps the tip where it is, so a standing leg slides through its null space to the minimum
of ``Φ_p`` on its tip — a posture fixed by the joint limits and the tip alone, whatever path the leg came by. That is
why a simulated robot's standing joint angles (and with them its stance-ground power,
docs/experiments/openshc-cot.md) are a property of its joint limits and stance. The minimum here is found by
SciPy's SLSQP on the study's formula (docs/experiments/vertical_load.py), independently of the controller's
code; the recording is the real binary.
"""

from __future__ import annotations

import numpy as np
import pytest
import vertical_load  # docs/experiments (on the path through conftest): its SLSQP search

from shc_cli.model.chains import Chains
from shc_cli.model.ik import ik_step
from shc_cli.replay.opening import open_source
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Robot

from .conftest import GOLDEN


def _limit_cost_minimum(chains: Chains, leg: int, tip: np.ndarray, start: np.ndarray) -> np.ndarray:
    """Joint angles [rad] minimising the limit cost of leg ``leg`` among those that put its tip at ``tip`` [m]."""
    one = chains.take(np.array([leg]))
    best: np.ndarray = vertical_load.best_posture(one, tip, vertical_load.limit_cost(one.lower[0], one.upper[0]),
                                                  start[None])
    return best


def _distance_to_minimum(chains: Chains, q: np.ndarray) -> np.ndarray:
    """Largest joint difference [rad] per leg between ``q`` and the limit-cost minimum at the same tips."""
    tips = chains.tips(q)
    return np.array([np.abs(_limit_cost_minimum(chains, leg, tips[leg], q[leg]) - q[leg]).max()
                     for leg in range(chains.size)])


def test_the_binary_settles_standing_legs_at_the_limit_cost_minimum(bullet: Robot) -> None:
    """The real OpenSHC, Bullet insectoid: after the turn (cycle 7263) all velocities are zero for 6.7 s; the legs
    start 0.05–0.17 rad away from the minimum at their tips and end within 0.01 rad of it (five of six: 0.003)."""
    recording = open_source(GOLDEN / "openshc-runs" / "insectoid")
    chains = Chains.from_robot(bullet)
    joints = recording.joints.reshape(recording.cycles, chains.size, chains.joints)
    at_stop = _distance_to_minimum(chains, joints[7263])
    at_end = _distance_to_minimum(chains, joints[-1])
    assert at_stop.max() > 0.1
    assert at_end.max() < 0.01
    assert np.all(at_end < at_stop / 5)


@pytest.mark.parametrize("cap", [0.0, 0.5], ids=["openshc", "capped"])
@pytest.mark.parametrize("name", ["bullet", "bullet_mammalian_b", "bullet_insectoid_a"])
def test_our_ik_settles_standing_legs_at_the_limit_cost_minimum(name: str, cap: float) -> None:
    """Our IK step, from the unpacked pose moved to the stance in 2 s and then held for 38 s (100 Hz), ends at the
    same minimum within 0.005 rad for every leg — OpenSHC's own Bullet and two of the paper's robots; both as OpenSHC
    (``avoidance_cap`` 0) and with shc's default cap on the velocity term (docs/deviations.md: no chatter, same
    posture)."""
    robot = load_robot(name).robot
    chains = Chains.from_robot(robot)
    q = np.array([[joint.unpacked for joint in leg.joints.values()] for leg in robot.legs.values()])
    height = robot.walker.body_clearance
    stance = np.array([[leg.stance.x, leg.stance.y, -height] for leg in robot.legs.values()])
    start, qd = chains.tips(q), np.zeros_like(q)
    for cycle in range(1, 4001):
        target = start + (stance - start) * min(cycle / 200, 1.0)
        step = ik_step(chains, q, qd, chains.tips(q), target, 0.01, avoidance_cap=cap)
        q, qd = step.q, step.qd
    np.testing.assert_allclose(chains.tips(q), stance, atol=1e-4)
    assert _distance_to_minimum(chains, q).max() < 0.005
