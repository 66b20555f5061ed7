"""Stance-ground power if every foot carried only its share of the weight, at the joint angles a run stood in, and
at the cheapest posture that puts the feet in the same places.

Run on ``shc simulate ROBOT --scenario SG`` run directories (docs/experiments/openshc-cot.md, "Stance ground"):

    .venv/bin/python docs/experiments/vertical_load.py runs/sg-bullet_insectoid_a runs/sg-bullet_mammalian_a

For each run: the mean joint angles of its last 2 s, the joint torques ``τ = Jᵀ(0, 0, m·g/legs)`` that a purely
vertical foot force needs there, and the supply power the robot's servo model draws holding them (joint speed 0).
The simulated stance power minus this is what friction at the feet carried (or cost). Two more columns: how far
the standing angles are from the minimum of OpenSHC's joint-limit cost at the same feet (where a redundant leg's IK
settles while its foot stands still; tests/test_null_space.py), and the least vertical-load power of any posture
within the joint limits that puts the feet where they stood (SLSQP from 24 starts per leg) — what the stance would
cost if the legs stood in their best posture instead of the one their joint limits choose.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from shc_cli.backends.servo import ServoModel
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot

G = 9.81
"""Gravity [m/s²]."""
STARTS = 24
"""Random starting postures per leg for the least-power search."""


def _leg_torque(chain: Chains, q: np.ndarray, force: np.ndarray) -> np.ndarray:
    """Joint torques [N·m] of one leg at joints ``q`` [rad] carrying the foot force ``force`` [N] given in base_link
    (the Jacobian is in the leg frame, whose axes differ from base_link's where the leg's base DH tilts them)."""
    return np.asarray(chain.jacobians(q[None])[0].T @ (chain.base[0, :3, :3].T @ force))


def _leg_power(servo: ServoModel, chain: Chains, q: np.ndarray, *, force: np.ndarray) -> float:
    """Supply power [W] of one leg's servos holding the foot force ``force`` [N] (base_link) at joints ``q`` [rad]."""
    torque = _leg_torque(chain, q, force)
    return float(servo.electrical(torque, np.zeros(torque.size)).power.sum())


def best_posture(chain: Chains, tip: np.ndarray, cost: Callable[[np.ndarray], float],
                 starts: np.ndarray) -> np.ndarray:
    """Joints [rad] of the one-leg ``chain`` within its limits that put the tip at ``tip`` [m] and minimise
    ``cost`` (SLSQP from each of ``starts``, the best success)."""
    bounds = list(zip(chain.lower[0], chain.upper[0], strict=True))
    reach = {"type": "eq", "fun": lambda q: chain.tips(q[None])[0] - tip}
    found = [minimize(cost, start, method="SLSQP", bounds=bounds, constraints=[reach], options={"ftol": 1e-10})
             for start in starts]
    good = [r for r in found if r.success and np.abs(chain.tips(r.x[None])[0] - tip).max() < 1e-4]
    return np.asarray(min(good, key=lambda r: r.fun).x)


@dataclass(frozen=True)
class VerticalLoad:
    """What holding the weight with vertical foot forces costs at one run's stance."""

    robot: str
    power: float
    """Supply power [W] at the joint angles the run stood in."""
    least: float
    """Supply power [W] at the cheapest posture within the joint limits with the same feet."""
    torque: np.ndarray
    """Mean |τ| per joint over the legs [N·m] at the run's angles."""
    from_limit_minimum: float
    """Largest joint distance [rad] between the run's angles and the limit-cost minimum at the same feet."""


def limit_cost(lower: np.ndarray, upper: np.ndarray) -> Callable[[np.ndarray], float]:
    """OpenSHC's joint-limit cost without its weight: Σ ((q − centre)/range)² (study §2.1, step 4)."""
    centre, span = (lower + upper) / 2, np.where(upper > lower, upper - lower, 1.0)
    return lambda q: float(np.sum(((q - centre) / span) ** 2))


def vertical_load(run: Path, window_s: float = 2.0) -> VerticalLoad:
    """The vertical-load figures of one ``shc simulate --scenario SG`` run, from its last ``window_s`` [s]."""
    robot = load_robot(run / "robot.toml").robot
    assert robot is not None, f"{run}: robot.toml holds no robot"
    legs = list(robot.legs)
    names = [f"{leg}_{joint}" for leg in legs for joint in robot.legs[leg].joints]
    with open(run / "log.csv", encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
    table = np.genfromtxt(run / "log.csv", delimiter=",", skip_header=1,
                          usecols=[header.index(c) for c in ["t", *names]])
    angles = table[table[:, 0] > table[-1, 0] - window_s, 1:].mean(axis=0).reshape(len(legs), -1)
    chains = Chains.from_robot(robot)
    servo = ServoModel(robot.servo)
    force = np.array([0.0, 0.0, robot.total_mass() * G / len(legs)])
    tips = chains.tips(angles)
    rng = np.random.default_rng(0)
    torque = np.empty_like(angles)
    stood = least = drift = 0.0
    for leg in range(chains.size):
        chain = chains.take(np.array([leg]))
        torque[leg] = _leg_torque(chain, angles[leg], force)
        lower, upper = chain.lower[0], chain.upper[0]
        settled = best_posture(chain, tips[leg], limit_cost(lower, upper), angles[leg][None])
        drift = max(drift, float(np.abs(settled - angles[leg]).max()))
        stood += _leg_power(servo, chain, angles[leg], force=force)
        starts = np.vstack([angles[leg], rng.uniform(lower, upper, (STARTS - 1, lower.size))])
        cheapest = best_posture(chain, tips[leg], partial(_leg_power, servo, chain, force=force), starts)
        least += _leg_power(servo, chain, cheapest, force=force)
    return VerticalLoad(robot.name, stood, least, np.abs(torque).mean(axis=0), drift)


def main(runs: list[str]) -> None:
    for run in runs:
        row = vertical_load(Path(run))
        print(f"{row.robot:22s} vertical load {row.power:6.1f} W (cheapest posture, same feet: {row.least:5.1f} W)"
              f"   mean |τ| per joint [N·m] {np.round(row.torque, 2).tolist()}"
              f"   stance − limit-cost minimum ≤ {row.from_limit_minimum:.3f} rad")


if __name__ == "__main__":
    from script import run

    run(main, "SG_RUN_DIR [SG_RUN_DIR ...] (shc simulate ROBOT --scenario SG run directories)", 1)
