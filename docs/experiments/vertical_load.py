"""Stance-ground power if every foot carried only its share of the weight, at the joint angles a run stood in.

Run on ``shc simulate ROBOT --scenario SG`` run directories (docs/experiments/openshc-cot.md, "Stance ground"):

    .venv/bin/python docs/experiments/vertical_load.py runs/sg-bullet_insectoid_a runs/sg-bullet_mammalian_a

For each run: the mean joint angles of its last 2 s, the joint torques ``τ = Jᵀ(0, 0, m·g/legs)`` that a purely
vertical foot force needs there, and the supply power the robot's servo model draws holding them (joint speed 0).
The simulated stance power minus this is what friction at the feet carried (or cost).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from shc_cli.backends.servo import ServoModel
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot

G = 9.81
"""Gravity [m/s²]."""


def vertical_load_power(run: Path, window_s: float = 2.0) -> tuple[str, float, np.ndarray]:
    """Robot name, supply power [W] and mean |τ| per joint [N·m] of the vertical load at the run's last stance."""
    robot = load_robot(run / "robot.toml").robot
    assert robot is not None, f"{run}: robot.toml holds no robot"
    legs = list(robot.legs)
    names = [f"{leg}_{joint}" for leg in legs for joint in robot.legs[leg].joints]
    with open(run / "log.csv", encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
    table = np.genfromtxt(run / "log.csv", delimiter=",", skip_header=1,
                          usecols=[header.index(c) for c in ["t", *names]])
    angles = table[table[:, 0] > table[-1, 0] - window_s, 1:].mean(axis=0).reshape(len(legs), -1)
    jacobians = Chains.from_robot(robot).jacobians(angles)  # (legs, 3, joints), body frame
    force = np.array([0.0, 0.0, robot.total_mass() * G / len(legs)])
    torque = np.einsum("lkn,k->ln", jacobians, force)
    power = ServoModel(robot.servo).electrical(torque.ravel(), np.zeros(torque.size)).power.sum()
    return robot.name, float(power), np.abs(torque).mean(axis=0)


def main(runs: list[str]) -> None:
    for run in runs:
        name, power, torque = vertical_load_power(Path(run))
        print(f"{name:22s} vertical load {power:6.1f} W   mean |τ| per joint [N·m] {np.round(torque, 2).tolist()}")


if __name__ == "__main__":
    from script import run

    run(main, "SG_RUN_DIR [SG_RUN_DIR ...] (shc simulate ROBOT --scenario SG run directories)", 1)
