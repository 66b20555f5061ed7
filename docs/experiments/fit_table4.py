"""The Table IV calibration of docs/experiments/fit_servo.py redone with ``shc fit``.

Run (after ``shc sweep sweeps/openshc_table4.toml --out runs/openshc_table4``):

    .venv/bin/python docs/experiments/fit_table4.py runs/openshc_table4 [OUT]

The paper gives one figure per cell — the mean supply power of a 10 s run — and no trace, so each of the sweep's
runs becomes a recording whose measured ``power_w`` is the run's own shifted to that cell's Table IV mean, and whose
joints and torques are the run's own. ``shc fit`` then fits ``idle_power``, ``coulomb_friction`` and
``holding_ratio`` — the three figures ``fit_servo.py`` fits, none of which changes the motion — one fit per robot
of the sweep (``shc fit`` fits the runs of one robot; the default robot, ``bullet``, is ``bullet_insectoid_a``,
whose six cells are its tripod and bipod rows). Least squares on every cycle's power weighs the cell's mean against
how each parameter reshapes the trace (idle power shifts it, Coulomb friction follows the joint speeds, the holding
ratio the still joints' loads); a constant trace instead would make the fit shrink every term that fluctuates
(``Σ(P − c)² = N·((P̄ − c)² + var P)``). Prints, per robot, the fitted values against ``robots/bullet.toml``'s and
each cell's mean power with the shipped and the fitted values against the paper (``fit_servo.py``'s re-evaluation
of the logged torques), and the fit's RMS errors: the replay must give the run's own joints back (position ≈ 0).
"""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

from fit_servo import load_cells, mean_power

FITTED = ("idle_power", "coulomb_friction", "holding_ratio")


def paper_recording(run: Path, out: Path, paper: float) -> Path:
    """A copy of the simulated ``run`` whose ``power_w`` is its own, shifted so that its RUNNING cycles' mean is the
    paper's ``paper`` [W] (the trace keeps the simulation's fluctuation; a constant would make the fit shrink
    every term that fluctuates, Coulomb friction first: ``Σ(P − c)² = N·((P̄ − c)² + var P)``)."""
    shutil.copytree(run, out, ignore=shutil.ignore_patterns("*.png", "*.mcap"))
    lines = (run / "log.csv").read_text(encoding="utf-8").splitlines()
    header = lines[0].split(",")
    column, state = header.index("power_w"), header.index("robot_state")
    rows = [line.split(",") for line in lines[1:]]
    running = [float(row[column]) for row in rows if row[state] == "RUNNING"]
    shift = paper - sum(running) / len(running)
    for row in rows:
        row[column] = f"{float(row[column]) + shift:.6g}"
    (out / "log.csv").write_text("\n".join([lines[0], *(",".join(row) for row in rows)]) + "\n", encoding="utf-8")
    return out


def main(arguments: list[str]) -> None:
    from shc_cli.api import fit, load_robot

    sweep = Path(arguments[0])
    out = Path(arguments[1]) if len(arguments) > 1 else Path("fits/table4")
    with open(sweep / "results.csv", encoding="utf-8") as handle:
        rows = list(csv.DictReader(handle))
    cells = load_cells(sweep)  # (the rows' order)
    shipped = {name: float(getattr(load_robot("bullet").servo, name)) for name in FITTED}
    print("robots/bullet.toml: " + ", ".join(f"{name} {value:g}" for name, value in shipped.items()))
    for robot in dict.fromkeys(row["robot"] for row in rows):
        mine = [(row, cell) for row, cell in zip(rows, cells, strict=True) if row["robot"] == robot]
        runs = [paper_recording(sweep / "runs" / row["slug"], out / "recordings" / row["slug"], cell.paper)
                for row, cell in mine]
        result = fit(runs, robot=robot, params=",".join(FITTED), out=out / robot, plots=False, overwrite=True)
        group = result.fits[0]
        print(f"{robot}: " + ", ".join(
            f"{name} {group.values[name]:.3g} ± {float(group.solution.uncertainty[i]):.2g}"
            + ("" if group.solution.identifiable[i] else " (not identifiable)") for i, name in enumerate(FITTED))
            + "; RMS " + ", ".join(f"{k} {group.before[k]:.3g} → {group.after[k]:.3g}" for k in group.after))
        for _, cell in mine:
            before, after = mean_power(cell, shipped), mean_power(cell, group.values)
            print(f"  {cell.label:36s} paper {cell.paper:5.1f}  shipped {before:5.1f} ({before / cell.paper - 1:+.0%})"
                  f"  fitted {after:5.1f} ({after / cell.paper - 1:+.0%})")


if __name__ == "__main__":
    from script import run

    run(main, "TABLE4_SWEEP_DIR (the --out of shc sweep sweeps/openshc_table4.toml) [OUT]", 1, 2)
