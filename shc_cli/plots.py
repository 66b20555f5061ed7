"""Figures in the style of the OpenSHC paper. matplotlib is imported here only, with the Agg backend."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.analysis.workspace import WorkspaceReport


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
