"""Figures in the style of the OpenSHC paper, drawn with matplotlib's object API on Agg canvases (not pyplot: no
figure manager, no global state, no backend switch)."""

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
    from matplotlib.patches import Rectangle

    figure, axes = _subplots(figsize=(7, 8), dpi=120)
    length, width, _ = report.robot.body.size
    axes.add_patch(Rectangle((-length / 2, -width / 2), length, width, fill=False, color="0.3", lw=1.5,
                                 label="body"))
    colours = matplotlib.colormaps["tab10"]
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
    _tight(figure)
    figure.savefig(path, format="png")


def _subplots(*grid: int, figsize: tuple[float, float], dpi: float, **options: Any) -> Any:
    """``pyplot.subplots`` without pyplot: a :class:`~matplotlib.figure.Figure` on its own Agg canvas and its axes
    (``options``: :meth:`Figure.subplots`'). No figure manager and no global figure list: nothing to close, the
    figure goes with its last reference."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(figure)
    return figure, figure.subplots(*grid, **options)


def _tight(figure: Any) -> None:
    """``figure.tight_layout()``, done once: the figure is then left without a layout engine. (``tight_layout``
    leaves a placeholder engine behind, and ``savefig`` draws a figure that has one twice — once to lay it out,
    once to render; 0.03 s of a simulation's three figures. The pixels are the same.)"""
    figure.tight_layout()
    figure.set_layout_engine(None)


def fitted_title(axes: Any, text: str, fontsize: float = 10.0) -> None:
    """``axes.set_title(text)`` wrapped to the figure's width (a long title was cut at the figure's edges: the
    Pareto plot's "…40 complete"): lines of at most the characters of ``fontsize`` that fit across the figure."""
    import textwrap

    columns = int(axes.figure.get_figwidth() * 72.0 / (0.6 * fontsize))  # 72 points an inch; a glyph ≈ 0.6 em
    axes.set_title(textwrap.fill(text, max(20, columns - 4)), fontsize=fontsize)


SWING_COLOUR = "black"
"""Gait diagrams (paper Fig. 5): a leg in swing is a black bar, in stance white (left blank); start-up is grey."""
STANCE_COLOUR = "white"
STARTUP_COLOUR = "0.85"


def run_title(robot: Robot, gait: str | None) -> str:
    """``robot / gait``: the start of every run plot's title (``gait`` defaults to the robot's own)."""
    return f"{robot.name} / {gait or robot.walker.gait}"


def plot_plan(robot: Robot, outputs: list[CycleOutput], folder: Path, gait: str | None = None) -> None:
    """gait.png (paper Fig. 5), tips.png (Fig. 7: side and top view) and joints.png in ``folder``; ``gait`` names
    the run's gait in the titles (default: the robot's)."""
    import numpy as np

    dt = robot.time_delta
    legs = list(robot.legs)
    t = np.arange(len(outputs)) * dt
    swing = np.array([o.swing_progress for o in outputs])
    title = run_title(robot, gait)
    startup = np.array([o.robot_state.name != "RUNNING" for o in outputs])

    _leg_bars(legs, t, dt, swing >= 0.0, f"{title}: gait diagram (planned)", folder / "gait.png", startup)

    walker = np.array([o.walker_tips for o in outputs])
    figure, (side, top) = _subplots(1, 2, figsize=(11, 4.5), dpi=110)
    for row, leg in enumerate(legs):
        side.plot(walker[:, row, 0], walker[:, row, 2], lw=0.8, label=leg)
        top.plot(walker[:, row, 0], walker[:, row, 1], lw=0.8, label=leg)
    side.set_xlabel("x [m]")
    side.set_ylabel("z [m]")
    side.set_title("side view (walk plane)")
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.set_title("top view")
    top.legend(fontsize=7, ncols=2)
    figure.suptitle(f"{title}: foot tip trajectories")
    _tight(figure)
    figure.savefig(folder / "tips.png")

    joints = np.array([o.joints for o in outputs])
    figure, axes_grid = _subplots(len(legs), 1, figsize=(10, 1.6 * len(legs) + 0.6), dpi=110, sharex=True,
                                     squeeze=False)
    for row, (leg, spec) in enumerate(robot.legs.items()):
        axis = axes_grid[row, 0]
        for k, name in enumerate(spec.joints):
            axis.plot(t, joints[:, row, k], lw=0.8, label=name)
        axis.set_ylabel(f"{leg} [rad]")
        # beside the plot, not on the curves
        axis.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5), frameon=False)
    axes_grid[-1, 0].set_xlabel("time [s]")
    figure.suptitle(f"{title}: commanded joint positions")
    _tight(figure)
    figure.savefig(folder / "joints.png")


def plot_simulation(robot: Robot, series: dict[str, list[Any]], folder: Path, gait: str | None = None) -> None:
    """trajectory.png (body path, top view), power.png (total electrical power) and contacts.png (feet off the
    ground over time: the measured gait diagram, drawn like the planned one) in ``folder``; ``gait`` names the
    run's gait in the titles (default: the robot's)."""
    import numpy as np

    t = np.array(series["t"])
    position = np.array(series["position"])
    title = run_title(robot, gait)
    paths = {"ground truth": position[:, :2]}
    points = None
    if series.get("yaw") is not None:
        heading = float(np.array(series["yaw"])[0])
        if series.get("odometry") is not None:
            paths["leg odometry"] = odometry_in_world(np.array(series["odometry"]), position[0, :2], heading)
        planned = planned_path(folder)  # a --path run keeps its path file: drawn where the odom frame is
        if planned is not None:
            paths["planned path"] = odometry_in_world(planned, position[0, :2], heading)
            points = {"waypoints": paths["planned path"][1:]}
    plot_trajectory(paths, folder / "trajectory.png", f"{title}: body trajectory", points)

    running = np.array(series["running"], dtype=bool) if "running" in series else np.ones(len(t), dtype=bool)
    _power_plot(t, np.array(series["power"], dtype=float), running, robot.time_delta, f"{title}: total servo power",
                folder / "power.png")

    contact = np.array(series["contact"], dtype=bool)
    startup = ~running if "running" in series else None
    _leg_bars(list(robot.legs), t, robot.time_delta, ~contact, f"{title}: gait diagram (measured foot contacts)",
              folder / "contacts.png", startup, off_label="foot off the ground")


def planned_path(folder: Path) -> Any:
    """The planned path of a ``--path`` run in ``folder`` (its ``path.csv`` or ``path.toml``): the start (0, 0) and
    every waypoint ``(K + 1, 2)`` in the odom frame [m]; ``None`` for a run without one."""
    import numpy as np

    from shc_cli.spec.path import load_path

    for name in ("path.csv", "path.toml"):
        if (folder / name).is_file():
            waypoints = load_path(folder / name).waypoints
            return np.array([(0.0, 0.0), *((w.x, w.y) for w in waypoints)])
    return None


def odometry_in_world(odometry: Any, origin: Any, heading: float) -> Any:
    """Odometry positions ``(N, 2)`` of poses ``(N, 3)`` in the odom frame, placed in the world at the body's start
    position ``origin`` (x, y) [m] and heading [rad]."""
    import numpy as np

    c, s = math.cos(heading), math.sin(heading)
    x, y = odometry[:, 0], odometry[:, 1]
    return np.column_stack([origin[0] + c * x - s * y, origin[1] + s * x + c * y])


TRAJECTORY_STYLES: dict[str, dict[str, Any]] = {
    "ground truth": {"lw": 1.2, "color": "C0"},
    "leg odometry": {"lw": 1.0, "ls": "--", "color": "C1"},
    "planned path": {"lw": 0.8, "ls": ":", "color": "k"},
}
"""Line styles of :func:`plot_trajectory` by path name; other names get matplotlib's next colour."""


def plot_trajectory(paths: dict[str, Any], path: Path, title: str,
                    points: dict[str, Any] | None = None) -> Path:
    """``trajectory.png``: a top view of planar paths in one frame — the ground truth, the leg odometry and any
    other (a planned path) — each a ``(N, 2)`` array [m] by name, with the start (circle) and end (square) of
    the first; ``points`` adds named sets of marked points ``(K, 2)`` (waypoints). Returns ``path``."""
    import numpy as np

    figure, axes = _subplots(figsize=(6, 5), dpi=110)
    for name, xy in paths.items():
        xy = np.asarray(xy, dtype=float)
        if len(xy):
            axes.plot(xy[:, 0], xy[:, 1], label=name, **TRAJECTORY_STYLES.get(name, {"lw": 1.0}))
    first = np.asarray(next(iter(paths.values())), dtype=float) if paths else np.zeros((0, 2))
    if len(first):
        axes.plot(first[0, 0], first[0, 1], "go", label="start")
        axes.plot(first[-1, 0], first[-1, 1], "rs", label="end")
    for name, xy in (points or {}).items():
        xy = np.asarray(xy, dtype=float)
        axes.plot(xy[:, 0], xy[:, 1], "kx", ms=7, label=name)
    axes.set_aspect("equal", adjustable="datalim")
    axes.set_xlabel("x [m]")
    axes.set_ylabel("y [m]")
    axes.set_title(title, fontsize=10)
    axes.grid(True, lw=0.3)
    axes.legend(fontsize=8)
    _tight(figure)
    _save(figure, path)
    return path


def _power_plot(t: Any, power: Any, running: Any, dt: float, title: str, path: Path) -> None:
    """power.png: the total power over time with the start-up shaded, the analysed window (the RUNNING cycles, what
    the summary's mean power and CoT use) marked by its mean, and the axis scaled to that window — a start-up peak
    several times higher is clipped and named instead of flattening the walk."""
    import numpy as np
    from matplotlib.patches import Patch

    figure, axes = _subplots(figsize=(8, 3.5), dpi=110)
    for a, b in _intervals(~running):
        axes.axvspan(t[a], t[a] + (b - a + 1) * dt, color=STARTUP_COLOUR, lw=0, zorder=0)
    axes.plot(t, power, lw=0.8, zorder=2)
    handles: list[Any] = [Patch(facecolor=STARTUP_COLOUR, label="start-up")] if (~running).any() else []
    if running.any():
        window = power[running]
        mean = float(window.mean())
        rows = np.flatnonzero(running)
        handles.append(axes.hlines(mean, t[rows[0]], t[rows[-1]], colors="tab:red", lw=1.2, zorder=3,
                                   label=f"analysed window: mean {mean:.1f} W"))
        top = float(np.nanmax(window))
        if float(np.nanmax(power)) > 1.5 * top > 0.0:
            axes.set_ylim(min(0.0, float(np.nanmin(window))), 1.25 * top)
            axes.text(0.01, 0.97, f"start-up peak {float(np.nanmax(power)):.0f} W off the scale",
                      transform=axes.transAxes, fontsize=7, va="top")
    axes.set_xlabel("time [s]")
    axes.set_ylabel("electrical power [W]")
    axes.set_title(title)
    axes.grid(True, lw=0.3)
    if handles:
        axes.legend(handles=handles, fontsize=7, loc="lower right")
    _tight(figure)
    figure.savefig(path)


def _intervals(flags: Any) -> list[tuple[int, int]]:
    """(first, last) index of every run of True in a 1-D boolean array."""
    import numpy as np

    on = np.asarray(flags).astype(int)
    starts = np.flatnonzero(np.diff(np.concatenate([[0], on])) == 1)
    ends = np.flatnonzero(np.diff(np.concatenate([on, [0]])) == -1)
    return [(int(a), int(b)) for a, b in zip(starts, ends, strict=True)]


def _leg_bars(legs: list[str], t: Any, dt: float, swing: Any, title: str, path: Path, startup: Any = None,
              off_label: str = "swing") -> None:
    """A gait diagram (paper Fig. 5): one row per leg, black where ``swing[:, leg]`` is set, white in stance, the
    start-up (``startup``, cycles before RUNNING) shaded grey; cycles at times ``t`` [s], ``dt`` apart. ``off_label``
    names the black bars: a planned swing, or a measured foot off the ground (which need not be a swing: a foot
    hanging over a ramp's edge is off the ground for seconds)."""
    from matplotlib.patches import Patch

    figure, axes = _subplots(figsize=(9, 0.45 * len(legs) + 1.4), dpi=110)
    if startup is not None:
        for a, b in _intervals(startup):
            axes.axvspan(t[a], t[a] + (b - a + 1) * dt, color=STARTUP_COLOUR, lw=0, zorder=0)
    for row in range(len(legs)):
        axes.broken_barh([(t[a], (b - a + 1) * dt) for a, b in _intervals(swing[:, row])],
                         (row - 0.4, 0.8), facecolors=SWING_COLOUR, zorder=2)
    axes.set_yticks(range(len(legs)), legs)
    axes.invert_yaxis()
    axes.set_xlabel("time [s]")
    axes.set_title(title)
    handles = [Patch(facecolor=SWING_COLOUR, label=off_label),
               Patch(facecolor=STANCE_COLOUR, edgecolor="0.5",
                     label="stance" if off_label == "swing" else "foot on the ground")]
    if startup is not None and startup.any():
        handles.append(Patch(facecolor=STARTUP_COLOUR, label="start-up"))
    axes.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncols=len(handles), fontsize=7,
                frameon=False)
    _tight(figure)
    figure.savefig(path)


def _save(figure: Any, path: Path) -> None:
    """Save a figure atomically (complete or absent)."""
    from shc_cli.outputs import atomic_path

    with atomic_path(path) as temporary:
        figure.savefig(temporary, format=path.suffix.lstrip("."))


def _finish_time_plot(figure: Any, axes: Any, ylabel: str, path: Path, title: str) -> Path:
    """Title and label a plot over time, add its grid and legend, save it atomically; returns ``path``."""
    axes.set_title(title, fontsize=10)
    axes.set_xlabel("time [s]")
    axes.set_ylabel(ylabel)
    axes.grid(True, lw=0.3)
    axes.legend(fontsize=7)
    _tight(figure)
    _save(figure, path)
    return path


def _label(result: dict[str, Any]) -> str:
    return Path(str(result["run"])).name


def _robots_and_gaits(results: list[dict[str, Any]]) -> str:
    """``robot / gait`` of every run, each once, in order (for the titles of plots over several runs)."""
    names = [" / ".join(str(x) for x in (r.get("robot"), r.get("gait")) if x) for r in results]
    return ", ".join(dict.fromkeys(n for n in names if n))


def plot_analysis(results: list[dict[str, Any]], runs: list[Any], folder: Path) -> list[Path]:
    """The ``shc analyze --out`` plots; returns the files written.

    * ``power.png`` — total electrical power over time, one line per run (runs with power only);
    * ``cycles.png`` — boxplots of the per-gait-cycle RMS of body height, roll rate and pitch rate, one box per run
      (ATHENA Fig. 10 style);
    * ``stability.png`` — static (CoM) and ZMP margins to the support polygon over time;
    * ``zmp_<run>.png`` — the ZMP (ATHENA eq. 32) and the centre of mass over the support polygons, top view;
    * ``trajectory.png`` (``trajectory_<run>.png`` for several runs) — ground truth and leg odometry in the odom
      frame of the window (:func:`plot_trajectory`), runs with both;
    * ``cot.png`` — cost of transport and speed vs step frequency, one line per robot / gait / velocity input
      (OpenSHC paper Fig. 14–16 style), when the runs differ in step frequency.
    """
    import numpy as np

    written: list[Path] = []
    powered = [(r, run) for r, run in zip(results, runs, strict=True) if run.power is not None]
    if powered:
        figure, axes = _subplots(figsize=(8, 3.5), dpi=110)
        for result, run in powered:
            axes.plot(run.t, run.power, lw=0.7, label=_label(result))
        written.append(_finish_time_plot(figure, axes, "electrical power [W]", folder / "power.png",
                                         f"{_robots_and_gaits([r for r, _ in powered])}: total servo power"))

    figure, axes = _subplots(1, 3, figsize=(10, 3.6), dpi=110)
    names = [_label(r) for r in results]
    for ax, (key, unit) in zip(axes, (("height", "m"), ("roll_rate", "rad/s"), ("pitch_rate", "rad/s")),
                               strict=True):
        data = [r["_series"]["cycles"][key] if "_series" in r else np.zeros(0) for r in results]
        if any(len(d) for d in data):
            ax.boxplot([d if len(d) else [np.nan] for d in data])
            ax.set_xticks(range(1, len(names) + 1), names, rotation=30, ha="right", fontsize=7)
        ax.set_title(f"RMS {key.replace('_', ' ')} per gait cycle [{unit}]", fontsize=9)
        ax.grid(True, axis="y", lw=0.3)
    figure.suptitle(f"{_robots_and_gaits(results)}: posture per gait cycle", fontsize=10)
    _tight(figure)
    _save(figure, folder / "cycles.png")
    written.append(folder / "cycles.png")

    for result in results:
        series = result.get("_series")
        if series is None or not np.isfinite(series["margin"]).any():
            continue
        feet, contact, com, zmp = series["feet"], series["contact"], series["com"], series["zmp"]
        from shc_cli.analysis.metrics import support_polygon

        figure, axes = _subplots(figsize=(7, 5), dpi=110)
        step = max(1, len(feet) // 60)  # about 60 polygons
        for i in range(0, len(feet), step):
            polygon = support_polygon(feet[i, contact[i], :2])
            if len(polygon) >= 3:
                closed = np.vstack([polygon, polygon[:1]])
                axes.plot(closed[:, 0], closed[:, 1], color="0.75", lw=0.5)
        if np.isfinite(zmp).any():  # dots, not a line: the ZMP jumps between feet as contacts change
            axes.plot(zmp[:, 0], zmp[:, 1], ".", ms=3.0, alpha=0.5, color="tab:orange", mew=0,
                      label="ZMP (eq. 32), one dot per cycle")
        axes.plot(com[:, 0], com[:, 1], lw=1.4, color="black", zorder=3, label="centre of mass")
        axes.set_aspect("equal", adjustable="datalim")
        axes.set_xlabel("x [m]")
        axes.set_ylabel("y [m]")
        axes.set_title(f"{_label(result)} ({_robots_and_gaits([result])}): ZMP and CoM over the support polygons",
                       fontsize=9)
        axes.legend(fontsize=7, markerscale=3.0)
        _tight(figure)
        path = folder / f"zmp_{_label(result)}.png"
        _save(figure, path)
        written.append(path)

    margined = [(r, run) for r, run in zip(results, runs, strict=True)
                if "_series" in r and np.isfinite(r["_series"]["margin"]).any()]
    if margined:
        figure, axes = _subplots(figsize=(8, 3.5), dpi=110)
        for result, run in margined:
            series = result["_series"]
            t = run.t[series["rows"]]
            few = series["contact"].sum(axis=1) < 3  # a point or a segment of feet: no polygon to have a margin to
            line = axes.plot(t, np.where(few, np.nan, series["margin"]), lw=0.7, label=f"{_label(result)}: CoM")[0]
            if np.isfinite(series["zmp_margin"]).any():
                axes.plot(t, np.where(few, np.nan, series["zmp_margin"]), lw=0.5, ls="--", color=line.get_color(),
                          label=f"{_label(result)}: ZMP")
            if few.any():
                axes.fill_between(t, 0.0, 1.0, where=few, step="mid", transform=axes.get_xaxis_transform(),
                                  color=line.get_color(), alpha=0.15, lw=0,
                                  label=f"{_label(result)}: fewer than 3 feet in contact ({100 * few.mean():.0f} % "
                                        "of the window; margins not drawn)")
        axes.axhline(0.0, color="0.3", lw=0.6)
        written.append(_finish_time_plot(figure, axes, "margin to the support polygon [m]",
                                         folder / "stability.png", f"{_robots_and_gaits([r for r, _ in margined])}: "
                                         "static (CoM) and ZMP stability margins"))

    for result in results:
        found = result.get("_series", {}).get("tracks")
        if found is None:
            continue
        name = "trajectory.png" if len(results) == 1 else f"trajectory_{_label(result)}.png"
        drift = result.get("odometry_drift_percent")
        note = f" (drift {drift:.2f} %)" if drift is not None else ""
        paths = {"ground truth": found.truth[:, :2], "leg odometry": found.odometry[:, :2]}
        planned = planned_path(Path(str(result["run"])))
        if planned is not None:
            paths["planned path"] = planned
        marks = {"waypoints": planned[1:]} if planned is not None else None
        written.append(plot_trajectory(paths, folder / name, f"{_label(result)} ({_robots_and_gaits([result])}): "
                                       f"odom frame{note}", marks))

    placed = [{**r, "terrain": r.get("terrain") or run.summary.terrain}
              for r, run in zip(results, runs, strict=True)]
    if any(len({p[0] for p in points}) > 1 for points in cot_lines(placed).values()):  # a setting at several
        written.append(plot_cot(placed, folder / "cot.png"))  # step frequencies: else the lines mean nothing
    return written


def cot_lines(results: list[dict[str, Any]]) -> dict[str, list[tuple[float, float | None, float | None]]]:
    """(step frequency, CoT, speed) per line of :func:`plot_cot`: one line per robot, gait, terrain and group (a
    sweep's other grid values, else the velocity input) — runs of different robots or terrains are never joined
    into one CoT-vs-frequency line."""
    lines: dict[str, list[tuple[float, float | None, float | None]]] = {}
    for r in results:
        label = " / ".join(str(x) for x in (r.get("robot"), r.get("gait"), r.get("terrain"), r.get("group") or "")
                           if x) or "runs"
        speed = r.get("displacement_speed_mps", r.get("mean_speed_mps"))
        lines.setdefault(label, []).append((float(r["step_frequency_hz"]), r.get("cot"), speed))
    return lines


def plot_cot(results: list[dict[str, Any]], path: Path) -> Path:
    """CoT and mean speed vs step frequency, one line per (robot, gait, group) — OpenSHC paper Fig. 14–16 style.

    A result's group is its ``group`` entry (a sweep's stride share, say) if present, else its velocity input.
    """
    import textwrap

    lines = cot_lines(results)
    figure, (top, bottom) = _subplots(2, 1, figsize=(7, 6.5), dpi=110, sharex=True)
    for label, points in sorted(lines.items()):
        points.sort()
        style = "o-" if len({p[0] for p in points}) > 1 else "o"  # a single frequency is a point, not a line
        top.plot([p[0] for p in points if p[1] is not None], [p[1] for p in points if p[1] is not None], style,
                 ms=3, lw=1.0, label=label)
        bottom.plot([p[0] for p in points if p[2] is not None], [p[2] for p in points if p[2] is not None], style,
                    ms=3, lw=1.0, label=label)
    top.set_ylabel("CoT (eq. 22)")
    top.grid(True, lw=0.3)
    if top.get_legend_handles_labels()[0]:
        top.legend(fontsize=6, ncol=2)
    title = f"{_robots_and_gaits(results) or 'runs'}: cost of transport and speed vs step frequency"
    top.set_title(textwrap.fill(title, 80), fontsize=9)
    bottom.set_ylabel("displacement speed [m/s]")
    bottom.set_xlabel("step frequency [Hz]")
    bottom.grid(True, lw=0.3)
    _tight(figure)
    _save(figure, path)
    return path
