"""The one run-log reader: a ``plan``, ``simulate`` or ``run-hw`` run directory as arrays, whatever wrote it.

:func:`shc_cli.domain.stored_run.open_run` opens any run — a directory here, or a bag through
:mod:`shc_cli.interop.bagrun` — so this module does not know about bags (no import circle).

:func:`read_run` gives a :class:`RunLog` with the same fields for every kind of run; what a kind cannot know
is ``None`` (a plan has no measured power, forces or IMU). ``simulate`` logs what the sensors saw; a ``plan``
run gives the ideal body path (its desired velocity integrated) and the commanded joints.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.errors import OutputError, SpecError
from shc_cli.record.runlog import ODOMETRY_COLUMNS, PARTIAL_SUFFIX, ROBOT_FILE
from shc_cli.record.summary import RunSummary
from shc_cli.spec.robot import Robot


@dataclass
class RunLog:
    """One run, one row per control cycle (legs in id order).

    Attributes:
        path: the run directory.
        kind: ``"simulate"`` or ``"plan"``.
        summary: the run's ``summary.json``.
        robot: the robot the run used (its ``robot.toml``).
        t: time [s], ``(N,)``.
        running: robot state RUNNING, ``(N,)``.
        walk_state: walk state name per cycle, ``(N,)``.
        command: velocity input (x, y, yaw) in the robot's input mode, ``(N, 3)``.
        desired: body velocity the controller commanded after its limits [m/s, m/s, rad/s], ``(N, 3)``.
        position: body (base_link) position in the world [m], ``(N, 3)``.
        rpy: body roll, pitch, yaw [rad], ``(N, 3)``.
        joints: joint positions ``(N, L, n)`` [rad] — measured (simulate) or commanded (plan).
        contact: foot on the ground, ``(N, L)`` — contact sensor (simulate) or stance phase (plan).
        power: total electrical power [W], ``(N,)``, or ``None``.
        foot_force: contact normal force per foot [N], ``(N, L)``, or ``None``.
        body_rate: body-frame angular rate (roll, pitch, yaw rate) [rad/s], ``(N, 3)``, or ``None``.
        height: body height above the terrain [m], ``(N,)``, or ``None``.
        commanded: commanded joint positions ``(N, L, n)`` [rad].
        efforts: measured joint torques ``(N, L, n)`` [N·m], or ``None``.
        twist: body velocity in the world (vx, vy, vz [m/s], wx, wy, wz [rad/s]) ``(N, 6)``, or ``None``.
        imu: IMU quaternion (x, y, z, w), body rate [rad/s], specific force [m/s²] ``(N, 10)``, or ``None``.
        progress: stance and swing progress per leg ``(N, L, 2)`` (−1 outside the phase), or ``None``.
        tips: walker, poser and model tips per leg ``(N, L, 3, 3)`` [m] (plan), or ``None``.
        states: robot and walk state names ``(N, 2)``.
        odometry: the controller's leg odometry (x, y [m], yaw [rad]) in the odom frame (the start pose) ``(N, 3)``,
            or ``None`` (runs logged before it existed).
    """

    path: Path
    kind: str
    summary: RunSummary
    robot: Robot
    t: np.ndarray
    running: np.ndarray
    walk_state: np.ndarray
    command: np.ndarray
    desired: np.ndarray
    position: np.ndarray
    rpy: np.ndarray
    joints: np.ndarray
    contact: np.ndarray
    power: np.ndarray | None = None
    foot_force: np.ndarray | None = None
    body_rate: np.ndarray | None = None
    height: np.ndarray | None = None
    commanded: np.ndarray | None = None
    efforts: np.ndarray | None = None
    twist: np.ndarray | None = None
    imu: np.ndarray | None = None
    progress: np.ndarray | None = None
    tips: np.ndarray | None = None
    states: np.ndarray | None = None
    odometry: np.ndarray | None = None
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def dt(self) -> float:
        return float(self.robot.time_delta)

    @property
    def legs(self) -> list[str]:
        return list(self.robot.legs)

    @property
    def complete(self) -> bool:
        """The run played its input to the end (runs written before ``complete`` existed count as complete)."""
        return self.summary.complete

    def partial_note(self) -> str | None:
        """``"<path>: a partial run (stopped by SIGINT after 4.2 s)"`` for an interrupted run, else None."""
        if self.complete:
            return None
        seconds = float(self.t[-1]) if len(self.t) else 0.0
        return f"{self.path}: a partial run (stopped by {self.summary.stop_reason} after {seconds:.2f} s)"


def read_run(path: Path) -> RunLog:
    """Read a run directory written by ``shc plan``, ``shc simulate`` or ``shc run-hw``; raises :class:`SpecError`
    (exit 2) with one line when it is not one. Bags too: :func:`shc_cli.domain.stored_run.open_run`."""
    path = Path(path)
    if is_bag(path):
        raise bad_run(path, "a bag, not a run directory", "open it with shc_cli.domain.stored_run.open_run")
    if not path.is_dir():
        raise bad_run(path, "not a run directory", "give a directory written by shc plan or shc simulate")
    if path.name.endswith(PARTIAL_SUFFIX) and not (path / "summary.json").exists():
        raise bad_run(path, "an unfinished run (no summary.json)", "analyse a finished run")
    try:
        data = json.loads((path / "summary.json").read_text(encoding="utf-8"))
    except FileNotFoundError:
        if (path / "results.csv").is_file() and (path / "runs").is_dir():
            raise bad_run(path, "a sweep's output, not a run directory",
                          f"analyse its runs: {path / 'runs' / '*'} (its table is {path / 'results.csv'})") from None
        if (path / "trials.csv").is_file() or (path / "study.db").is_file():
            raise bad_run(path, "a study's output, not a run directory",
                          f"analyse a trial's runs under {path}, or read its trials.csv") from None
        raise bad_run(path, "no summary.json", "give a directory written by shc plan or shc simulate") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise bad_run(path / "summary.json", f"unreadable: {first_line(error)}", "re-run to regenerate it") from None
    summary = checked_summary(path / "summary.json", data)
    robot = _robot(path, summary)
    try:
        if (path / "log.csv").exists():
            return _simulate_run(path, summary, robot)
        if (path / "joints.csv").exists() and (path / "body.csv").exists():
            return _plan_run(path, summary, robot)
    except (KeyError, ValueError, IndexError, TypeError) as error:  # tables that do not fit together or the robot
        raise bad_run(path, f"malformed run tables: {first_line(error)}", "re-run to regenerate it") from None
    raise bad_run(path, "neither log.csv (simulate) nor joints.csv and body.csv (plan)", "re-run to regenerate it")


def first_line(error: BaseException) -> str:
    text = str(error).strip().splitlines()
    return f"{type(error).__name__}: {text[0].strip() if text else ''}".rstrip(": ")


def read_tables(path: Path, robot: Robot, summary: RunSummary | None = None) -> RunLog:
    """The tables of a run directory as a :class:`RunLog`, also while it is still ``.partial`` (a finished loop's
    rows, before its summary is written: the summary is made from them), with the given robot and ``summary``
    (default: an empty one)."""
    summary = summary or RunSummary()
    if (path / "log.csv").exists():
        return _simulate_run(path, summary, robot)
    return _plan_run(path, summary, robot)


def checked_summary(file: Path, data: object) -> RunSummary:
    """The :class:`RunSummary` of a ``summary.json``'s JSON data; one line naming the first bad field if it is not
    one (keys this version does not know are left out)."""
    from pydantic import ValidationError

    from shc_cli.record.summary import parse_summary

    try:
        return parse_summary(data)
    except TypeError as error:
        raise bad_run(file, str(error), "re-run to regenerate it") from None
    except ValidationError as error:
        first = error.errors()[0]
        where = ".".join(str(part) for part in first["loc"])
        raise bad_run(file, f"{where}: {first.get('input')!r} {first['msg'].lower()}",
                      "re-run to regenerate it") from None


def is_bag(path: Path) -> bool:
    """A ROS 2 bag directory or a ROS 1 ``.bag`` file (what ``shc export bag`` writes)."""
    return (path / "metadata.yaml").exists() or (path.is_file() and path.suffix == ".bag")


def bad_run(path: Path, problem: str, fix: str) -> SpecError:
    from shc_cli.errors import Issue

    return SpecError([Issue(path, None, "", problem, fix)])


def _robot(path: Path, summary: RunSummary) -> Robot:
    """The run's own expanded robot, or the bundled robot it names (runs written before robot.toml existed)."""
    from shc_cli.spec.loading import load_robot

    source: str | Path = path / ROBOT_FILE if (path / ROBOT_FILE).exists() else str(summary.robot or "")
    loaded = load_robot(source)
    if loaded.robot is None:
        raise bad_run(path, f"robot '{source}' cannot be loaded", "keep robot.toml in the run directory")
    return loaded.robot


def _table(file: Path) -> dict[str, np.ndarray]:
    """A CSV table as columns: numbers as float arrays, other columns as string arrays (numpy's C parser).

    Reads the run directories shc writes itself (mixed text/number columns; a bad file means "re-run").
    :func:`shc_cli.replay.recording.read_table` is the other reader, kept apart on purpose: it takes other
    programs' gzipped, numbers-only recordings row by row to name the exact line and column of a bad value, and
    is ≈ 1.7× slower (0.33 s against 0.19 s for an 8,000 × 120 numeric CSV here) and numbers-only.

    One pass of the parser over the file: the text columns (those not numbers in the first row; a run's robot and
    walk states) are read as codes of their distinct values, then turned back into strings (0.05 s instead of
    0.09 s for a 60 s walk's 6,500 × 169 log, whose summary is made from it)."""
    try:
        with file.open(encoding="utf-8") as stream:
            header = stream.readline().rstrip("\r\n").split(",")
            first = stream.readline().rstrip("\r\n")
        if not first:
            raise bad_run(file, "no rows", "re-run to regenerate it")
        text = [index for index, cell in enumerate(first.split(",")) if not _is_number(cell)]
        values: dict[str, int] = {}

        def code(cell: str) -> int:
            return values.setdefault(cell, len(values))

        table = np.loadtxt(file, delimiter=",", skiprows=1, ndmin=2, encoding="utf-8",
                           converters=dict.fromkeys(text, code))
    except OSError as error:
        raise OutputError(f"{file}: cannot read the table ({error})") from None
    except UnicodeDecodeError as error:
        raise bad_run(file, f"not UTF-8 text at byte {error.start}", "re-run to regenerate it") from None
    except ValueError as error:
        raise bad_run(file, f"malformed row ({error})", "re-run to regenerate it") from None
    if table.shape[1] != len(header):
        raise bad_run(file, f"{table.shape[1]} columns where the header has {len(header)}", "re-run to regenerate it")
    out = {name: table[:, index] for index, name in enumerate(header) if index not in text}
    names = np.array(list(values), dtype=str)
    for index in text:
        out[header[index]] = names[table[:, index].astype(np.intp)]
    return out


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _joint_array(columns: dict[str, np.ndarray], robot: Robot, rows: int, suffix: str = "") -> np.ndarray:
    width = max(len(leg.joints) for leg in robot.legs.values())
    out = np.zeros((rows, len(robot.legs), width))
    for i, (leg_id, leg) in enumerate(robot.legs.items()):
        for k, joint in enumerate(leg.joints):
            out[:, i, k] = columns[f"{leg_id}_{joint}{suffix}"]
    return out


def _stack(columns: dict[str, np.ndarray], names: list[str]) -> np.ndarray:
    return np.stack([columns[name] for name in names], axis=1)


def _simulate_run(path: Path, summary: RunSummary, robot: Robot) -> RunLog:
    c = _table(path / "log.csv")
    rows = len(c["t"])
    legs = list(robot.legs)
    zeros = np.zeros((rows, 3))
    has_velocity = "vel_x" in c  # runs logged before the velocity columns existed
    return RunLog(
        path=path, kind="simulate", summary=summary, robot=robot, t=c["t"],
        running=c["robot_state"] == "RUNNING", walk_state=c["walk_state"],
        command=_stack(c, ["cmd_vx", "cmd_vy", "cmd_wz"]) if has_velocity else zeros,
        desired=_stack(c, ["vel_x", "vel_y", "vel_wz"]) if has_velocity else zeros,
        position=_stack(c, ["x", "y", "z"]), rpy=_stack(c, ["roll", "pitch", "yaw"]),
        joints=_joint_array(c, robot, rows),
        contact=_stack(c, [f"{leg}_contact" for leg in legs]) > 0.5,
        power=c["power_w"], foot_force=_stack(c, [f"{leg}_force" for leg in legs]),
        body_rate=_stack(c, ["gyro_x", "gyro_y", "gyro_z"]), height=c["height"],
        commanded=_joint_array(c, robot, rows, "_cmd"), efforts=_joint_array(c, robot, rows, "_torque"),
        twist=_stack(c, ["vx", "vy", "vz", "wx", "wy", "wz"]),
        imu=_stack(c, ["imu_qx", "imu_qy", "imu_qz", "imu_qw", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y",
                       "acc_z"]),
        states=np.column_stack([c["robot_state"], c["walk_state"]]),
        odometry=_stack(c, ODOMETRY_COLUMNS) if "odom_x" in c else None,
    )


def _plan_run(path: Path, summary: RunSummary, robot: Robot) -> RunLog:
    joints = _table(path / "joints.csv")
    body = _table(path / "body.csv")
    tips = _table(path / "tips.csv") if (path / "tips.csv").exists() else None
    rows = len(joints["t"])
    for name, table in (("body.csv", body), ("tips.csv", tips)):
        if table is not None and len(table["t"]) != rows:
            raise bad_run(path / name, f"{len(table['t'])} rows where joints.csv has {rows}", "re-run to regenerate it")
    dt = float(robot.time_delta)
    desired = _stack(body, ["vel_x", "vel_y", "vel_wz"])
    xy, yaw = ideal_path(desired, dt)
    z = body["pose_z"]  # the body pose in the walk plane: its z is the height above the ground plane
    position = np.column_stack([xy, z])
    rpy = np.column_stack([body["pose_roll"], body["pose_pitch"], yaw + body["pose_yaw"]])
    legs = list(robot.legs)
    contact = (_stack(tips, [f"{leg}_stance_progress" for leg in legs]) >= 0.0 if tips is not None
               else np.ones((rows, len(legs)), dtype=bool))
    planned = _joint_array(joints, robot, rows)
    progress = tip_stages = None
    if tips is not None:
        progress = np.stack([_stack(tips, [f"{leg}_stance_progress", f"{leg}_swing_progress"]) for leg in legs],
                            axis=1)
        tip_stages = np.stack([np.stack([_stack(tips, [f"{leg}_{stage}_{axis}" for axis in "xyz"])
                                         for stage in ("walker", "poser", "model")], axis=1) for leg in legs], axis=1)
    return RunLog(
        path=path, kind="plan", summary=summary, robot=robot, t=joints["t"],
        running=body["robot_state"] == "RUNNING", walk_state=body["walk_state"],
        command=_stack(body, ["cmd_vx", "cmd_vy", "cmd_wz"]), desired=desired, position=position, rpy=rpy,
        joints=planned, contact=contact, height=z, commanded=planned, progress=progress, tips=tip_stages,
        states=np.column_stack([body["robot_state"], body["walk_state"]]),
        odometry=_stack(body, ODOMETRY_COLUMNS) if "odom_x" in body else None,
    )


def ideal_path(desired: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The ideal body path of a plan: the commanded body-frame velocity ``desired`` ``(N, 3)`` [m/s, m/s, rad/s]
    integrated in the world (what a robot without slip would do), yaw first so each cycle moves along the heading
    it had. Returns ``xy`` ``(N, 2)`` [m] and ``yaw`` ``(N,)`` [rad] per logged row, the first row at the origin."""
    yaw = np.concatenate([[0.0], np.cumsum(desired[:-1, 2] * dt)])
    step = np.stack([desired[:, 0] * np.cos(yaw) - desired[:, 1] * np.sin(yaw),
                     desired[:, 0] * np.sin(yaw) + desired[:, 1] * np.cos(yaw)], axis=1) * dt
    xy = np.concatenate([np.zeros((1, 2)), np.cumsum(step[:-1], axis=0)])
    return xy, yaw
