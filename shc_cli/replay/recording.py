"""The recorder's CSVs of a real OpenSHC run (``shared/reference/openshc-runs/README.md``) as a :class:`Recorded`.

A recording ``DIR/NAME`` is three gzipped CSVs with one row per control cycle, joined by row:

* ``NAME_joints.csv.gz``: ``cycle,t`` and the desired joint positions [rad] named as in ``/desired_joint_states``;
* ``NAME_tips.csv.gz``: per leg ``LEG_{walker,poser,model}_{x,y,z}`` [m] and ``LEG_{stance,swing}_progress``
  (from ``/shc/LEG/state``);
* ``NAME_body.csv.gz``: ``cmd_vx,cmd_vy,cmd_wz`` (the last ``/syropod_remote/desired_velocity`` the recorder saw
  before the cycle's output), ``vel_x,vel_y,vel_wz`` (``/shc/velocity``) and ``pose_{x,y,z,roll,pitch,yaw}``
  (``/shc/pose``).

Only the joints file and the body file's ``cmd_*`` columns are required; whatever else is there is compared.
"""

from __future__ import annotations

import csv
import gzip
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shc_cli.errors import Issue, NotFoundError, SpecError
from shc_cli.replay.source import TIP_STAGES, Recorded

JOINT_SUFFIX = "_joint"
COMMAND_COLUMNS = ["cmd_vx", "cmd_vy", "cmd_wz"]
VELOCITY_COLUMNS = ["vel_x", "vel_y", "vel_wz"]
POSE_COLUMNS = ["pose_x", "pose_y", "pose_z", "pose_roll", "pose_pitch", "pose_yaw"]


@dataclass(frozen=True)
class Table:
    """A recorded CSV: column names and a float matrix (one row per cycle)."""

    path: Path
    columns: list[str]
    rows: np.ndarray

    def has(self, names: list[str]) -> bool:
        return all(name in self.columns for name in names)

    def columns_of(self, names: list[str]) -> np.ndarray:
        return np.asarray(self.rows[:, [self.columns.index(n) for n in names]])


def read_table(path: Path) -> Table:
    """Read a (possibly gzipped) CSV of numbers; a one-line error names the line and column of a bad value.

    For recordings made by other programs (user input, so every bad cell is reported as ``file:line column``),
    hence the row-by-row Python parse. shc's own run tables, with text columns and no gzip, go through the faster
    C-parser reader :func:`shc_cli.record.runread._table` instead."""
    opener = gzip.open if path.suffix == ".gz" else open
    try:
        with opener(path, "rt", encoding="utf-8") as handle:
            reader = csv.reader(handle)
            columns = next(reader, None)
            if columns is None:
                raise SpecError([Issue(path, 1, "", "empty file", "a recording CSV starts with a header row")])
            values: list[list[float]] = []
            for line, row in enumerate(reader, start=2):
                if len(row) != len(columns):
                    raise SpecError([Issue(path, line, "", f"{len(row)} values for {len(columns)} columns",
                                           "each row has one value per header column")])
                try:
                    values.append([float(v) for v in row])
                except ValueError:
                    bad = next(i for i, v in enumerate(row) if not _is_number(v))
                    raise SpecError([Issue(path, line, columns[bad], f"'{row[bad]}' is not a number",
                                           "a recording holds numbers only")]) from None
    except (OSError, EOFError, UnicodeDecodeError, zlib.error, csv.Error) as error:
        if isinstance(error, FileNotFoundError):
            raise NotFoundError(f"{path}: no such file (a recording DIR/NAME needs NAME_joints.csv.gz and "
                                "NAME_body.csv.gz)") from None
        raise SpecError([Issue(path, None, "", f"unreadable: {error}", "give the recorder's CSV files")]) from None
    rows = np.array(values, dtype=float).reshape(len(values), len(columns))
    return Table(path, columns, rows)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def read_recording(prefix: Path) -> Recorded:
    """Read ``PREFIX_{joints,tips,body}.csv.gz`` (the tips file is optional) into per-cycle arrays."""
    joints = read_table(Path(f"{prefix}_joints.csv.gz"))
    body = read_table(Path(f"{prefix}_body.csv.gz"))
    tips_path = Path(f"{prefix}_tips.csv.gz")
    tips = read_table(tips_path) if tips_path.is_file() else None
    joint_names = [c for c in joints.columns if c.endswith(JOINT_SUFFIX)]
    if not joint_names or "t" not in joints.columns:
        raise SpecError([Issue(joints.path, 1, "", "no 't' column or no joint columns (names ending in '_joint')",
                               "the header is cycle,t,LEG_JOINT_joint,...")])
    if not body.has(COMMAND_COLUMNS):
        raise SpecError([Issue(body.path, 1, "", "no cmd_vx,cmd_vy,cmd_wz columns (the velocity inputs)",
                               "the replay drives the controller with them")])
    n = len(joints.rows)
    for table in (body, tips):
        if table is not None and len(table.rows) != n:
            raise SpecError([Issue(table.path, None, "", f"{len(table.rows)} rows, but {n} in {joints.path.name}",
                                   "the three files hold the same cycles")])
    topics = ["/desired_joint_states", "/syropod_remote/desired_velocity"]
    recorded = Recorded(source=prefix, kind="recording", t=joints.columns_of(["t"])[:, 0],
                        joint_names=joint_names, joints=joints.columns_of(joint_names),
                        command=body.columns_of(COMMAND_COLUMNS))
    if body.has(VELOCITY_COLUMNS):
        recorded.velocity = body.columns_of(VELOCITY_COLUMNS)
        topics.append("/shc/velocity")
    if body.has(POSE_COLUMNS):
        recorded.pose = body.columns_of(POSE_COLUMNS)
        topics.append("/shc/pose")
    if tips is not None:
        legs = [c[: -len("_walker_x")] for c in tips.columns if c.endswith("_walker_x")]
        stage_names = {stage: [f"{leg}_{stage}_{axis}" for leg in legs for axis in "xyz"] for stage in TIP_STAGES}
        progress_names = [f"{leg}_{kind}_progress" for leg in legs for kind in ("stance", "swing")]
        if legs and all(tips.has(names) for names in stage_names.values()) and tips.has(progress_names):
            recorded.legs = legs
            recorded.tips = {stage: tips.columns_of(names).reshape(n, len(legs), 3)
                             for stage, names in stage_names.items()}
            recorded.progress = tips.columns_of(progress_names).reshape(n, len(legs), 2)
            topics.append("/shc/LEG/state")
    recorded.topics = topics
    return recorded
