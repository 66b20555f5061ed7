"""What ``shc replay`` prints and writes: the worst differences as text or JSON, the per-cycle CSV and its plot."""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from shc_cli.replay.compare import LABELS, QUANTITIES
from shc_cli.replay.run import Replay
from shc_cli.replay.source import ABSURD

ISSUE_KEYS = ("joints_rad", "model_tip_m", "walker_tip_m", "poser_tip_m", "velocity", "progress")
"""Quantities always present in ``--json``'s ``worst`` (``null`` when the source does not hold them)."""


def summary(result: Replay, robot: str, gait: str) -> dict[str, Any]:
    """The ``--json`` document."""
    comparison = result.comparison
    worst, at = comparison.worst, comparison.at_cycle
    keys = [*ISSUE_KEYS, *(q for q in QUANTITIES if q not in ISSUE_KEYS and q in comparison.differences)]
    plan = result.plan
    return {
        "cycles": result.recorded.cycles,
        "worst": {q: worst.get(q) for q in keys},
        "at_cycle": {q: at.get(q) for q in keys},
        "skipped": {q: comparison.skipped[q] for q in comparison.quantities},
        "source": str(result.recorded.source),
        "kind": result.recorded.kind,
        "robot": robot,
        "gait": gait,
        "topics": result.recorded.topics,
        "compared": comparison.compared,
        "not_compared": comparison.missing,
        "not_replayed": result.recorded.not_replayed,
        "states": {"first_motion": plan.first_motion, "running": plan.running, "evidence": plan.evidence,
                   "later": [[cycle, state.name] for cycle, state in plan.later]},
        "retimed_inputs": [[cycle, shift] for cycle, shift in result.retimed],
    }


WRONG_ROBOT_RAD = 0.3
"""Joint differences above this [rad] are not a controller discrepancy but (almost always) the wrong ``--robot`` or
``--gait``: the faithful replays differ by micro-radians (tests/test_replay_golden.py)."""


def wrong_robot_hint(result: Replay, robot: str) -> str | None:
    """A hint when the joints differ so much that the recording was most likely made with another robot."""
    worst = result.comparison.worst.get("joints_rad")
    if worst is None or worst <= WRONG_ROBOT_RAD:
        return None
    return (f"hint: joints differ by up to {worst:.2g} rad — far beyond a controller difference; was the recording "
            f"made with another robot or gait than {robot}? (give it with --robot, --gait)")


def text(result: Replay, robot: str, gait: str) -> str:
    """The terminal report: what was read and compared, the inferred states and the worst difference of each
    quantity with its cycle."""
    recorded, comparison = result.recorded, result.comparison
    lines = [f"{recorded.source} ({recorded.kind}, {recorded.cycles} cycles) replayed on {robot} / {gait}",
             f"read: {', '.join(recorded.topics)}",
             f"compared: {', '.join(comparison.compared)}"]
    if comparison.missing:
        lines.append(f"not in the source: {', '.join(comparison.missing)}")
    if recorded.not_replayed:
        lines.append(f"inputs not replayed (expect differences where they act): {', '.join(recorded.not_replayed)}")
    lines.append(result.plan.describe())
    if result.retimed:
        moved = ", ".join(f"cycle {cycle} {shift:+d}" for cycle, shift in result.retimed)
        lines.append(f"velocity changes placed by the joints (arrived on a cycle's edge): {moved}")
    worst, at = comparison.worst, comparison.at_cycle
    rows = [(LABELS[q][0], f"{worst[q]:.3g}", LABELS[q][1], str(at[q])) for q in comparison.quantities if q in worst]
    lines.append("worst difference:")
    width = max((len(r[0]) for r in rows), default=0)
    lines += [f"  {name:<{width}}  {value:>9} {unit:<10}  at cycle {cycle}" for name, value, unit, cycle in rows]
    skipped = [f"{LABELS[q][0]} {n}" for q, n in comparison.skipped.items() if n]
    if skipped:
        lines.append(f"skipped (recorded numbers non-finite or beyond ±{ABSURD:g}): {', '.join(skipped)}")
    hint = wrong_robot_hint(result, robot)
    if hint is not None:
        lines.append(hint)
    return "\n".join(lines)


def differences_csv(result: Replay) -> str:
    """One row per cycle: time, the controller's robot and walk state, each quantity's difference (empty where
    nothing was compared)."""
    comparison = result.comparison
    quantities = comparison.quantities
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["cycle", "t", "robot_state", "walk_state", *quantities])
    for cycle in range(result.recorded.cycles):
        values = [comparison.differences[q][cycle] for q in quantities]
        writer.writerow([cycle, f"{result.recorded.t[cycle]:.6f}", result.robot_states[cycle].name,
                         result.walk_states[cycle].name, *("" if math.isnan(v) else f"{v:.9g}" for v in values)])
    return buffer.getvalue()


def plot_differences(result: Replay, title: str, path: Path) -> Path:
    """Differences over time (log scale) with the robot and walk states underneath; saved atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from shc_cli.outputs import atomic_path

    comparison = result.comparison
    t = result.recorded.t
    figure, (top, states) = plt.subplots(2, 1, figsize=(10, 6), sharex=True, height_ratios=(3, 1))
    floor = 1e-9
    for q in comparison.quantities:
        d = comparison.differences[q]
        if np.isfinite(d).any():
            name, unit = LABELS[q]
            top.semilogy(t, np.maximum(d, floor), lw=0.6, label=f"{name} [{unit}]" if unit else name)
    top.set_ylabel("|shc − OpenSHC|")
    top.set_title(title, fontsize=9)
    top.grid(True, lw=0.3)
    top.legend(fontsize=7, loc="upper right")
    robot_codes = np.array([int(s) for s in result.robot_states])
    walk_codes = np.array([int(s) for s in result.walk_states])
    states.step(t, robot_codes, where="post", lw=1.0, label="robot state")
    states.step(t, walk_codes - 5, where="post", lw=1.0, label="walk state")
    names = ["UNKNOWN", "PACKED", "READY", "RUNNING", "STARTING", "MOVING", "STOPPING", "STOPPED"]
    states.set_yticks([-1, 0, 1, 2, -5, -4, -3, -2], names, fontsize=6)
    states.set_xlabel("time [s]")
    states.grid(True, lw=0.3)
    states.legend(fontsize=7, loc="upper right")
    figure.tight_layout()
    with atomic_path(path) as temporary:
        figure.savefig(temporary, format="png")
    plt.close(figure)
    return path
