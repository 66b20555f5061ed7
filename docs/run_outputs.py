"""Writes docs/run-outputs.md, the reference of a run directory's files, from the code that writes them.

    .venv/bin/python docs/run_outputs.py > docs/run-outputs.md

``summary.json``'s keys, types and meanings come from its model, :class:`shc_cli.record.summary.RunSummary` (the JSON
Schema ``shc schema summary`` prints). The column names come from the writers themselves
(:class:`shc_cli.record.runlog.RunWriter` for ``plan``,
:func:`shc_cli.record.runlog.log_columns` for ``simulate`` and ``run-hw``), run on a bundled robot and folded into
patterns (``<LEG>_<joint>_cmd``). :data:`MEANING` says what each pattern holds; a column without a meaning, or a
meaning no column uses, stops the script, so a new column cannot reach the page undocumented.
``tests/test_docs_reference.py`` checks the committed page equals this script's output.
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path
from typing import Any

MEANING: dict[str, str] = {
    "cycle": "control cycle since the run started (start-up included)",
    "t": "time since the run started: cycle × control period [s]",
    # plan: joints.csv
    "<LEG>_<joint>": "joint position [rad]: plan, the controller's target; log.csv, the measured position",
    # plan: tips.csv (OpenSHC's LegState stages)
    "<LEG>_walker_x": "walker tip: the foot target the gait generates, in the walk-plane frame [m]",
    "<LEG>_walker_y": "",
    "<LEG>_walker_z": "",
    "<LEG>_poser_x": "poser tip: the walker tip after body posing, in base_link — the IK's target [m]",
    "<LEG>_poser_y": "",
    "<LEG>_poser_z": "",
    "<LEG>_model_x": "model tip: where the IK's joints put the foot, in base_link [m]",
    "<LEG>_model_y": "",
    "<LEG>_model_z": "",
    "<LEG>_stance_progress": "share of the stance phase done, 0–1; −1 when not in stance",
    "<LEG>_swing_progress": "share of the swing phase done, 0–1; −1 when not in swing",
    # plan: body.csv; log.csv
    "cmd_vx": "velocity input: forward, sideways [throttle −1…1, or m/s with velocity_input_mode = real]",
    "cmd_vy": "",
    "cmd_wz": "velocity input: turning [throttle −1…1, or rad/s]",
    "vel_x": "desired body velocity after the walkspace and acceleration limits: forward, sideways [m/s]",
    "vel_y": "",
    "vel_wz": "desired turning rate after the limits [rad/s]",
    "pose_x": "the controller's body pose in the walk plane: position [m]",
    "pose_y": "",
    "pose_z": "",
    "pose_roll": "the controller's body pose: orientation [rad]",
    "pose_pitch": "",
    "pose_yaw": "",
    "odom_x": "leg odometry: the body's estimated position in the odom frame (its start pose: origin at the start "
              "position, x along the start heading) [m] — from the stance feet and the IMU, see docs/odometry.md",
    "odom_y": "",
    "odom_yaw": "leg odometry: the body's estimated heading in the odom frame [rad]",
    "robot_state": "the controller's robot state (UNKNOWN, PACKED, READY, RUNNING)",
    "walk_state": "the walker's state (STOPPED, STARTING, MOVING, STOPPING)",
    # log.csv
    "<LEG>_<joint>_cmd": "commanded joint position sent to the servo [rad]",
    "<LEG>_<joint>_torque": "joint torque [N·m] (run-hw: the servo's present current [A])",
    "<LEG>_<joint>_power": "electrical power of the joint's servo [W] (0 on hardware: not measured)",
    "<LEG>_force": "normal force on the foot from the ground [N] (0 on hardware)",
    "<LEG>_contact": "1 when the foot touches the ground, else 0 (0 on hardware)",
    "x": "body position, ground truth, world frame [m] (0 on hardware)",
    "y": "",
    "z": "",
    "roll": "body orientation, ground truth [rad] (0 on hardware)",
    "pitch": "",
    "yaw": "",
    "vx": "body linear velocity, world frame [m/s] (0 on hardware)",
    "vy": "",
    "vz": "",
    "wx": "body angular velocity, world frame [rad/s] (0 on hardware)",
    "wy": "",
    "wz": "",
    "imu_qx": "IMU orientation quaternion, body → world (x, y, z, w)",
    "imu_qy": "",
    "imu_qz": "",
    "imu_qw": "",
    "gyro_x": "IMU angular rate, body frame [rad/s]",
    "gyro_y": "",
    "gyro_z": "",
    "acc_x": "IMU specific force, body frame [m/s²]",
    "acc_y": "",
    "acc_z": "",
    "height": "body height above the terrain below it [m]",
    "power_w": "total electrical power of all servos [W]",
}
"""What each column pattern holds, with its unit; an empty meaning continues the row above (x, y, z)."""

ROBOT = "bullet"
"""The bundled robot whose columns are folded into the patterns."""


def patterns(columns: list[str], legs: list[str], joints: list[str]) -> list[str]:
    """Column names with the leg ids and joint names replaced by ``<LEG>`` and ``<joint>``, each once, in order."""
    folded: list[str] = []
    for column in columns:
        name = column
        for leg in legs:
            if name.startswith(f"{leg}_"):
                name = "<LEG>_" + name[len(leg) + 1:]
                for joint in joints:
                    if name == f"<LEG>_{joint}" or name.startswith(f"<LEG>_{joint}_"):
                        name = "<LEG>_<joint>" + name[len(f"<LEG>_{joint}"):]
                        break
                break
        if name not in folded:
            folded.append(name)
    return folded


def tables() -> dict[str, list[str]]:
    """Every table a run writes, by file name: its column patterns."""
    from shc_cli.record.runlog import RunWriter, log_columns
    from shc_cli.spec.loading import load_robot

    robot = load_robot(ROBOT).robot
    assert robot is not None
    legs = list(robot.legs)
    joints = sorted({joint for leg in robot.legs.values() for joint in leg.joints}, key=len, reverse=True)
    found: dict[str, list[str]] = {}
    with tempfile.TemporaryDirectory() as folder:
        writer = RunWriter(Path(folder) / "run", robot)
        writer.close()
        for name in ("joints.csv", "tips.csv", "body.csv"):
            header = (writer.partial / name).read_text(encoding="utf-8").splitlines()[0].split(",")
            found[name] = patterns(header, legs, joints)
    found["log.csv"] = patterns(["cycle", "t", *log_columns(robot)], legs, joints)
    return found


def table_rows(columns: list[str]) -> list[str]:
    """Markdown rows: a pattern whose meaning is empty joins the row above it."""
    rows: list[tuple[list[str], str]] = []
    for column in columns:
        if column not in MEANING:
            raise SystemExit(f"docs/run_outputs.py: column '{column}' has no meaning in MEANING (add it)")
        if MEANING[column] or not rows:
            rows.append(([column], MEANING[column]))
        else:
            rows[-1][0].append(column)
    return [f"| {', '.join(f'`{c}`' for c in names)} | {meaning} |" for names, meaning in rows]


def value_type(field: dict[str, Any]) -> str:
    """A JSON Schema property's type in words: ``integer ≥ 0``, ``list of string``, ``number, or null``."""
    options = field.get("anyOf", [field])
    words = []
    for option in options:
        kind = option.get("type", "value")
        if kind == "null":
            continue
        if kind == "array":
            kind = f"list of {option.get('items', {}).get('type', 'values')}"
        elif kind == "object":
            kind = f"object of {option.get('additionalProperties', {}).get('type', 'values')}"
        if "minimum" in option:
            kind += f" ≥ {option['minimum']:g}"
        words.append(kind)
    nullable = any(option.get("type") == "null" for option in options)
    return " or ".join(words) + (", or null" if nullable else "")


def summary_rows() -> list[str]:
    """One Markdown row per ``summary.json`` key: name, type, meaning (from RunSummary's JSON Schema)."""
    from shc_cli.record.summary import summary_schema

    properties: dict[str, dict[str, Any]] = summary_schema()["properties"]
    rows = []
    for name, field in properties.items():
        meaning = str(field.get("description", "")).replace("|", "\\|")
        rows.append(f"| `{name}` | {value_type(field)} | {meaning} |")
    return rows


def page() -> str:
    found = tables()
    used = {c for columns in found.values() for c in columns}
    unused = sorted(set(MEANING) - used)
    if unused:
        raise SystemExit(f"docs/run_outputs.py: MEANING names columns no table has: {', '.join(unused)}")
    intro = {
        "joints.csv": "`shc plan`: the controller's joint targets, one row per control cycle.",
        "tips.csv": "`shc plan`: each leg's foot tip at OpenSHC's three LegState stages and its phase progress "
                    "(the format of the OpenSHC recordings in `golden/openshc-runs/`).",
        "body.csv": "`shc plan`: the velocity input, the limited velocity, the body pose and the states.",
        "log.csv": "`shc simulate` and `shc run-hw`: commanded and measured joints, torques, power, foot forces "
                   "and contacts, the body's ground truth, the IMU, the input and the states. The columns are the "
                   "same on every engine and on hardware; what a backend does not measure is 0 and listed in "
                   "`summary.json`'s `unmeasured`.",
    }
    lines = ["# Run outputs: `summary.json` and the tables of a run directory", "",
             "<!-- Generated by docs/run_outputs.py from the code that writes the run; do not edit by hand "
             "(tests/test_docs_reference.py checks it). -->", "",
             "A run directory (`runs/NAME/`, written by `shc plan`, `shc simulate` and `shc run-hw`) holds "
             "`summary.json`, CSV tables with one row per control cycle, `robot.toml` (the robot as run, fully "
             "expanded), `events.log` and plots. While a run goes on its folder is `NAME.partial`.", "",
             "## `summary.json`", "",
             "One object per run. A key a kind of run does not have is absent (`null` in the Python API's "
             "`Run.summary`, a `RunSummary`); the description says which runs write it. `shc schema summary` "
             "prints the same as a JSON Schema.", "",
             "| key | type | holds |", "|---|---|---|", *summary_rows(), "",
             "In the tables below `<LEG>` is a leg id (`AR`, `BR`, …) and `<joint>` a joint name (`coxa`, `femur`, "
             "…), in the robot file's order: legs in id order, joints body to tip "
             f"(the names are folded from the bundled `{ROBOT}` robot).", ""]
    for name, columns in found.items():
        lines += [f"## `{name}`", "", intro[name], "", "| column | holds |", "|---|---|", *table_rows(columns), ""]
    lines += ["## `events.log`", "", events_text(), ""]
    return "\n".join(lines)


def events_text() -> str:
    """The events file's format, from the module that writes it (:mod:`shc_cli.events`)."""
    from shc_cli.events import EVENTS_FORMAT

    return EVENTS_FORMAT


if __name__ == "__main__":
    sys.stdout.write(page())
