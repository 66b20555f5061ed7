"""Plot conventions: one gait-diagram convention (paper Fig. 5: swing black, stance white) in plan and simulate,
the robot and gait in every title, legends beside the joint curves rather than on them."""

from __future__ import annotations

import csv
import re
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from shc_cli.plots import SWING_COLOUR, plot_simulation
from shc_cli.spec.robot import Robot

from .test_cli import run


@pytest.fixture
def figures(monkeypatch: pytest.MonkeyPatch) -> dict[str, Any]:
    """Every figure saved during the test, by file name (its artists inspected instead of its pixels)."""
    from matplotlib.figure import Figure

    saved: dict[str, Any] = {}
    original = Figure.savefig

    def record(self: Figure, fname: Any, *args: Any, **kwargs: Any) -> None:
        name = re.sub(r"^\.(.+)\.[^.]+\.partial\.[^.]+$", r"\1", Path(str(fname)).name)  # atomic saves' temporaries
        saved[name] = self
        original(self, fname, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", record)
    return saved


def _titles(figure: Any) -> str:
    texts = [axis.get_title() for axis in figure.axes]
    if figure._suptitle is not None:
        texts.append(figure._suptitle.get_text())
    return " | ".join(texts)


def _black_bars(figure: Any, row: int) -> list[tuple[float, float]]:
    """(start, end) [s] of the black bars in row ``row`` of a gait diagram."""
    from matplotlib.colors import to_rgba

    axis = figure.axes[0]
    bars = []
    for collection in axis.collections:
        if not np.allclose(collection.get_facecolor()[0], to_rgba(SWING_COLOUR)):
            continue
        for path in collection.get_paths():
            xs, ys = path.vertices[:, 0], path.vertices[:, 1]
            if abs(ys.mean() - row) < 0.41:
                bars.append((float(xs.min()), float(xs.max())))
    return sorted(bars)


def _runs(flags: np.ndarray, t: np.ndarray, dt: float) -> list[tuple[float, float]]:
    edges = np.diff(np.concatenate([[0], flags.astype(int), [0]]))
    return [(float(t[a]), float(t[b - 1] + dt)) for a, b in zip(np.flatnonzero(edges == 1),
                                                                   np.flatnonzero(edges == -1), strict=True)]


def test_plan_plots_have_titles_black_swing_and_legends_off_the_curves(tmp_path: Path, figures: dict[str, Any],
                                                                       capsys: pytest.CaptureFixture[str],
                                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "plan"
    code, _, err = run(["plan", "bullet", "--gait", "wave", "--duration", "4", "--out", str(out)], capsys,
                       monkeypatch)
    assert code == 0, err
    for name in ("gait.png", "tips.png", "joints.png"):
        assert "bullet / wave" in _titles(figures[name]), name
    # the black bars of leg AR are exactly its swing phases in tips.csv
    with (out / "tips.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    t = np.array([float(r["t"]) for r in rows])
    swing = np.array([float(r["AR_swing_progress"]) >= 0.0 for r in rows])
    assert swing.any()
    np.testing.assert_allclose(_black_bars(figures["gait.png"], 0), _runs(swing, t, 0.01), atol=1e-9)
    # joints.png: every legend lies outside its axes (beside the curves, not on them)
    figure = figures["joints.png"]
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    renderer = FigureCanvasAgg(figure).get_renderer()  # type: ignore[no-untyped-call]
    for axis in figure.axes:
        legend = axis.get_legend()
        assert legend is not None
        box, frame = legend.get_window_extent(renderer), axis.get_window_extent(renderer)
        assert box.x0 >= frame.x1 - 1.0


def test_measured_contacts_use_the_same_convention(tmp_path: Path, figures: dict[str, Any]) -> None:
    from shc_cli.spec.loading import load_robot

    bullet = load_robot("bullet").robot
    assert bullet is not None
    n = 200
    t = np.arange(n) * bullet.time_delta
    contact = np.ones((n, len(bullet.legs)), dtype=bool)
    contact[50:80, 0] = False  # leg AR lifted from 0.5 s to 0.8 s
    contact[120:150, 0] = False
    series = {"t": list(t), "position": [np.array([0.01 * i, 0.0, 0.2]) for i in range(n)], "power": [100.0] * n,
              "contact": list(contact), "running": [i >= 20 for i in range(n)]}
    plot_simulation(bullet, series, tmp_path, gait="tripod")
    np.testing.assert_allclose(_black_bars(figures["contacts.png"], 0), [(0.5, 0.8), (1.2, 1.5)], atol=1e-9)
    assert _black_bars(figures["contacts.png"], 1) == []  # always on the ground: all white
    for name in ("contacts.png", "trajectory.png", "power.png"):
        assert "bullet / tripod" in _titles(figures[name]), name


def test_analyze_plots_are_titled_with_robot_and_gait(tmp_path: Path, figures: dict[str, Any],
                                                      capsys: pytest.CaptureFixture[str],
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from shc_cli.plots import plot_cot

    results = [{"run": f"r{f}", "robot": "bullet", "gait": "tripod", "step_frequency_hz": f, "cot": 3.0 / f,
                "displacement_speed_mps": 0.1 * f} for f in (0.5, 1.0, 1.5)]
    plot_cot(results, tmp_path / "cot.png")
    assert "bullet / tripod" in _titles(figures["cot.png"])
    plan = tmp_path / "plan"
    assert run(["plan", "bullet", "--duration", "3", "--out", str(plan), "--no-plots"], capsys, monkeypatch)[0] == 0
    code, _, err = run(["analyze", str(plan), "--out", str(tmp_path / "an")], capsys, monkeypatch)
    assert code == 0, err
    for name in ("stability.png", "cycles.png"):
        assert "bullet / tripod" in _titles(figures[name]), name


def _legend_texts(figure: Any) -> list[str]:
    return [text.get_text() for axis in figure.axes if axis.get_legend() for text in axis.get_legend().get_texts()]


def _simulated_series(robot: Robot, n: int = 300, startup: int = 100, peak: float = 600.0) -> dict[str, Any]:
    t = np.arange(n) * robot.time_delta
    contact = np.ones((n, len(robot.legs)), dtype=bool)
    contact[150:200, 1] = False
    power = [peak if i == 10 else (80.0 if i < startup else 120.0) for i in range(n)]
    return {"t": list(t), "position": [np.array([0.01 * i, 0.0, 0.2]) for i in range(n)], "power": power,
            "contact": list(contact), "running": [i >= startup for i in range(n)]}


def test_power_marks_start_up_and_the_analysed_window_and_contacts_say_off_the_ground(
        tmp_path: Path, figures: dict[str, Any], bullet: Robot) -> None:
    """power.png: the analysed window's mean (what the summary prints) is drawn and named, a start-up peak five
    times higher does not set the axis; contacts.png calls a foot off the ground that, not a swing (issue 26)."""
    plot_simulation(bullet, _simulated_series(bullet), tmp_path, gait="tripod")
    power = figures["power.png"]
    assert "analysed window: mean 120.0 W" in _legend_texts(power) and "start-up" in _legend_texts(power)
    assert power.axes[0].get_ylim()[1] == pytest.approx(150.0)
    assert any("start-up peak 600 W off the scale" in text.get_text() for text in power.axes[0].texts)
    labels = _legend_texts(figures["contacts.png"])
    assert "foot off the ground" in labels and "swing" not in labels


def test_cot_lines_never_join_different_robots_or_terrains(tmp_path: Path, figures: dict[str, Any]) -> None:
    """Two runs of different robots on different terrains at different step frequencies are two points, not a
    CoT-vs-frequency line; a sweep without robot or gait in its grid plots without matplotlib's "No artists with
    labels" warning, and a long title is wrapped, not cut."""
    import warnings

    from shc_cli.plots import cot_lines, plot_cot

    results = [{"robot": "bullet", "gait": "tripod", "terrain": "flat", "step_frequency_hz": 1.0, "cot": 6.0,
                "displacement_speed_mps": 0.2},
               {"robot": "athena", "gait": "tripod", "terrain": "ramp:10", "step_frequency_hz": 1.5, "cot": 9.0,
                "displacement_speed_mps": 0.1}]
    assert all(len(points) == 1 for points in cot_lines(results).values()) and len(cot_lines(results)) == 2
    plain = [{"step_frequency_hz": f, "cot": 5.0 + f, "displacement_speed_mps": 0.1 * f} for f in (0.8, 1.2)]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        plot_cot(plain, tmp_path / "cot.png")
    many = [{**plain[0], "robot": f"robot_with_a_long_name_{k}", "gait": "tripod"} for k in range(4)]
    plot_cot(many, tmp_path / "many.png")
    title = figures["many.png"].axes[0].get_title()
    assert "\n" in title and all(len(line) <= 80 for line in title.splitlines())


def test_pareto_projection_of_three_objectives_draws_no_front_line(tmp_path: Path, figures: dict[str, Any]) -> None:
    """A 3-objective front seen in two of them is points, not a line; the trials non-dominated in the plotted two
    are named separately (a front trial worst in both plotted objectives was drawn 'on the front')."""
    from shc_cli.domain.optimize.plots import _front_2d, plot_pareto_pairs
    from shc_cli.spec.study import Study

    study = Study(path=tmp_path / "s.toml", name="s", description="", robot="bullet", engine="mujoco", seeds=(0,),
                  skip=0.0, trials=None, fixed={}, space=[],
                  objectives={"cot": "minimize", "mean_speed_mps": "maximize", "stability_margin_median_m": "maximize"},
                  constraints=[], sampler="nsga2", sampler_seed=1, population=None)
    front = [{"trial": n, "state": "complete", "feasible": True, "cot": c, "mean_speed_mps": v,
              "stability_margin_median_m": m} for n, (c, v, m) in enumerate([(3.0, 0.5, 0.01), (5.0, 0.3, 0.1),
                                                                             (6.0, 0.2, 0.2)])]
    assert [p[2] for p in _front_2d([(3.0, 0.5, 0), (5.0, 0.3, 1), (6.0, 0.2, 2)], "minimize", "maximize")] == [0]
    plot_pareto_pairs(study, front, front, tmp_path)
    labels = _legend_texts(figures["pareto_cot__mean_speed_mps.png"])
    assert any("on the 3-objective Pareto front" in label for label in labels)
    assert "non-dominated in cot and mean_speed_mps (1)" in labels


def _inside_figure(figure: Any, text: Any) -> bool:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas: Any = FigureCanvasAgg(figure)  # a closed pyplot figure keeps only a base canvas
    canvas.draw()
    box = text.get_window_extent(renderer=canvas.get_renderer())
    return bool(box.x0 >= 0.0 and box.x1 <= figure.bbox.width and box.y1 <= figure.bbox.height)


def test_a_long_pareto_title_is_wrapped_inside_the_figure(tmp_path: Path, figures: dict[str, Any]) -> None:
    """Issue 42 point 14: "bullet_flat: stability_margin_median_m vs displacement_speed_mps, 40 complete trials" was
    cut at both edges of the figure."""
    from shc_cli.domain.optimize.plots import plot_parallel, plot_pareto_pairs
    from shc_cli.spec.study import Study

    study = Study(path=tmp_path / "s.toml", name="bullet_flat", description="", robot="bullet", engine="mujoco",
                  seeds=(0,), skip=0.0, trials=None, fixed={}, space=[],
                  objectives={"displacement_speed_mps": "maximize", "stability_margin_median_m": "maximize"},
                  constraints=[], sampler="nsga2", sampler_seed=1, population=None)
    rows = [{"trial": n, "state": "complete", "feasible": True, "displacement_speed_mps": 0.1 * n,
             "stability_margin_median_m": 0.2 - 0.01 * n} for n in range(40)]
    plot_pareto_pairs(study, rows, rows[:3], tmp_path)
    plot_parallel(study, rows, rows[:3], tmp_path / "parallel.png")
    for name in ("pareto_displacement_speed_mps__stability_margin_median_m.png", "parallel.png"):
        axes = figures[name].axes[0]
        assert "40 complete trials" in axes.get_title().replace("\n", " ") or name == "parallel.png"
        assert _inside_figure(figures[name], axes.title), f"{name}: {axes.get_title()!r} is cut"


def _walk_series(n: int = 200) -> tuple[list[dict[str, Any]], list[Any]]:
    """An analysed run by hand: a tripod whose measured contacts drop to one foot for 20 cycles (a stance foot
    chattering at a transition), with the CoM and ZMP a margin inside the feet otherwise."""
    from types import SimpleNamespace

    t = np.arange(n) * 0.01
    feet = np.zeros((n, 6, 3))
    feet[:, :, 0] = np.array([0.3, 0.0, -0.3, -0.3, 0.0, 0.3]) + 0.001 * np.arange(n)[:, None]
    feet[:, :, 1] = np.array([-0.2, -0.3, -0.2, 0.2, 0.3, 0.2])
    contact = np.tile(np.array([True, False, True, False, True, False]), (n, 1))
    contact[100:120] = [True, False, False, False, False, False]
    com = np.column_stack([0.001 * np.arange(n), np.zeros(n), np.full(n, 0.2)])
    margin = np.where(contact.sum(axis=1) < 3, -0.33, 0.1)
    series = {"rows": np.arange(n), "margin": margin, "zmp": com[:, :2] + 0.01, "zmp_margin": margin - 0.01,
              "feet": feet, "com": com, "contact": contact, "tracks": None,
              "cycles": {"height": np.zeros(0), "roll_rate": np.zeros(0), "pitch_rate": np.zeros(0)}}
    result = {"run": "walk", "robot": "athena", "gait": "tripod", "step_frequency_hz": 1.0, "_series": series}
    return [result], [SimpleNamespace(t=t, power=None, summary=SimpleNamespace(terrain="flat"))]


def test_margins_are_not_drawn_where_fewer_than_three_feet_touch(tmp_path: Path, figures: dict[str, Any]) -> None:
    """Issue 42 point 14: ATHENA's stability plot showed CoM margin spikes of −0.33 m on a run that did not fall —
    the samples where the contact sensors had one or two feet down (a point or a segment: no support polygon, the
    margin is minus the distance to it). They are shaded and named instead."""
    from shc_cli.plots import plot_analysis

    results, runs = _walk_series()
    plot_analysis(results, runs, tmp_path)
    axes = figures["stability.png"].axes[0]
    com = next(line for line in axes.get_lines() if line.get_label() == "walk: CoM")
    drawn = com.get_ydata()
    assert np.isnan(drawn[100:120]).all() and np.nanmin(drawn) == pytest.approx(0.1)
    assert axes.get_ylim()[0] > -0.1  # the −0.33 m samples do not set the axis
    assert "walk: fewer than 3 feet in contact (10 % of the window; margins not drawn)" in _legend_texts(
        figures["stability.png"])


def test_the_centre_of_mass_is_drawn_over_the_zmp(tmp_path: Path, figures: dict[str, Any]) -> None:
    """The ZMP plot's "centre of mass" line was invisible under the ZMP's line: the ZMP is dots, the CoM a black
    line on top."""
    from matplotlib.colors import to_rgba

    from shc_cli.plots import plot_analysis

    results, runs = _walk_series()
    plot_analysis(results, runs, tmp_path)
    lines = {line.get_label(): line for line in figures["zmp_walk.png"].axes[0].get_lines()}
    com, zmp = lines["centre of mass"], lines["ZMP (eq. 32), one dot per cycle"]
    assert com.get_zorder() > zmp.get_zorder() and to_rgba(com.get_color()) == to_rgba("black")
    assert zmp.get_linestyle() == "None" and zmp.get_marker() == "."


def test_fits_joint_grids_say_their_time_axis(tmp_path: Path, figures: dict[str, Any]) -> None:
    """Issue 42 point 14: fit's position and torque grids (one panel per joint) had no time label; the bottom panel
    of every column shows the times (the one above an empty cell too)."""
    from types import SimpleNamespace

    from shc_cli.domain.fit.outputs import plot_fit

    n, joints = 50, 7  # two rows of five: columns 3–5 end above an empty cell
    wave = np.sin(np.linspace(0.0, 3.0, n))[:, None] * np.ones((1, joints))
    recording = SimpleNamespace(position=wave, torque=wave, current=None, power=None, dt=0.01,
                                path=tmp_path / "run")
    simulated = SimpleNamespace(channel=lambda _: wave * 0.9, power=np.full(n, 10.0))
    plot_fit(recording, simulated, simulated, [f"j{k}" for k in range(joints)], tmp_path,  # type: ignore[arg-type]
             "01_run")
    for name in ("01_run_position.png", "01_run_torque.png"):
        figure = figures[name]
        assert figure._supxlabel is not None and figure._supxlabel.get_text() == "time [s]", name
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(figure).draw()  # type: ignore[no-untyped-call,unused-ignore]
        shown = [axis for axis in figure.axes if axis.axison and any(
            label.get_visible() and label.get_text() for label in axis.get_xticklabels())]
        assert len(shown) == 5, name  # one per column: j5, j6 in row 2 and j2, j3, j4 above the empty cells
        assert _inside_figure(figure, figure._supxlabel), name
