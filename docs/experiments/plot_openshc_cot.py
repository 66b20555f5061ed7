"""Figures of docs/experiments/openshc-cot.md from the sweeps' results tables.

Run (after the two sweeps):  .venv/bin/python docs/experiments/plot_openshc_cot.py runs/bullet_cot/results.csv

Writes docs/experiments/img/cot_fig14.png (mammalian tripod, CoT vs step frequency per stride — paper Fig. 14),
cot_fig15.png (100 % stride: CoT and speed of every configuration and gait — Fig. 15) and cot_fig16.png
(mammalian vs insectoid tripod per stride — Fig. 16).
"""

from __future__ import annotations

import csv
import sys
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

OUT = Path(__file__).parent / "img"
NAMES = {"bullet": "insectoid", "bullet_mammalian": "mammalian"}


def load(path: Path) -> dict[tuple[str, str, int], list[tuple[float, float, float]]]:
    """(robot, gait, stride %) → sorted (step frequency, CoT, speed) of the runs that did not fall."""
    lines: dict[tuple[str, str, int], list[tuple[float, float, float]]] = defaultdict(list)
    with path.open() as handle:
        for row in csv.DictReader(handle):
            if row["status"] != "ok" or row["fell"] == "True" or not row["cot"]:
                continue
            key = (row["robot"], row["gait"], int(float(row["stride_percent"])))
            lines[key].append((float(row["walker.step_frequency"]), float(row["cot"]), float(row["mean_speed_mps"])))
    return {k: sorted(v) for k, v in lines.items()}


def panel(axes: plt.Axes, lines: dict, keys: list, column: int, label) -> None:  # type: ignore[type-arg, no-untyped-def]
    markers = "osD^v<>"
    for i, key in enumerate(keys):
        points = lines.get(key, [])
        axes.plot([p[0] for p in points], [p[column] for p in points], marker=markers[i % len(markers)], ms=4,
                  lw=1.2, label=label(key))
    axes.grid(True, lw=0.3)


def main() -> None:
    lines = load(Path(sys.argv[1] if len(sys.argv) > 1 else "runs/bullet_cot/results.csv"))
    OUT.mkdir(parents=True, exist_ok=True)
    strides = [60, 75, 90, 100]

    figure, axes = plt.subplots(figsize=(6.5, 4), dpi=110)
    panel(axes, lines, [("bullet_mammalian", "tripod", s) for s in strides], 1, lambda k: f"stride {k[2]} %")
    axes.set(xlabel="step frequency [Hz]", ylabel="CoT (eq. 22)", title="Mammalian tripod (cf. paper Fig. 14)")
    axes.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(OUT / "cot_fig14.png")

    figure, (top, bottom) = plt.subplots(2, 1, figsize=(6.5, 6.5), dpi=110, sharex=True)
    keys = [("bullet", "tripod", 100), ("bullet", "bipod", 100), ("bullet_mammalian", "tripod", 100),
            ("bullet_mammalian", "bipod", 100)]
    panel(top, lines, keys, 1, lambda k: f"{NAMES[k[0]]} {k[1]}")
    panel(bottom, lines, keys, 2, lambda k: f"{NAMES[k[0]]} {k[1]}")
    top.set(ylabel="CoT (eq. 22)", title="100 % stride (cf. paper Fig. 15)")
    bottom.set(xlabel="step frequency [Hz]", ylabel="mean speed [m/s]")
    top.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(OUT / "cot_fig15.png")

    figure, (left, right) = plt.subplots(1, 2, figsize=(10, 4), dpi=110, sharey=True)
    panel(left, lines, [("bullet", "tripod", s) for s in strides], 1, lambda k: f"stride {k[2]} %")
    panel(right, lines, [("bullet_mammalian", "tripod", s) for s in strides], 1, lambda k: f"stride {k[2]} %")
    left.set(xlabel="step frequency [Hz]", ylabel="CoT (eq. 22)", title="insectoid tripod")
    right.set(xlabel="step frequency [Hz]", title="mammalian tripod (cf. paper Fig. 16)")
    left.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(OUT / "cot_fig16.png")
    print(f"wrote {OUT}/cot_fig14.png, cot_fig15.png, cot_fig16.png")


if __name__ == "__main__":
    main()
