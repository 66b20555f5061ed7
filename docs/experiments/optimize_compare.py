"""docs/experiments/optimize.md: the bullet_flat study's front vs the CoT grid, and three Pareto points re-simulated.

Run (after `shc optimize docs/experiments/bullet_flat_openshc.toml --out runs/bullet_flat_openshc` and
`shc sweep docs/experiments/bullet_cot_10s.toml --out runs/bullet_cot_10s`):

    .venv/bin/python docs/experiments/optimize_compare.py runs/bullet_flat_openshc runs/bullet_cot_10s [--recheck]

Prints (Markdown) the grid's feasible CoT–speed front and, for each of its points, the study's lowest CoT among its
feasible trials at equal or higher speed; writes docs/experiments/img/optimize_vs_grid.png. The grid's runs get the
study's constraints (no fall, speed ≥ 0.02 m/s, commanded joints at a limit in ≤ 5 % of the cycles).
``--recheck``: simulates three Pareto trials (lowest CoT, highest speed, the middle one) again from their generated
robot files (`pareto/tNNNN.toml`, with the `shc simulate` options in their header) with fresh seeds 11, 12, 13 and
prints each objective's relative difference from the study's value.
"""

from __future__ import annotations

import csv
import re
import subprocess
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from shc_cli.analysis.metrics import analyze_run
from shc_cli.record.runread import read_run

IMG = Path(__file__).parent / "img"
OBJECTIVES = ("cot", "mean_speed_mps", "stability_margin_median_m")
MIN_SPEED, MAX_LIMITS = 0.02, 0.05


def rows(path: Path) -> list[dict[str, str]]:
    with path.open(newline="") as handle:
        return list(csv.DictReader(handle))


def front(points: list[tuple[float, float, dict[str, str]]]) -> list[tuple[float, float, dict[str, str]]]:
    """(speed, CoT) points no other beats on both (faster or as fast, and cheaper or as cheap), by speed."""
    out = [p for p in points if not any(q[0] >= p[0] and q[1] <= p[1] and (q[0], q[1]) != (p[0], p[1])
                                        for q in points)]
    return sorted(out, key=lambda p: p[0])


def grid_points(folder: Path) -> list[tuple[float, float, dict[str, str]]]:
    out = []
    for row in rows(folder / "results.csv"):
        if row["status"] != "ok" or row["fell"] == "True" or not row["cot"]:
            continue
        result = analyze_run(read_run(folder / "runs" / row["slug"]))
        row["joint_limit_fraction"] = f"{result['joint_limit_fraction']:.4f}"
        if float(row["mean_speed_mps"]) >= MIN_SPEED and result["joint_limit_fraction"] <= MAX_LIMITS:
            out.append((float(row["mean_speed_mps"]), float(row["cot"]), row))
    return out


def study_points(folder: Path) -> list[tuple[float, float, dict[str, str]]]:
    return [(float(r["mean_speed_mps"]), float(r["cot"]), r) for r in rows(folder / "trials.csv")
            if r["state"] == "complete" and r["feasible"] == "True"]


def describe(row: dict[str, str]) -> str:
    frequency = float(row["walker.step_frequency"])
    text = f"{row['gait']}, {frequency:.2f} Hz, stride {row['stride_percent']} %"
    if "walker.swing_height" in row:
        text += (f", swing {float(row['walker.swing_height']):.3f} m, "
                 f"clearance {float(row['walker.body_clearance']):.3f} m")
    return text


def compare(study: Path, grid: Path) -> None:
    grid_all, trials = grid_points(grid), study_points(study)
    grid_front = front(grid_all)
    print(f"grid: {len(grid_all)} feasible runs, {len(grid_front)} on its CoT–speed front; study: {len(trials)} "
          f"feasible trials\n")
    print("| grid point | speed [m/s] | CoT | study's lowest CoT at ≥ that speed | speed [m/s] | CoT | change |")
    print("|---|---|---|---|---|---|---|")
    for speed, cot, row in grid_front:
        faster = [t for t in trials if t[0] >= speed]
        if not faster:
            print(f"| {describe(row)} | {speed:.3f} | {cot:.2f} | none as fast | | | |")
            continue
        best = min(faster, key=lambda t: t[1])
        print(f"| {describe(row)} | {speed:.3f} | {cot:.2f} | trial {best[2]['trial']}: {describe(best[2])} | "
              f"{best[0]:.3f} | {best[1]:.2f} | {(best[1] - cot) / cot:+.0%} |")
    print("\n| speed at least [m/s] | grid: lowest CoT (point, speed) | study: lowest CoT (trial, speed) | change |")
    print("|---|---|---|---|")
    for floor in (0.1, 0.2, 0.3, 0.4, 0.45, 0.5):
        cells = []
        for points in (grid_all, trials):
            faster = [p for p in points if p[0] >= floor]
            cells.append(min(faster, key=lambda p: p[1]) if faster else None)
        text = [f"{c[1]:.2f} ({describe(c[2])}{'; trial ' + c[2]['trial'] if 'trial' in c[2] else ''}, {c[0]:.3f})"
                if c else "none" for c in cells]
        change = f"{(cells[1][1] - cells[0][1]) / cells[0][1]:+.0%}" if cells[0] and cells[1] else ""
        print(f"| {floor:.2f} | {text[0]} | {text[1]} | {change} |")
    print("\n| gait | grid: lowest CoT (point, speed [m/s]) | study, same gait, at ≥ that speed: lowest CoT "
          "(trial, speed) "
          "| change |")
    print("|---|---|---|---|")
    for gait in ("tripod", "bipod", "ripple"):
        mine = [p for p in grid_all if p[2]["gait"] == gait]
        base = min(mine, key=lambda p: p[1]) if mine else None
        found = [p for p in trials if p[2]["gait"] == gait and (base is None or p[0] >= base[0])]
        best = min(found, key=lambda p: p[1]) if found else None
        left = f"{base[1]:.2f} ({describe(base[2])}, {base[0]:.3f})" if base else "not in the grid"
        right = f"{best[1]:.2f} (trial {best[2]['trial']}: {describe(best[2])}, {best[0]:.3f})" if best else "none"
        change = f"{(best[1] - base[1]) / base[1]:+.0%}" if base and best else ""
        print(f"| {gait} | {left} | {right} | {change} |")
    figure, axes = plt.subplots(figsize=(7, 5), dpi=120)
    axes.scatter([p[0] for p in trials], [p[1] for p in trials], s=10, color="tab:blue", alpha=0.4,
                 label=f"study trials (feasible, {len(trials)})")
    axes.scatter([p[0] for p in grid_all], [p[1] for p in grid_all], s=16, marker="s", color="0.5", alpha=0.6,
                 label=f"grid runs (feasible, {len(grid_all)})")
    study_front = front(trials)
    axes.plot([p[0] for p in study_front], [p[1] for p in study_front], "o-", color="tab:red", ms=4,
              label="study: CoT–speed front")
    axes.plot([p[0] for p in grid_front], [p[1] for p in grid_front], "s--", color="k", ms=4,
              label="grid: CoT–speed front")
    axes.set_yscale("log")
    axes.set_xlabel("mean speed [m/s]")
    axes.set_ylabel("cost of transport (eq. 22), log scale")
    axes.set_title("Bullet insectoid, flat, 10 s walking: optimiser vs the paper's grid", fontsize=10)
    axes.grid(True, lw=0.3, which="both")
    axes.legend(fontsize=8)
    figure.tight_layout()
    IMG.mkdir(exist_ok=True)
    figure.savefig(IMG / "optimize_vs_grid.png")
    print(f"\nwrote {IMG / 'optimize_vs_grid.png'}")


def recheck(study: Path) -> None:
    pareto = sorted(rows(study / "pareto.csv"), key=lambda r: float(r["cot"]))
    if not pareto:
        print("no Pareto trials")
        return
    by_speed = sorted(pareto, key=lambda r: float(r["mean_speed_mps"]))
    chosen = list({r["trial"]: r for r in (pareto[0], by_speed[-1], by_speed[len(by_speed) // 2])}.values())
    print("\n| trial | seed | " + " | ".join(f"{k} study / again / diff" for k in OBJECTIVES) + " |")
    print("|---|---|" + "---|" * len(OBJECTIVES))
    for seed, row in zip((11, 12, 13), chosen, strict=False):
        robot = study / "pareto" / f"t{int(row['trial']):04d}.toml"
        flags = re.search(r"^# Found with: shc simulate THIS_FILE (.*)$", robot.read_text(), re.M)
        assert flags is not None
        out = study / "recheck" / f"t{int(row['trial']):04d}-s{seed}"
        if not (out / "summary.json").exists():
            subprocess.run([sys.executable, "-m", "shc_cli.cli", "simulate", str(robot), *flags.group(1).split(),
                            "--seed", str(seed), "--out", str(out), "--no-plots"], check=True, capture_output=True)
        result = analyze_run(read_run(out))
        cells = []
        for key in OBJECTIVES:
            a, b = float(row[key]), float(result[key])
            cells.append(f"{a:.4g} / {b:.4g} / {(b - a) / abs(a):+.2%}")
        print(f"| {row['trial']} ({describe(row)}) | {seed} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    compare(Path(sys.argv[1]), Path(sys.argv[2]))
    if "--recheck" in sys.argv:
        recheck(Path(sys.argv[1]))
