"""What a servo bus would have logged of a simulated run: logs with known truth for testing a fit.

:func:`bus_log` copies a ``simulate`` run directory and rewrites its ``log.csv`` as ``run-hw`` writes it: each
servo's position read in whole ticks of its ``[servo] ticks_per_revolution`` (after Gaussian sensor noise), its
present current — the simulated servo's :meth:`~shc_cli.backends.servo.ServoModel.electrical` current, with noise —
in steps of the bus's current unit (Dynamixel MX/X series: 2.69 mA) in the ``_torque`` column [A], and what a bus
does not measure written as 0 and listed in the summary's ``unmeasured``. The total supply power can be kept (a
supply meter; with noise) or dropped.
"""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np

from shc_cli.errors import OutputError

CURRENT_STEP_A = 0.00269
"""Present Current unit of the Dynamixel MX(2.0) and X series [A]."""


def bus_log(source: Path, out: Path, seed: int = 0, position_noise_ticks: float = 0.5,
            current_noise_a: float = 0.005, current_step_a: float = CURRENT_STEP_A, power: bool = True,
            power_noise: float = 0.01) -> Path:
    """Write ``out``: the simulated run ``source`` as a servo bus would have logged it (module docstring).

    Args:
        source: a ``simulate`` run directory.
        out: the new run directory (must not exist).
        seed: seed of the noise.
        position_noise_ticks: standard deviation of position noise before the rounding to ticks [ticks].
        current_noise_a: standard deviation of current noise before the rounding to the current unit [A].
        current_step_a: the current unit [A].
        power: keep the total supply power (``power_w``), as a supply meter would measure it.
        power_noise: its relative noise (standard deviation) [ratio].
    """
    from shc_cli.backends.servo import ServoModel
    from shc_cli.domain.fit.recording import speeds
    from shc_cli.record.runlog import joint_columns
    from shc_cli.record.runread import read_run

    run = read_run(source)
    if run.kind != "simulate" or run.efforts is None or run.summary.unmeasured is not None:
        raise OutputError(f"{source}: not a simulate run (bus_log needs its torques)")
    if out.exists():
        raise OutputError(f"{out}: already exists (choose another directory)")
    robot = run.robot
    rng = np.random.default_rng(seed)
    lines = (source / "log.csv").read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    rows = [line.split(",") for line in lines[1:]]
    index = {name: i for i, name in enumerate(header)}
    names = joint_columns(robot)
    tick = 2.0 * math.pi / robot.servo.ticks_per_revolution
    position = np.array([[float(row[index[n]]) for n in names] for row in rows])
    torque = np.array([[float(row[index[n + "_torque"]]) for n in names] for row in rows])
    current = ServoModel(robot.servo).electrical(torque, speeds(position, robot.time_delta)).current
    read_position = np.round((position + rng.normal(0.0, position_noise_ticks * tick, position.shape)) / tick) * tick
    read_current = np.round((current + rng.normal(0.0, current_noise_a, current.shape)) / current_step_a)
    read_current *= current_step_a
    total = np.array([float(row[index["power_w"]]) for row in rows])
    total = total * (1.0 + rng.normal(0.0, power_noise, total.shape)) if power else np.zeros_like(total)
    from shc_cli.backends.base import MEASURED_BODY_COLUMNS

    zero = [c for c in header if c.endswith("_power") or c.endswith("_force") or c.endswith("_contact")
            or (c in MEASURED_BODY_COLUMNS and c != "power_w")]
    for r, row in enumerate(rows):
        for j, name in enumerate(names):
            row[index[name]] = f"{read_position[r, j]:.6g}"
            row[index[name + "_torque"]] = f"{read_current[r, j]:.6g}"
        for name in zero:
            row[index[name]] = "0"
        row[index["power_w"]] = f"{total[r]:.6g}"
    shutil.copytree(source, out, ignore=shutil.ignore_patterns("*.png", "log.csv"))
    (out / "log.csv").write_text("\n".join([lines[0], *(",".join(row) for row in rows)]) + "\n", encoding="utf-8")
    summary = json.loads((source / "summary.json").read_text(encoding="utf-8"))
    from shc_cli.backends.dynamixel import UNMEASURED

    summary["unmeasured"] = [c for c in UNMEASURED if power is False or c != "power_w"]
    (out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    return out
