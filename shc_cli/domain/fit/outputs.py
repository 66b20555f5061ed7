"""What ``shc fit`` writes into its output directory: ``robot.toml`` (the robot with the fitted ``[servo]`` values,
extending the robot fitted), ``fit.json`` and the before/after figures.

``fit.json`` is ``{"params": {NAME: {"value", "initial", "lower", "upper", "uncertainty", "identifiable",
"independence", "correlated_with"}}, "residuals": {...}}``: NAME a ``[servo]`` field; ``uncertainty`` one standard
deviation in the parameter's unit (``null`` when the data do not see it); ``independence`` the share of its effect
the other fitted parameters cannot reproduce and ``correlated_with`` the ones it trades with (when that share is
too small to identify it), ``unsettled`` true when the solver stopped unconverged with a probe of it still lowering
the cost; ``residuals`` the RMS of each measured channel before and after (position
[rad], velocity [rad/s], current [A], torque [N·m], power [W]), the solver's costs, evaluations, replays and the
Jacobian's singular values (:mod:`shc_cli.domain.fit.solve`).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.spec.toml_out import dump_toml

if TYPE_CHECKING:
    from shc_cli.domain.fit.params import Parameter
    from shc_cli.domain.fit.recording import Recording
    from shc_cli.domain.fit.solve import Simulated, Solution

FIT_FILE = "fit.json"
ROBOT_FILE = "robot.toml"
UNITS = {"position": "rad", "velocity": "rad/s", "current": "A", "torque": "N·m", "power": "W"}


def extends_reference(robot: str, out: Path) -> str:
    """How the override names the robot it extends: a bundled name as it is, a file relative to ``out``."""
    path = Path(robot)
    if path.suffix != ".toml" and os.sep not in robot and "/" not in robot:
        return robot
    return os.path.relpath(path.resolve(), out.resolve())


def override_text(robot: str, out: Path, name: str, values: dict[str, float], note: str) -> str:
    """The override robot file: ``extends`` the fitted robot, its ``[servo]`` values replaced (5 digits)."""
    header = [f"# {name}'s servo model fitted by shc fit ({note})",
              dump_toml({"extends": extends_reference(robot, out)}), "[servo]"]
    lines = [*header, *(f"{key} = {float(f'{value:.5g}')!r}" for key, value in values.items())]
    return "\n".join(lines) + "\n"


def fit_json(parameters: list[Parameter], solution: Solution, before: dict[str, float],
             after: dict[str, float]) -> dict[str, Any]:
    """The content of ``fit.json`` (module docstring)."""
    params = {}
    for index, p in enumerate(parameters):
        sigma = float(solution.uncertainty[index])
        params[p.name] = {"value": float(solution.x[index]), "initial": p.initial, "lower": p.lower, "upper": p.upper,
                          "uncertainty": sigma if math.isfinite(sigma) else None,
                          "identifiable": bool(solution.identifiable[index]),
                          "independence": round(float(solution.independence[index]), 4),
                          "correlated_with": [parameters[k].name for k in solution.correlated[index]],
                          "unsettled": bool(solution.unsettled[index])}
    residuals = {"before": before, "after": after, "units": {k: UNITS[k] for k in after},
                 "cost_before": solution.cost_before, "cost_after": solution.cost_after,
                 "evaluations": solution.iterations, "replays": solution.replays, "converged": solution.converged,
                 "singular_values": [float(s) for s in solution.singular_values]}
    return {"params": params, "residuals": residuals}


def write_json(path: Path, data: Mapping[str, object]) -> None:
    path.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


def plot_fit(recording: Recording, before: Simulated, after: Simulated, names: list[str], folder: Path,
             stem: str) -> list[Path]:
    """``<stem>_position.png``, ``<stem>_current.png`` (or ``_torque``) with one panel per joint, and
    ``<stem>_power.png``: measured against simulated before and after the fit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(len(recording.position)) * recording.dt
    written = []
    channels = [("position", recording.position)]
    if recording.current is not None:
        channels.append(("current", recording.current))
    if recording.torque is not None:
        channels.append(("torque", recording.torque))
    for channel, measured in channels:
        count = measured.shape[1]
        columns = min(count, 5)
        rows = math.ceil(count / columns)
        figure, axes = plt.subplots(rows, columns, figsize=(3.2 * columns, 1.8 * rows + 0.6), dpi=90,
                                    sharex=True, squeeze=False)
        for j in range(count):
            ax = axes[j // columns][j % columns]
            ax.plot(t, measured[:, j], lw=0.8, color="black", label="measured")
            ax.plot(t, before.channel(channel)[:, j], lw=0.7, color="tab:red", alpha=0.8, label="before")
            ax.plot(t, after.channel(channel)[:, j], lw=0.7, color="tab:blue", alpha=0.8, label="after")
            ax.set_title(names[j], fontsize=7)
            ax.tick_params(labelsize=6)
        for j in range(count, rows * columns):
            axes[j // columns][j % columns].axis("off")
            if j >= columns:  # the panel above an empty one is the bottom of its column: its times are shown
                axes[j // columns - 1][j % columns].xaxis.set_tick_params(labelbottom=True)
        axes[0][0].legend(fontsize=6)
        figure.suptitle(f"{recording.path.name}: {channel} [{UNITS[channel]}], measured and simulated", fontsize=9)
        figure.supxlabel("time [s]", fontsize=8)
        height = 1.8 * rows + 0.6  # [in]: room below for the tick labels and the time label, above for the titles
        figure.subplots_adjust(left=0.05, right=0.99, bottom=0.5 / height, top=1.0 - 0.55 / height, wspace=0.25,
                               hspace=0.45)
        path = folder / f"{stem}_{channel}.png"
        figure.savefig(path)
        plt.close(figure)
        written.append(path)
    figure, ax = plt.subplots(figsize=(8, 3.5), dpi=100)
    if recording.power is not None:
        ax.plot(t, recording.power, lw=0.8, color="black", label=f"measured (mean {recording.power.mean():.1f} W)")
    ax.plot(t, before.power, lw=0.7, color="tab:red", label=f"before (mean {before.power.mean():.1f} W)")
    ax.plot(t, after.power, lw=0.7, color="tab:blue", label=f"after (mean {after.power.mean():.1f} W)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("total supply power [W]")
    ax.set_title(f"{recording.path.name}: total power" + ("" if recording.power is not None else
                                                           " (not measured: simulated only)"), fontsize=9)
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=7)
    figure.tight_layout()
    path = folder / f"{stem}_power.png"
    figure.savefig(path)
    plt.close(figure)
    written.append(path)
    return written
