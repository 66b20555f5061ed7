"""The one run-log format: a run directory of CSV tables written row by row, plus ``summary.json``.

While a run is going its directory is ``<name>.partial``; every completed control cycle is already on
disk (rows are flushed as they are written), so an interrupted run keeps what it did and is clearly
marked. :meth:`RunWriter.finish` writes the summary and renames the directory to its final name.
``robot.toml`` holds the fully expanded robot of the run.

Tables (one row per control cycle, ``cycle`` and time ``t`` [s] first):
* ``joints.csv`` — desired joint positions [rad], one column ``<LEG>_<joint>`` per joint;
* ``tips.csv`` — per leg the OpenSHC LegState stages: ``<LEG>_walker_{x,y,z}`` (walk-plane frame),
  ``<LEG>_poser_{x,y,z}`` and ``<LEG>_model_{x,y,z}`` (base_link) [m], ``<LEG>_stance_progress``,
  ``<LEG>_swing_progress`` (−1 when not in that phase) — the format of the OpenSHC recordings;
* ``body.csv`` — ``cmd_{vx,vy,wz}`` (input), ``vel_{x,y,wz}`` (desired velocity after limits) [m/s, rad/s],
  ``pose_{x,y,z,roll,pitch,yaw}`` (body pose in the walk plane) [m, rad], ``odom_{x,y,yaw}`` (leg odometry in the
  odom frame) [m, rad], ``robot_state``, ``walk_state``.

Runs on a measuring backend (``simulate``, ``run-hw``) have one table instead, ``log.csv``, whose columns
:func:`log_columns` defines (the only place): commanded and measured joints, torques, servo power, foot forces
and contacts, ground-truth body pose and twist, IMU, height, total power, input and desired velocity, leg odometry,
states.
The column set is the same for every measuring backend so every reader sees one schema; what a backend does
not measure (a real robot: body pose, IMU, foot forces, power) is written as 0 and listed in the summary's
``unmeasured`` (see docs/architecture.md).

``summary.json`` of every run says whether it ran to its end: ``"complete"`` (true when the input or the
duration was played to its end) and ``"stop_reason"`` (``"end"``, ``"SIGINT"``, ``"SIGTERM"``, ``"fault"``,
``"fell"``). An interrupted run is still finished (summary written, directory renamed to its final name): it is
marked only by ``"complete": false``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import IO, TYPE_CHECKING, Generic, TypeVar

import numpy as np

from shc_cli.backends.base import MEASURED_BODY_COLUMNS, Measured
from shc_cli.errors import OutputError
from shc_cli.model.chains import JointSlots, joint_slots
from shc_cli.record.stop_signals import StopSignals
from shc_cli.spec.robot import Robot

if TYPE_CHECKING:  # the controller (and numba) only for the annotation: readers of runs stay light
    from shc_cli.backends.base import MeasuringBackend
    from shc_cli.control.controller import Command, CycleOutput
    from shc_cli.record.summary import RunSummary

ReadingT = TypeVar("ReadingT")
"""The measuring backend's reading type (:data:`shc_cli.backends.base.ReadingT`)."""
PARTIAL_SUFFIX = ".partial"
ROBOT_FILE = "robot.toml"
RUNS_FOLDER = Path("runs")
ODOMETRY_COLUMNS = ["odom_x", "odom_y", "odom_yaw"]
"""The controller's leg odometry (:attr:`~shc_cli.control.controller.CycleOutput.odometry`): the body's planar pose
in the odom frame (the start pose) [m, m, rad], in ``log.csv`` and ``body.csv``."""
"""Where runs go without ``--out`` (relative to the working directory)."""


def default_run_directory(kind: str) -> Path:
    """A new run's directory without ``--out``: ``runs/<YYYYmmdd-HHMMSS>-<kind>`` (local time)."""
    from datetime import datetime

    return RUNS_FOLDER / f"{datetime.now():%Y%m%d-%H%M%S}-{kind}"


class RunDirectory:
    """A run directory written while the run goes on: ``<name>.partial`` until :meth:`finish` renames it.

    Tables are CSV files whose rows are formatted with one ``%`` operation each (``log.csv``: a block at a time by
    the compiled formatter, :mod:`shc_cli.record.csv_rows`, the same bytes) and flushed by :meth:`flush`, so an
    interrupted run keeps every flushed row; :meth:`close` writes and flushes every recorded row.

    Args:
        directory: final run directory (must not exist yet, unless ``overwrite``).
        overwrite: replace an existing run directory — only when the new run finishes (the old one stays whole until
            then); a directory that is not a run directory is never replaced.
    """

    def __init__(self, directory: Path, overwrite: bool = False) -> None:
        if directory.exists():
            if not overwrite:
                raise OutputError(f"{directory}: already exists (add --overwrite to replace it, or choose another "
                                  "--out)")
            check_replaceable(directory)
        self.directory = directory
        self.overwrite = overwrite
        self.partial = directory.with_name(directory.name + PARTIAL_SUFFIX)
        try:
            self.partial.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise OutputError(f"{self.partial}: cannot create run directory: {error.strerror} "
                              "(choose another --out)") from None
        self._handles: list[IO[str]] = []
        self._before_close: list[Callable[[], None]] = []
        self.signals = StopSignals()
        """SIGINT/SIGTERM become this run's stop request from now on (:mod:`shc_cli.record.stop_signals`)."""
        self.signals.install()

    def __enter__(self) -> RunDirectory:
        return self

    def __exit__(self, kind: type[BaseException] | None, *exc: object) -> None:
        """Close the tables; an unfinished run keeps its ``.partial`` directory with every written row — unless it
        failed before any table was opened (nothing half-written is left then)."""
        self.close()
        self.signals.restore()
        if kind is not None and not self._handles and self.partial.exists():
            import shutil

            shutil.rmtree(self.partial, ignore_errors=True)

    def table(self, name: str, columns: list[str], formats: list[str]) -> tuple[IO[str], str]:
        """A new table: its file (header written) and its row format (``cycle``, ``t`` come first)."""
        handle = (self.partial / name).open("w", encoding="utf-8")
        self._handles.append(handle)
        handle.write(",".join(["cycle", "t", *columns]) + "\n")
        return handle, ",".join(["%d", "%.4f", *formats]) + "\n"

    def write_robot(self, robot: Robot) -> None:
        """``robot.toml``: the fully expanded robot the run used (``shc validate --show`` format), so the run can
        be analysed without the original files."""
        from shc_cli.spec.toml_out import dump_toml

        text = f"# the robot of this run, expanded\n{dump_toml(robot.model_dump(mode='json'))}"
        (self.partial / ROBOT_FILE).write_text(text, encoding="utf-8")

    def before_close(self, write: Callable[[], None]) -> None:
        """Call ``write`` before the tables close (a recorder that keeps rows writes them)."""
        self._before_close.append(write)

    def flush(self) -> None:
        for handle in self._handles:
            handle.flush()

    def close(self) -> None:
        """Write what recorders keep, flush and close every table: every recorded row is on disk."""
        try:
            for write in self._before_close:
                write()
        finally:
            self._before_close.clear()
            for handle in self._handles:
                handle.close()

    @property
    def finished(self) -> bool:
        return not self.partial.exists() and self.directory.exists()

    def finish(self, summary: RunSummary) -> Path:
        """Write ``summary.json`` (:class:`~shc_cli.record.summary.RunSummary`), close the tables and give the
        directory its final name."""
        from shc_cli.record.summary import write_summary

        self.close()
        write_summary(self.partial, summary)
        replace_directory(self.partial, self.directory, self.overwrite)
        return self.directory


RUN_MARKERS = ("summary.json", ROBOT_FILE, "log.csv", "joints.csv", "results.csv", "results.partial.csv",
               "sweep.toml", "study.toml", "study.db", "trials.csv")
"""Files of which one marks a directory as shc output that ``--overwrite`` may replace."""


def check_replaceable(directory: Path) -> None:
    """Refuse (one line) to overwrite anything but an empty directory or one shc wrote (a run or a sweep)."""
    if not directory.is_dir():
        raise OutputError(f"{directory}: exists and is not a directory (choose another --out)")
    if any(directory.iterdir()) and not any((directory / name).exists() for name in RUN_MARKERS):
        raise OutputError(f"{directory}: not a run directory, so --overwrite leaves it alone (choose another --out)")


def clear_output(out: Path, overwrite: bool, advice: str) -> None:
    """Make room for a sweep's or a study's output folder ``out``: a non-empty one is refused (one line, with
    ``advice``) unless ``overwrite``, and then deleted — only if shc wrote it (:func:`check_replaceable`)."""
    import shutil

    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise OutputError(f"{out}: already exists ({advice})")
        check_replaceable(out)
        shutil.rmtree(out)


def replace_directory(source: Path, target: Path, overwrite: bool) -> None:
    """Rename ``source`` to ``target``; with ``overwrite`` an existing ``target`` is first moved aside and deleted
    only once ``source`` is in its place."""
    import shutil

    if not (overwrite and target.exists()):
        os.replace(source, target)
        return
    check_replaceable(target)
    aside = target.with_name(f"{target.name}.replaced-{os.getpid()}")
    os.replace(target, aside)
    os.replace(source, target)
    shutil.rmtree(aside, ignore_errors=True)


def joint_columns(robot: Robot, suffix: str = "") -> list[str]:
    """``<LEG>_<joint><suffix>`` for every joint, legs in id order."""
    return [f"{leg}_{joint}{suffix}" for leg, spec in robot.legs.items() for joint in spec.joints]


def log_columns(robot: Robot) -> list[str]:
    """The columns of ``log.csv`` after ``cycle`` and ``t``."""
    legs = list(robot.legs)
    return (joint_columns(robot, "_cmd") + joint_columns(robot) + joint_columns(robot, "_torque")
            + joint_columns(robot, "_power") + [f"{leg}_force" for leg in legs] + [f"{leg}_contact" for leg in legs]
            + MEASURED_BODY_COLUMNS + ["cmd_vx", "cmd_vy", "cmd_wz", "vel_x", "vel_y", "vel_wz", *ODOMETRY_COLUMNS,
                                       "robot_state", "walk_state"])


class LogRecorder(Generic[ReadingT]):
    """Streams cycles of a measuring backend into ``log.csv`` (:func:`log_columns`).

    Args:
        run: the run directory.
        robot: the robot (column names, joint order).
        backend: gives each reading's measured values.
    """

    def __init__(self, run: RunDirectory, robot: Robot, backend: MeasuringBackend[ReadingT]) -> None:
        from shc_cli.record.csv_rows import RowBlock

        self.run = run
        columns = log_columns(robot)
        self.handle, self.row = run.table("log.csv", columns, ["%.6g"] * (len(columns) - 2) + ["%s", "%s"])
        self.block = RowBlock(len(columns) - 2, 2, self.row)
        """Rows not yet written: formatted a block at a time by the compiled formatter (the same bytes as
        ``self.row % …``), at every :meth:`flush` and when the run directory closes."""
        run.before_close(self.write_rows)
        self.slots = JointSlots.of(robot)
        self.dt = robot.time_delta
        self.measured = backend.measured
        self.zero_joints = np.zeros(len(self.slots.rows))
        self.zero_legs = np.zeros(len(robot.legs))
        self.zero_body = np.zeros(len(MEASURED_BODY_COLUMNS) - 1)
        self._states: tuple[object, object] = (None, None)
        self._codes = (0, 0)

    def measured_values(self, measured: Measured) -> list[np.ndarray | tuple[float, ...]]:
        """The measured columns of ``log.csv`` (measured joints to ``power_w``); what is not measured is 0."""
        power, forces, contact = measured.power, measured.foot_forces, measured.foot_contact
        parts = [measured.joints, measured.torques, self.zero_joints if power is None else power,
                 self.zero_legs if forces is None else forces, self.zero_legs if contact is None else contact]
        if measured.body is None:
            return [*parts, self.zero_body, (measured.total_power(),)]
        return [*parts, *measured.body_values()]

    def record(self, cycle: int, command: Command, out: CycleOutput, applied: np.ndarray,
               reading: ReadingT) -> None:
        """One row of ``log.csv``: the cycle's values gathered into the block's next row by one concatenation
        (the input, desired velocity and odometry as one list of floats)."""
        block = self.block
        states = out.robot_state, out.walk_state
        if states[0] is not self._states[0] or states[1] is not self._states[1]:  # they change a few times a run
            self._states = states
            self._codes = (block.code(0, states[0]), block.code(1, states[1]))
        row = block.add(self.handle, cycle, cycle * self.dt, self._codes)
        np.concatenate((self.slots.servo_order(applied), *self.measured_values(self.measured(reading)),
                        [*command.velocity, *out.velocity, *out.odometry]), out=row)

    def write_rows(self) -> None:
        """Write the rows recorded so far into the table (not flushed)."""
        self.block.drain(self.handle)

    def flush(self) -> None:
        """Every recorded row on disk."""
        self.write_rows()
        self.run.flush()


def joint_values(robot: Robot, values: np.ndarray) -> list[float]:
    """The real joints' values of a padded ``(L, n)`` array, in :func:`joint_columns` order."""
    counts = {len(leg.joints) for leg in robot.legs.values()}
    if len(counts) == 1 and counts.pop() == values.shape[1]:  # no padding: every value, row by row
        return list(values.ravel().tolist())
    rows, cols = joint_slots(robot)
    return list(values[rows, cols].tolist())


class RunWriter(RunDirectory):
    """Streams controller outputs into a ``plan`` run directory (joints, tips, body tables).

    Args:
        directory: final run directory (must not exist yet, unless ``overwrite``).
        robot: the robot (for column names).
        overwrite: replace an existing run directory when this run finishes.
    """

    def __init__(self, directory: Path, robot: Robot, overwrite: bool = False) -> None:
        super().__init__(directory, overwrite)
        self.robot = robot
        legs = list(robot.legs)
        joints = joint_columns(robot)
        tips = [f"{leg}_{stage}_{axis}" for leg in legs for stage in ("walker", "poser", "model") for axis in "xyz"]
        tips = [c for leg in legs for c in (*[t for t in tips if t.startswith(f"{leg}_")],
                                            f"{leg}_stance_progress", f"{leg}_swing_progress")]
        body = ["cmd_vx", "cmd_vy", "cmd_wz", "vel_x", "vel_y", "vel_wz", "pose_x", "pose_y", "pose_z",
                "pose_roll", "pose_pitch", "pose_yaw", *ODOMETRY_COLUMNS, "robot_state", "walk_state"]
        self._joints = self.table("joints.csv", joints, ["%.9g"] * len(joints))
        self._tips = self.table("tips.csv", tips, ["%.9g"] * len(tips))
        self._body = self.table("body.csv", body, ["%.9g"] * 12 + ["%.12g"] * 3 + ["%s", "%s"])

    def record(self, cycle: int, command: Command, out: CycleOutput, applied: np.ndarray,
               reading: object) -> None:
        """The loop's recorder interface: one cycle of the controller's tables."""
        self.write(cycle, cycle * self.robot.time_delta, command.velocity, out)

    def write(self, cycle: int, time: float, command: tuple[float, float, float], out: CycleOutput) -> None:
        """Append one control cycle to every table."""
        handle, row = self._joints
        handle.write(row % (cycle, time, *joint_values(self.robot, out.joints)))
        stages = np.concatenate([out.walker_tips, out.poser_tips, out.model_tips, out.stance_progress[:, None],
                                 out.swing_progress[:, None]], axis=1)
        handle, row = self._tips
        handle.write(row % (cycle, time, *stages.ravel().tolist()))
        handle, row = self._body
        handle.write(row % (cycle, time, *command, *out.velocity, *out.pose, *out.odometry, out.robot_state.name,
                            out.walk_state.name))
