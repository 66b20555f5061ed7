"""Figures in the style of the OpenSHC paper. matplotlib is imported here only, with the Agg backend."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from shc_cli.analysis.workspace import WorkspaceReport
    from shc_cli.control.controller import CycleOutput
    from shc_cli.spec.robot import Robot


def _polygon(centre: tuple[float, float], plane: dict[int, float]) -> tuple[list[float], list[float]]:
    xs, ys = [], []
    for bearing in sorted(plane):
        radius = plane[bearing]
        xs.append(centre[0] + radius * math.cos(math.radians(bearing)))
        ys.append(centre[1] + radius * math.sin(math.radians(bearing)))
    return xs, ys


def plot_workspace(report: WorkspaceReport, path: Path) -> None:
    """Top view (paper Fig. 13): body outline, foot tips, each leg's workspace and the walkspace."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    figure, axes = plt.subplots(figsize=(7, 8), dpi=120)
    length, width, _ = report.robot.body.size
    axes.add_patch(Rectangle((-length / 2, -width / 2), length, width, fill=False, color="0.3", lw=1.5,
                                 label="body"))
    colours = plt.get_cmap("tab10")
    for index, (leg, plane) in enumerate(report.planes.items()):
        centre = (float(report.identity_tips[index, 0]), float(report.identity_tips[index, 1]))
        colour = colours(index % 10)
        xs, ys = _polygon(centre, plane)
        axes.fill(xs, ys, color=colour, alpha=0.15)
        axes.plot(xs, ys, color=colour, lw=1.2, label=f"{leg} workspace")
        wx, wy = _polygon(centre, report.walkspace)
        axes.plot(wx, wy, color="k", lw=1.0, ls="--", label="walkspace" if index == 0 else None)
        axes.plot(*centre, "o", color=colour, ms=5)
        axes.annotate(leg, centre, textcoords="offset points", xytext=(4, 4), fontsize=8)
    axes.set_aspect("equal")
    axes.set_xlabel("x (forward) [m]")
    axes.set_ylabel("y (left) [m]")
    axes.set_title(f"{report.robot.name}: leg workspaces and walkspace ({report.gait.name})")
    axes.grid(True, lw=0.3)
    axes.legend(loc="upper center", bbox_to_anchor=(0.5, -0.09), fontsize=7, ncols=4, frameon=False)
    figure.tight_layout()
    figure.savefig(path, format="png")
    plt.close(figure)


def plot_plan(robot: Robot, outputs: list[CycleOutput], folder: Path) -> None:
    """gait.png (paper Fig. 5), tips.png (Fig. 7: side and top view) and joints.png in ``folder``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    dt = robot.time_delta
    legs = list(robot.legs)
    t = np.arange(len(outputs)) * dt
    swing = np.array([o.swing_progress for o in outputs])

    _leg_bars(legs, t, dt, swing >= 0.0, "time [s] (black: swing, white: stance)", f"{robot.name}: gait diagram",
              folder / "gait.png")

    walker = np.array([o.walker_tips for o in outputs])
    figure, (side, top) = plt.subplots(1, 2, figsize=(11, 4.5), dpi=110)
    for row, leg in enumerate(legs):
        side.plot(walker[:, row, 0], walker[:, row, 2], lw=0.8, label=leg)
        top.plot(walker[:, row, 0], walker[:, row, 1], lw=0.8, label=leg)
    side.set_xlabel("x [m]")
    side.set_ylabel("z [m]")
    side.set_title("tip trajectories, side view (walk plane)")
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.set_title("top view")
    top.legend(fontsize=7, ncols=2)
    figure.tight_layout()
    figure.savefig(folder / "tips.png")
    plt.close(figure)

    joints = np.array([o.joints for o in outputs])
    figure, axes_grid = plt.subplots(len(legs), 1, figsize=(9, 1.6 * len(legs)), dpi=110, sharex=True)
    for row, (leg, spec) in enumerate(robot.legs.items()):
        axis = axes_grid[row] if len(legs) > 1 else axes_grid
        for k, name in enumerate(spec.joints):
            axis.plot(t, joints[:, row, k], lw=0.8, label=name)
        axis.set_ylabel(f"{leg} [rad]")
        axis.legend(fontsize=6, loc="upper right", ncols=len(spec.joints))
    (axes_grid[-1] if len(legs) > 1 else axes_grid).set_xlabel("time [s]")
    figure.tight_layout()
    figure.savefig(folder / "joints.png")
    plt.close(figure)


def plot_simulation(robot: Robot, series: dict[str, list[Any]], folder: Path) -> None:
    """trajectory.png (body path, top view), power.png (total electrical power) and contacts.png (feet on the
    ground over time: the measured gait diagram) in ``folder``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    t = np.array(series["t"])
    position = np.array(series["position"])
    figure, axes = plt.subplots(figsize=(6, 5), dpi=110)
    axes.plot(position[:, 0], position[:, 1], lw=1.0)
    axes.plot(position[0, 0], position[0, 1], "go", label="start")
    axes.plot(position[-1, 0], position[-1, 1], "rs", label="end")
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel("x [m]")
    axes.set_ylabel("y [m]")
    axes.set_title(f"{robot.name}: body trajectory")
    axes.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(folder / "trajectory.png")
    plt.close(figure)

    figure, axes = plt.subplots(figsize=(8, 3.5), dpi=110)
    axes.plot(t, series["power"], lw=0.8)
    axes.set_xlabel("time [s]")
    axes.set_ylabel("electrical power [W]")
    axes.set_title(f"{robot.name}: total servo power")
    axes.grid(True, lw=0.3)
    figure.tight_layout()
    figure.savefig(folder / "power.png")
    plt.close(figure)

    contact = np.array(series["contact"], dtype=bool)
    _leg_bars(list(robot.legs), t, robot.time_delta, contact, "time [s] (black: foot on the ground)",
              f"{robot.name}: measured foot contacts", folder / "contacts.png")


def _leg_bars(legs: list[str], t: Any, dt: float, flags: Any, xlabel: str, title: str, path: Path) -> None:
    """One row of black bars per leg where ``flags[:, leg]`` is set (cycles at times ``t`` [s], ``dt`` apart)."""
    import matplotlib.pyplot as plt
    import numpy as np

    figure, axes = plt.subplots(figsize=(9, 0.45 * len(legs) + 1.2), dpi=110)
    for row in range(len(legs)):
        on = flags[:, row].astype(int)
        starts = np.flatnonzero(np.diff(np.concatenate([[0], on])) == 1)
        ends = np.flatnonzero(np.diff(np.concatenate([on, [0]])) == -1)
        axes.broken_barh([(t[a], (b - a + 1) * dt) for a, b in zip(starts, ends, strict=True)],
                         (row - 0.4, 0.8), facecolors="0.2")
    axes.set_yticks(range(len(legs)), legs)
    axes.invert_yaxis()
    axes.set_xlabel(xlabel)
    axes.set_title(title)
    figure.tight_layout()
    figure.savefig(path)
    plt.close(figure)
