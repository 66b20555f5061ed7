"""Cycle-by-cycle differences between the controller's outputs and a recorded OpenSHC run.

Every quantity the source holds is compared as the largest absolute difference over its numbers in a cycle:
joints [rad], walker/poser/model tips [m], body velocity (x, y [m/s] and yaw rate [rad/s] together), stance and
swing progress, body pose (x, y, z [m], roll, pitch, yaw [rad] together). Recorded numbers that are not usable
(non-finite, or absurd as OpenSHC's 2147483647 for a tip not yet posed) are skipped and counted per quantity.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shc_cli.control.controller import CycleOutput
from shc_cli.errors import ShcError
from shc_cli.replay.source import TIP_STAGES, Recorded, usable
from shc_cli.spec.robot import Robot

QUANTITIES = ("joints_rad", "model_tip_m", "walker_tip_m", "poser_tip_m", "velocity", "progress", "pose")
"""Compared quantities, in report order."""

LABELS = {"joints_rad": ("joints", "rad"), "model_tip_m": ("model tips", "m"), "walker_tip_m": ("walker tips", "m"),
          "poser_tip_m": ("poser tips", "m"), "velocity": ("body velocity", "m/s, rad/s"),
          "progress": ("phase progress", ""), "pose": ("body pose", "m, rad")}


def joint_names(robot: Robot) -> list[str]:
    """OpenSHC's joint names of a robot, in leg order (``AR_coxa_joint``, …)."""
    return [f"{leg}_{joint}_joint" for leg, spec in robot.legs.items() for joint in spec.joints]


def robot_joint_names(robot: Robot) -> list[str]:
    """The joints' names on the robot, in leg order: ``[hardware.servos]``'s ``joint`` where given (an imported
    URDF's joint names), else OpenSHC's (:func:`joint_names`); see :func:`shc_cli.model.body.hardware_joint_names`."""
    from shc_cli.model.body import hardware_joint_names

    return hardware_joint_names(robot)


@dataclass
class Comparison:
    """Per-cycle differences (NaN where nothing was compared), the worst of each quantity and its cycle, and the
    recorded numbers skipped."""

    differences: dict[str, np.ndarray]
    skipped: dict[str, int]
    compared: list[str] = field(default_factory=list)
    """What was compared, in words, for the report."""
    missing: list[str] = field(default_factory=list)
    """What the source does not hold (so was not compared)."""

    @property
    def quantities(self) -> list[str]:
        return [q for q in QUANTITIES if q in self.differences]

    @property
    def worst(self) -> dict[str, float]:
        return {q: float(np.nanmax(d)) for q, d in self.differences.items() if np.isfinite(d).any()}

    @property
    def at_cycle(self) -> dict[str, int]:
        return {q: int(np.nanargmax(d)) for q, d in self.differences.items() if np.isfinite(d).any()}


class Comparer:
    """Compares each cycle's :class:`CycleOutput` with the recorded cycle (robot legs and joints in the robot's order).

    Raises :class:`ShcError` at construction if the recorded joints are not the robot's.
    """

    def __init__(self, recorded: Recorded, robot: Robot) -> None:
        names = joint_names(robot)
        own = robot_joint_names(robot)
        if own != names and all(name in recorded.joint_names for name in own):
            names = own  # recorded on the robot under its own (URDF) joint names
        missing = [name for name in names if name not in recorded.joint_names]
        extra = [name for name in recorded.joint_names if name not in names]
        if missing or extra:
            shown = ", ".join(recorded.joint_names[:3]) + (", …" if len(recorded.joint_names) > 3 else "")
            what = (f"{len(missing)} of its {len(names)} joints are missing, e.g. {missing[0]}" if missing else
                    f"{len(extra)} of the {len(recorded.joint_names)} recorded joints are not its, e.g. {extra[0]}")
            raise ShcError(f"{recorded.source}: the recorded joints ({shown}) are not those of robot "
                           f"'{robot.name}': {what} (replay with the robot that was recorded: --robot)")
        n = recorded.cycles
        self.recorded = recorded
        columns = [recorded.joint_names.index(name) for name in names]
        self.joints = recorded.joints[:, columns]
        self.legs = [i for i, leg in enumerate(robot.legs) if leg in recorded.legs]
        """Robot leg indices the source has tips and progress for."""
        source_legs = [recorded.legs.index(leg) for leg in robot.legs if leg in recorded.legs]
        self.series: dict[str, np.ndarray] = {"joints_rad": self.joints}
        if recorded.tips is not None and self.legs:
            for stage in TIP_STAGES:
                self.series[f"{stage}_tip_m"] = recorded.tips[stage][:, source_legs].reshape(n, -1)
        if recorded.progress is not None and self.legs:
            self.series["progress"] = recorded.progress[:, source_legs].reshape(n, -1)
        if recorded.velocity is not None:
            self.series["velocity"] = recorded.velocity
        if recorded.pose is not None:
            self.series["pose"] = recorded.pose
        self.ok = {q: usable(values) for q, values in self.series.items()}
        self.differences = {q: np.full(n, np.nan) for q in self.series}
        legs = len(robot.legs)
        compared = [f"joints ({len(names)})"]
        absent = []
        if "model_tip_m" in self.series:
            compared.append(f"walker, poser and model tips and stance/swing progress ({len(self.legs)} of {legs} "
                            "legs)")
        else:
            absent.append("tips and phase progress (/shc/LEG/state)")
        for q, topic in (("velocity", "/shc/velocity"), ("pose", "/shc/pose")):
            (compared if q in self.series else absent).append(f"{LABELS[q][0]}" if q in self.series
                                                              else f"{LABELS[q][0]} ({topic})")
        self.compared, self.missing = compared, absent

    def add(self, cycle: int, out: CycleOutput) -> None:
        """Compare one cycle's outputs."""
        produced: dict[str, np.ndarray] = {"joints_rad": out.joints.ravel()}
        if "model_tip_m" in self.series:
            produced["walker_tip_m"] = out.walker_tips[self.legs].ravel()
            produced["poser_tip_m"] = out.poser_tips[self.legs].ravel()
            produced["model_tip_m"] = out.model_tips[self.legs].ravel()
        if "progress" in self.series:
            produced["progress"] = np.column_stack([out.stance_progress[self.legs],
                                                    out.swing_progress[self.legs]]).ravel()
        if "velocity" in self.series:
            produced["velocity"] = np.asarray(out.velocity, dtype=float)
        if "pose" in self.series:
            produced["pose"] = np.asarray(out.pose, dtype=float)
        for q, values in produced.items():
            ok = self.ok[q][cycle]
            if ok.any():
                self.differences[q][cycle] = float(np.abs(values[ok] - self.series[q][cycle][ok]).max())

    def result(self) -> Comparison:
        """The comparison so far (skipped counts cover every recorded cycle)."""
        skipped = {q: int((~ok).sum()) for q, ok in self.ok.items()}
        return Comparison(self.differences, skipped, self.compared, self.missing)
