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
                                                                       capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
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

    renderer = FigureCanvasAgg(figure).get_renderer()
    for axis in figure.axes:
        legend = axis.get_legend()
        assert legend is not None
        box, frame = legend.get_window_extent(renderer), axis.get_window_extent(renderer)
        assert box.x0 >= frame.x1 - 1.0


def test_measured_contacts_use_the_same_convention(tmp_path: Path, figures: dict[str, Any], bullet: Robot) -> None:
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


def test_analyze_plots_are_titled_with_robot_and_gait(tmp_path: Path, figures: dict[str, Any], capsys,
                                                      monkeypatch) -> None:  # type: ignore[no-untyped-def]
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
