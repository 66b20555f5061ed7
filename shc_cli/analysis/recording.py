"""Replaying a recording of the real OpenSHC binary through our controller and measuring the difference.

A recording (``<name>_joints.csv.gz``, ``<name>_tips.csv.gz``, ``<name>_body.csv.gz``, see
``shared/reference/openshc-runs/README.md``) holds one row per control cycle. The replay starts from the
same joints (all 0), makes the same state requests (start-up when the recorded joints first move,
RUNNING when the start-up ends) and feeds the recorded velocity commands with OpenSHC's one-cycle input
latency: the command the recorder saw before cycle ``c − 1``'s output is used in cycle ``c`` (OpenSHC
reads its topics after publishing). Every recorded quantity is then compared cycle by cycle.
"""

from __future__ import annotations

import csv
import gzip
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.control.startup import iterations
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot

INPUT_LATENCY_CYCLES = 1
"""Cycles between the recorder seeing a command and OpenSHC using it (measured at all 5 changes)."""


@dataclass(frozen=True)
class Table:
    """A recorded CSV: column names and a float matrix (one row per cycle)."""

    columns: list[str]
    rows: np.ndarray

    def column(self, name: str) -> np.ndarray:
        return np.asarray(self.rows[:, self.columns.index(name)])

    def columns_of(self, names: list[str]) -> np.ndarray:
        return np.asarray(self.rows[:, [self.columns.index(n) for n in names]])


def read_table(path: Path) -> Table:
    """Read a (possibly gzipped) CSV of numbers."""
    opener = gzip.open if path.suffix == ".gz" else open
    with opener(path, "rt") as handle:
        reader = csv.reader(handle)
        columns = next(reader)
        rows = np.array([[float(v) for v in row] for row in reader])
    return Table(columns, rows)


@dataclass(frozen=True)
class Recording:
    """The three tables of one recorded run."""

    joints: Table
    tips: Table
    body: Table

    @classmethod
    def load(cls, folder: Path, name: str) -> Recording:
        return cls(*(read_table(folder / f"{name}_{part}.csv.gz") for part in ("joints", "tips", "body")))

    @property
    def cycles(self) -> int:
        return len(self.joints.rows)


@dataclass
class Comparison:
    """Largest absolute differences over the replay, and the cycle where each occurred."""

    worst: dict[str, float] = field(default_factory=dict)
    at_cycle: dict[str, int] = field(default_factory=dict)

    def add(self, name: str, cycle: int, difference: float) -> None:
        if difference > self.worst.get(name, -1.0):
            self.worst[name] = difference
            self.at_cycle[name] = cycle


def startup_cycles(recording: Recording, robot: Robot) -> dict[int, RobotState]:
    """State requests that reproduce the recorded start-up: the joints first move in the start-up's first
    cycle, RUNNING is requested once its ``time_to_start`` has passed."""
    joints = recording.joints.rows[:, 2:]
    moved = np.flatnonzero(np.abs(joints - joints[0]).max(axis=1) > 0.0)
    start = int(moved[0]) if len(moved) else 1
    steps = iterations(robot.start_up.time_to_start, robot.time_delta)
    return {0: RobotState.RUNNING, start: RobotState.RUNNING, start + steps: RobotState.RUNNING}


def replay(recording: Recording, robot: Robot, gait: Gait) -> Comparison:
    """Run the controller on the recorded inputs and compare joints, tips, progress and velocity."""
    legs = list(robot.legs)
    joint_names = [f"{leg}_{joint}_joint" for leg, spec in robot.legs.items() for joint in spec.joints]
    tips = recording.tips
    stage_columns = {stage: [f"{leg}_{stage}_{axis}" for leg in legs for axis in "xyz"]
                     for stage in ("walker", "poser", "model")}
    commands = recording.body.columns_of(["cmd_vx", "cmd_vy", "cmd_wz"])
    velocities = recording.body.columns_of(["vel_x", "vel_y", "vel_wz"])
    recorded_joints = recording.joints.columns_of(joint_names)
    recorded_tips = {stage: tips.columns_of(columns) for stage, columns in stage_columns.items()}
    stance = tips.columns_of([f"{leg}_stance_progress" for leg in legs])
    swing = tips.columns_of([f"{leg}_swing_progress" for leg in legs])
    requests = startup_cycles(recording, robot)
    controller = Controller(robot, gait)
    comparison = Comparison()
    for cycle in range(recording.cycles):
        source = cycle - INPUT_LATENCY_CYCLES
        velocity = tuple(commands[source]) if source >= 0 else (0.0, 0.0, 0.0)
        out = controller.step(Command(velocity=velocity, state_request=requests.get(cycle)))
        _compare(comparison, cycle, out, recorded_joints[cycle], {k: v[cycle] for k, v in recorded_tips.items()},
                 stance[cycle], swing[cycle], velocities[cycle])
    return comparison


def _compare(comparison: Comparison, cycle: int, out: CycleOutput, joints: np.ndarray, tips: dict[str, np.ndarray],
             stance: np.ndarray, swing: np.ndarray, velocity: np.ndarray) -> None:
    comparison.add("joints_rad", cycle, float(np.abs(out.joints.ravel() - joints).max()))
    comparison.add("walker_tip_m", cycle, float(np.abs(out.walker_tips.ravel() - tips["walker"]).max()))
    comparison.add("poser_tip_m", cycle, float(np.abs(out.poser_tips.ravel() - tips["poser"]).max()))
    comparison.add("model_tip_m", cycle, float(np.abs(out.model_tips.ravel() - tips["model"]).max()))
    comparison.add("progress", cycle, float(max(np.abs(out.stance_progress - stance).max(),
                                                np.abs(out.swing_progress - swing).max())))
    comparison.add("velocity", cycle, float(np.abs(np.array(out.velocity) - velocity).max()))
