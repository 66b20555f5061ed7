"""A recorded OpenSHC run as per-cycle arrays, whatever it was read from (the recorder's CSVs or a ROS bag).

:func:`shc_cli.replay.opening.open_source` decides what ``SOURCE`` is: a recording prefix ``DIR/NAME``
(``NAME_joints.csv.gz``, …, see :mod:`shc_cli.replay.recording`), a ROS 1 ``.bag`` file or a ROS 2 bag directory
(mcap or sqlite3, see :mod:`shc_cli.replay.bagfile`). Both readers give a :class:`Recorded`: one row per control
cycle of OpenSHC, the inputs it received before each cycle's output and whatever of its outputs the source holds.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ABSURD = 1e3
"""Recorded numbers larger than this in magnitude are not compared (OpenSHC prints 2147483647 for a tip it has not
posed yet); neither are non-finite ones."""

TIP_STAGES = ("walker", "poser", "model")
"""LegState's tip poses that are compared: walker (walk_plane), poser (IK target) and model (after IK), [m]."""

RECORDING_PARTS = ("joints", "tips", "body")


@dataclass
class Recorded:
    """One OpenSHC run, one row per control cycle (N rows).

    Attributes:
        source: the file, directory or prefix it was read from.
        kind: ``"recording"``, ``"ROS 1 bag"`` or ``"ROS 2 bag"``.
        t: time of each cycle's output since the first [s], ``(N,)``.
        joint_names: names of the recorded joints (``/desired_joint_states``), ``(J,)``.
        joints: desired joint positions [rad], ``(N, J)``.
        command: the last velocity input (``/syropod_remote/desired_velocity``: linear x, y, angular z) received
            before each cycle's output, ``(N, 3)`` (0 before the first).
        robot_state: the last requested robot state (``/syropod_remote/robot_state``) received before each cycle's
            output, ``(N,)`` (NaN before the first), or ``None`` when the source does not hold it.
        legs: leg ids of ``tips`` and ``progress``.
        tips: walker, poser and model tip positions by stage, each ``(N, L, 3)`` [m], or ``None``.
        progress: stance and swing progress per leg ``(N, L, 2)`` (−1 outside the phase), or ``None``.
        velocity: OpenSHC's desired body velocity (``/shc/velocity``: x, y [m/s], yaw rate [rad/s]) ``(N, 3)``,
            or ``None``.
        pose: OpenSHC's body pose (``/shc/pose``: x, y, z [m], roll, pitch, yaw [rad]) ``(N, 6)``, or ``None``.
        topics: the topics (or CSV files) that were read, for the report.
        not_replayed: other ``/syropod_remote/…`` inputs the source holds messages of (posing, gait selection, …),
            which the replay does not feed to the controller.
    """

    source: Path
    kind: str
    t: np.ndarray
    joint_names: list[str]
    joints: np.ndarray
    command: np.ndarray
    robot_state: np.ndarray | None = None
    legs: list[str] = field(default_factory=list)
    tips: dict[str, np.ndarray] | None = None
    progress: np.ndarray | None = None
    velocity: np.ndarray | None = None
    pose: np.ndarray | None = None
    topics: list[str] = field(default_factory=list)
    not_replayed: list[str] = field(default_factory=list)

    @property
    def cycles(self) -> int:
        return len(self.t)

    def head(self, cycles: int) -> Recorded:
        """The first ``cycles`` cycles only."""
        return self.rows(0, cycles)

    def rows(self, start: int, stop: int) -> Recorded:
        """Cycles ``start`` to ``stop − 1`` (times as recorded)."""
        def cut(a: np.ndarray | None) -> np.ndarray | None:
            return None if a is None else a[start:stop]

        return Recorded(self.source, self.kind, self.t[start:stop], self.joint_names, self.joints[start:stop],
                        self.command[start:stop], cut(self.robot_state), self.legs,
                        None if self.tips is None else {k: v[start:stop] for k, v in self.tips.items()},
                        cut(self.progress), cut(self.velocity), cut(self.pose), self.topics, self.not_replayed)


def usable(values: np.ndarray) -> np.ndarray:
    """True where a recorded number can be compared: finite and not absurd (see :data:`ABSURD`)."""
    with np.errstate(invalid="ignore"):
        ok: np.ndarray = np.isfinite(values) & (np.abs(values) <= ABSURD)
    return ok
