"""Fit the three servo parameters no datasheet gives to Table IV, from the runs of one Table IV sweep.

Run (after ``shc sweep sweeps/openshc_table4.toml --out runs/openshc_table4``):

    .venv/bin/python docs/experiments/fit_servo.py runs/openshc_table4

The electrical model runs after the physics (``idle_power``, ``coulomb_friction`` and ``holding_ratio`` change no
torque and no motion in either engine), so each run's logged joint torques and angles are re-evaluated with
:meth:`ServoModel.electrical` for any parameter set — the same figures the run printed, to the log's precision. The fit
is least squares on the relative error of the 15 cells against the paper (each parameter mostly sets one scenario:
``idle_power`` stance air, ``coulomb_friction`` walk air, ``holding_ratio`` stance ground). Prints the fitted values
and every cell before and after.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shc_cli.backends.servo import ServoModel
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Servo

TABLE_IV = {("bullet_mammalian_a", "tripod"): (27.7, 51.0, 48.6), ("bullet_mammalian_b", "tripod"): (30.4, 47.1, 46.7),
            ("bullet_insectoid_a", "tripod"): (30.4, 61.9, 58.3), ("bullet_insectoid_a", "bipod"): (30.4, 72.3, 58.3),
            ("bullet_insectoid_b", "tripod"): (31.1, 62.9, 56.0)}
"""Paper Table IV [W]: stance air, walk air, stance ground."""
SCENARIOS = ("SA", "WA", "SG")
FITTED = ("idle_power", "coulomb_friction", "holding_ratio")


@dataclass(frozen=True)
class Cell:
    """One Table IV run: the paper's figure and what the electrical model needs."""

    label: str
    paper: float
    servo: Servo
    torque: np.ndarray
    """Joint torques of every RUNNING control period [N·m] (rows × joints)."""
    speed: np.ndarray
    """Joint speeds [rad/s], by differences of the logged angles."""


def load_cells(sweep: Path) -> list[Cell]:
    """The sweep's runs as cells, from results.csv and each run's robot.toml and log.csv."""
    cells = []
    with open(sweep / "results.csv", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    for row in rows:
        run = sweep / "runs" / row["slug"]
        robot = load_robot(run / "robot.toml").robot
        assert robot is not None, f"{run}: robot.toml holds no robot"
        names = [f"{leg}_{joint}" for leg in robot.legs for joint in robot.legs[leg].joints]
        with open(run / "log.csv", encoding="utf-8") as handle:
            log = list(csv.reader(handle))
        header, body = log[0], log[1:]
        columns = [header.index(c) for c in [*names, *(name + "_torque" for name in names)]]
        table = np.array([[float(line[i]) for i in columns] for line in body])
        angles, torque = table[:, :len(names)], table[:, len(names):]
        speed = np.vstack([np.zeros((1, len(names))), np.diff(angles, axis=0) / robot.time_delta])
        state = header.index("robot_state")
        running = np.array([line[state] == "RUNNING" for line in body])  # the summary's window
        paper = TABLE_IV[(row["robot"], row["gait"])][SCENARIOS.index(row["scenario"])]
        cells.append(Cell(f"{row['robot']} {row['gait']} {row['scenario']}", paper, robot.servo, torque[running],
                          speed[running]))
    return cells


def mean_power(cell: Cell, values: dict[str, float]) -> float:
    """The cell's mean supply power [W] with the fitted parameters set to ``values``."""
    servo = cell.servo.model_copy(update=values)
    return float(ServoModel(servo).electrical(cell.torque, cell.speed).power.sum(axis=1).mean())


def fit(cells: list[Cell]) -> dict[str, float]:
    """Least squares on the cells' relative errors over the three parameters (holding ratio within 0 … 1)."""
    from scipy.optimize import least_squares

    def residuals(x: np.ndarray) -> np.ndarray:
        values = dict(zip(FITTED, map(float, x), strict=True))
        return np.array([mean_power(cell, values) / cell.paper - 1.0 for cell in cells])

    start = np.array([getattr(cells[0].servo, name) for name in FITTED])
    result = least_squares(residuals, start, bounds=([0.0, 0.0, 0.0], [5.0, 5.0, 1.0]))
    return dict(zip(FITTED, map(float, result.x), strict=True))


def main(arguments: list[str]) -> None:
    cells = load_cells(Path(arguments[0]))
    before = {name: getattr(cells[0].servo, name) for name in FITTED}
    after = fit(cells)
    print("fitted: " + ", ".join(f"{k} {before[k]:.3g} -> {v:.3g}" for k, v in after.items()))
    for cell in cells:
        old, new = mean_power(cell, before), mean_power(cell, after)
        print(f"{cell.label:36s} paper {cell.paper:5.1f}  now {old:5.1f} ({old / cell.paper - 1:+.0%})"
              f"  fitted {new:5.1f} ({new / cell.paper - 1:+.0%})")


if __name__ == "__main__":
    from script import run

    run(main, "TABLE4_SWEEP_DIR (the --out of shc sweep sweeps/openshc_table4.toml)", 1, 1)
