"""Where a walk's commanded speed goes: servo lag, foot slip and the stance hand-over, from one simulate run.

Run (after ``shc simulate --out runs/bullet``; any robot, engine, terrain):

    .venv/bin/python docs/experiments/speed_breakdown.py runs/bullet

Over the run's analysis window (RUNNING cycles), for every pair of consecutive cycles with a foot in contact in both,
the body's forward speed (along its heading) is split exactly into what the feet in contact say:

    v_body = −mean(R·v_foot_body, measured joints) + mean(v_foot_world)

``v_foot_body`` is a contact foot's velocity in the body frame (the DH tips of the logged joints) and ``R`` the body's
rotation; a stance foot that holds still in the world carries the body at minus its body-frame speed, and what the
feet move in the world is slip (with the foot sphere's rolling). The commanded joints give the same stance term as the
controller meant it; the controller's desired velocity is the command. Prints, in m/s and as shares of the command:
the command, the stance feet's commanded speed (the plan's), the measured one (the difference: the servos' lag under
load and their torque limit), the slip term, and the body's speed.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from shc_cli.analysis.metrics import rotation_rpy
from shc_cli.model.chains import Chains
from shc_cli.record.runread import read_run


def stance_speed(chains: Chains, joints: np.ndarray, rpy: np.ndarray, contact: np.ndarray, heading: np.ndarray,
                 dt: np.ndarray) -> np.ndarray:
    """Per step, −(mean over the feet in contact at both ends) of the feet's body-frame velocity, rotated into the
    world and taken along the heading [m/s] (NaN where no foot was in contact)."""
    tips = chains.frames_in_base(joints)[..., -1, :3, 3]  # (N, L, 3) in base_link
    rotation = rotation_rpy(rpy)
    world = np.einsum("mij,mlj->mli", rotation[:-1], tips[1:] - tips[:-1]) / dt[:, None, None]
    along = world[..., 0] * np.cos(heading)[:, None] + world[..., 1] * np.sin(heading)[:, None]
    both = contact[1:] & contact[:-1]
    count = both.sum(axis=1)
    with np.errstate(invalid="ignore"):
        result: np.ndarray = -(along * both).sum(axis=1) / count
    return result


def breakdown(path: Path) -> dict[str, float]:
    run = read_run(path)
    if run.commanded is None:
        raise SystemExit(f"{path}: the log has no commanded joints")
    rows = np.flatnonzero(run.running)
    t, chains = run.t[rows], Chains.from_robot(run.robot)
    dt = np.diff(t)
    heading = run.rpy[rows[:-1], 2]
    contact = run.contact[rows].astype(bool)
    measured = stance_speed(chains, run.joints[rows], run.rpy[rows], contact, heading, dt)
    commanded = stance_speed(chains, run.commanded[rows], run.rpy[rows], contact, heading, dt)
    step = np.diff(run.position[rows, :2], axis=0) / dt[:, None]
    body = step[:, 0] * np.cos(heading) + step[:, 1] * np.sin(heading)
    ok = np.isfinite(measured)
    weights = dt[ok] / dt[ok].sum()
    command = float(np.mean(np.hypot(run.desired[rows, 0], run.desired[rows, 1])))
    stance_cmd, stance = float(weights @ commanded[ok]), float(weights @ measured[ok])
    body_mean = float(weights @ body[ok])
    return {"command": command, "stance_commanded": stance_cmd, "stance_measured": stance,
            "slip": body_mean - stance, "body": body_mean, "no_contact_share": float(1.0 - ok.mean())}


def main() -> None:
    for name in sys.argv[1:]:
        figures = breakdown(Path(name))
        command = figures["command"]
        print(f"{name}: command {command:.4f} m/s")
        for key in ("stance_commanded", "stance_measured", "slip", "body"):
            print(f"  {key:17s} {figures[key]:+.4f} m/s  {figures[key] / command:+7.1%}")
        print(f"  steps with no foot in contact at both ends: {figures['no_contact_share']:.1%}")


if __name__ == "__main__":
    main()
