"""The OpenSHC paper's §VIII claims and Figs. 14–16 from the two sweeps of docs/experiments/openshc-cot.md.

Run (after ``shc sweep sweeps/openshc_table4.toml`` and ``shc sweep sweeps/openshc_cot.toml``):

    .venv/bin/python docs/experiments/openshc_paper.py runs/openshc_table4/results.csv runs/openshc_cot/results.csv

Prints Table IV (ours, the paper's, the difference) and every quantitative §VIII claim with our figure, and writes
docs/experiments/img/paper_fig14.png, paper_fig15.png and paper_fig16.png (CoT and speed against step frequency).
"""

from __future__ import annotations

import csv
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

OUT = Path(__file__).parent / "img"
TABLE_IV = {("bullet_mammalian_a", "tripod"): (27.7, 51.0, 48.6), ("bullet_mammalian_b", "tripod"): (30.4, 47.1, 46.7),
            ("bullet_insectoid_a", "tripod"): (30.4, 61.9, 58.3), ("bullet_insectoid_a", "bipod"): (30.4, 72.3, 58.3),
            ("bullet_insectoid_b", "tripod"): (31.1, 62.9, 56.0)}
"""Paper Table IV [W]: stance air, walk air, stance ground."""
Line = dict[float, tuple[float | None, float, bool]]
"""Step frequency → (CoT or None, mean speed [m/s], fell)."""


def table4(path: Path) -> dict[tuple[str, str, str], float]:
    with path.open() as handle:
        return {(r["robot"], r["gait"], r["scenario"]): float(r["mean_power_w"]) for r in csv.DictReader(handle)
                if r["status"] == "ok"}


def cot_lines(path: Path) -> dict[tuple[str, str, float], Line]:
    lines: dict[tuple[str, str, float], Line] = defaultdict(dict)
    with path.open() as handle:
        for r in csv.DictReader(handle):
            if r["status"] != "ok":
                continue
            key = (r["robot"], r["gait"], float(r["stride_percent"]))
            cot = float(r["cot"]) if r["cot"] and r["fell"] != "True" else None
            lines[key][float(r["walker.step_frequency"])] = (cot, float(r["mean_speed_mps"]), r["fell"] == "True")
    return dict(lines)


def argmin(line: Line) -> float | None:
    cots = {f: c for f, (c, _, _) in line.items() if c is not None}
    return min(cots, key=lambda f: cots[f]) if cots else None


def values(line: Line) -> str:
    """``frequency CoT`` pairs of a line, ``fell`` where the run fell."""
    return ", ".join(f"{f:g} {c:.2f}" if c is not None else f"{f:g} fell" for f, (c, _, _) in sorted(line.items()))


def report(power: dict[tuple[str, str, str], float], lines: dict[tuple[str, str, float], Line]) -> list[str]:
    out = ["Table IV [W]: ours / paper (difference)"]
    for (robot, gait), paper in TABLE_IV.items():
        cells = []
        for scenario, want in zip(("SA", "WA", "SG"), paper, strict=True):
            got = power.get((robot, gait, scenario))
            cells.append(f"{scenario} {got:.1f} / {want} ({(got - want) / want:+.0%})" if got else f"{scenario} —")
        out.append(f"  {robot} {gait}: " + ", ".join(cells))

    def p(robot: str, scenario: str, gait: str = "tripod") -> float:
        return power[(robot, gait, scenario)]

    ma, mb, ia, ib = "bullet_mammalian_a", "bullet_mammalian_b", "bullet_insectoid_a", "bullet_insectoid_b"
    out.append("Claims")
    out.append(f"  SG mammalian < insectoid: A {p(ma, 'SG'):.1f} vs {p(ia, 'SG'):.1f}, B {p(mb, 'SG'):.1f} vs "
               f"{p(ib, 'SG'):.1f}")
    out.append(f"  SA mammalian < insectoid: A {p(ma, 'SA'):.1f} vs {p(ia, 'SA'):.1f}, B {p(mb, 'SA'):.1f} vs "
               f"{p(ib, 'SA'):.1f}")
    out.append(f"  SA A < B: mammalian {p(ma, 'SA'):.1f} vs {p(mb, 'SA'):.1f}, insectoid {p(ia, 'SA'):.1f} vs "
               f"{p(ib, 'SA'):.1f}")
    out.append(f"  SG B < A: mammalian {p(mb, 'SG'):.1f} vs {p(ma, 'SG'):.1f}, insectoid {p(ib, 'SG'):.1f} vs "
               f"{p(ia, 'SG'):.1f}")
    walk_air = {key: power[(*key, "WA")] for key in TABLE_IV if (*key, "WA") in power}
    out.append(f"  WA highest: {max(walk_air, key=lambda k: walk_air[k])}; WA mammalian B < A: {p(mb, 'WA'):.1f} vs "
               f"{p(ma, 'WA'):.1f}")
    out.append("  WA > SA: " + ", ".join(f"{r} {g} {power[(r, g, 'WA')] - power[(r, g, 'SA')]:+.1f} W"
                                           for r, g in TABLE_IV))
    if not lines:
        return out
    fig14 = {s: lines[(ma, "tripod", s)] for s in (60.0, 75.0, 90.0, 100.0) if (ma, "tripod", s) in lines}
    longer = [f for f in fig14.get(100.0, {}) if all(fig14[s].get(f, (None,))[0] is not None for s in fig14)]
    cheaper = sum(1 for f in longer if fig14[100.0][f][0] <= fig14[60.0][f][0])  # type: ignore[operator]
    out.append(f"  Fig. 14 100 % stride cheaper than 60 %: {cheaper} of {len(longer)} frequencies")
    m100 = fig14.get(100.0, {})
    out.append(f"  Fig. 14 mammalian A 100 % CoT minimum at {argmin(m100)} Hz: "
               + ", ".join(f"{f:g} Hz {c:.2f}" for f, (c, _, _) in sorted(m100.items()) if c is not None))
    if 1.2 in m100 and 1.4 in m100:
        out.append(f"  Fig. 14 speed 1.4 Hz {m100[1.4][1]:.3f} vs 1.2 Hz {m100[1.2][1]:.3f} m/s")
    tri, bi = lines.get((ia, "tripod", 100.0), {}), lines.get((ia, "bipod", 100.0), {})
    out.append(f"  Fig. 15 insectoid A tripod minimum at {argmin(tri)} Hz: {values(tri)}")
    out.append(f"  Fig. 15 insectoid A bipod minimum at {argmin(bi)} Hz: {values(bi)}")
    common = [f for f in tri if f in bi and tri[f][0] is not None and bi[f][0] is not None]
    below = sum(1 for f in common if bi[f][0] <= tri[f][0])  # type: ignore[operator]
    ratios = [bi[f][1] / tri[f][1] for f in common if tri[f][1] > 0]
    out.append(f"  bipod CoT <= tripod: {below} of {len(common)}; bipod/tripod speed mean "
               f"{sum(ratios) / len(ratios) - 1:+.0%} (range {min(ratios) - 1:+.0%} … {max(ratios) - 1:+.0%})"
               if ratios else "  bipod/tripod: no common frequencies")
    fell = sorted(f"{k[0]} {k[1]} {k[2]:g} % {f:g} Hz" for k, line in lines.items() for f, v in line.items() if v[2])
    out.append(f"  falls: {', '.join(fell) if fell else 'none'}")
    mb100, ib60, ib100 = (lines.get((mb, "tripod", 100.0), {}), lines.get((ib, "tripod", 60.27), {}),
                          lines.get((ib, "tripod", 100.0), {}))
    above = [f for f in mb100 if f > 2.0 and f in ib60 and mb100[f][0] is not None and ib60[f][0] is not None]
    lower = sum(1 for f in above if mb100[f][0] < ib60[f][0])  # type: ignore[operator]
    out.append(f"  Fig. 16 mammalian B below insectoid B 60.27 % above 2 Hz: {lower} of {len(above)}")
    slower = sum(1 for f in mb100 if f in ib60 and mb100[f][1] < ib60[f][1])
    out.append(f"  Fig. 16 mammalian B slower than insectoid B 60.27 %: {slower} of {len(mb100)}")
    for name, line in (("mammalian B 100 %", mb100), ("insectoid B 60.27 %", ib60), ("insectoid B 100 %", ib100)):
        out.append(f"  Fig. 16 {name} minimum at {argmin(line)} Hz: {values(line)}")
    everything = [(c, k, f) for k, line in lines.items() for f, (c, _, _) in line.items() if c is not None]
    best = min(everything)
    out.append(f"  lowest CoT of all: {best[1][0]} {best[1][1]} {best[1][2]:g} % at {best[2]:g} Hz ({best[0]:.2f})")
    return out


def figure(lines: dict[tuple[str, str, float], Line], keys: list[tuple[str, str, float]], name: str,
           title: str) -> None:
    fig, (cot_axes, speed_axes) = plt.subplots(1, 2, figsize=(11, 4))
    for key in keys:
        line = lines.get(key, {})
        label = f"{key[0].removeprefix('bullet_')} {key[1]} {key[2]:g} %"
        points = sorted((f, c, v) for f, (c, v, _) in line.items() if c is not None)
        cot_axes.plot([f for f, _, _ in points], [c for _, c, _ in points], "o-", label=label)
        speed_axes.plot([f for f, _, _ in points], [v for _, _, v in points], "o-", label=label)
    cot_axes.set(xlabel="step frequency [Hz]", ylabel="cost of transport (eq. 22)", title=title)
    speed_axes.set(xlabel="step frequency [Hz]", ylabel="mean speed [m/s]", title="speed")
    cot_axes.legend(fontsize=8)
    fig.tight_layout()
    OUT.mkdir(exist_ok=True)
    fig.savefig(OUT / name, dpi=90)
    plt.close(fig)


def main(arguments: list[str]) -> None:
    power = table4(Path(arguments[0]))
    lines = cot_lines(Path(arguments[1])) if len(arguments) > 1 else {}
    print("\n".join(report(power, lines)))
    if lines:
        ma, ia = "bullet_mammalian_a", "bullet_insectoid_a"
        figure(lines, [(ma, "tripod", s) for s in (60.0, 75.0, 90.0, 100.0)], "paper_fig14.png",
               "Fig. 14: mammalian A tripod")
        figure(lines, [(ia, "tripod", 100.0), (ia, "bipod", 100.0), (ma, "tripod", 100.0)], "paper_fig15.png",
               "Fig. 15: arrangement A, 100 % stride")
        figure(lines, [("bullet_mammalian_b", "tripod", 100.0), ("bullet_insectoid_b", "tripod", 60.27),
                       ("bullet_insectoid_b", "tripod", 100.0)], "paper_fig16.png", "Fig. 16: arrangement B")


if __name__ == "__main__":
    from script import run

    run(main, "TABLE4_RESULTS_CSV [COT_RESULTS_CSV]", 1, 2)
