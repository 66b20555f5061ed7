"""Logging: every run directory has an ``events.log`` (JSON lines: state changes, falls, faults, warnings, stop
requests), ``shc --verbose`` / ``--quiet`` choose what stderr shows, and ``shc view`` tells a closed tab from a bug."""

from __future__ import annotations

import json
import logging
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from .test_cli import run


def _events(directory: Path) -> list[dict[str, object]]:
    lines = (directory / "events.log").read_text(encoding="utf-8").splitlines()
    events = [json.loads(line) for line in lines]
    for entry in events:
        assert set(entry) == {"time", "cycle", "level", "event", "message"}, entry
    return events


def test_a_plan_logs_its_state_changes(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                       monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "plan"
    code, _, err = run(["--verbose", "plan", "bullet", "--duration", "1", "--no-plots", "--out", str(out)], capsys,
                       monkeypatch)
    assert code == 0
    events = _events(out)
    robot = [str(e["message"]) for e in events if e["event"] == "robot_state"]
    assert robot[0] == "robot state: PACKED" and robot[-1].endswith("→ RUNNING")
    walk = [(e["cycle"], e["message"]) for e in events if e["event"] == "walk_state"]
    assert ("walk state: STOPPED → STARTING" in [m for _, m in walk]) and all(isinstance(c, int) for c, _ in walk)
    summary = json.loads((out / "summary.json").read_text())
    assert events[-1]["event"] == "stopped" and events[-1]["cycle"] == summary["cycles"]
    assert [e["event"] for e in events].count("stop_requested") == 1  # the input is over
    assert "robot state: PACKED → READY" in err  # --verbose: the info events on stderr too
    code, _, err = run(["plan", "bullet", "--duration", "1", "--no-plots", "--out", str(tmp_path / "quiet")], capsys,
                       monkeypatch)
    assert code == 0 and "robot state" not in err and _events(tmp_path / "quiet")  # on file, not on the terminal


def test_terminal_levels_and_terminal_false(capsys: pytest.CaptureFixture[str]) -> None:
    from shc_cli.events import NOTICE, configure_terminal, event

    log = logging.getLogger("shc_cli.test")
    try:
        configure_terminal("normal")
        log.info("an info")
        event(log, NOTICE, "input", "a notice")
        event(log, logging.WARNING, "fell", "reported by the command", terminal=False)
        log.warning("a warning")
        assert capsys.readouterr().err.splitlines() == ["a notice", "a warning"]
        configure_terminal("quiet")
        log.warning("a warning")
        log.error("an error")
        assert capsys.readouterr().err.splitlines() == ["an error"]
        configure_terminal("verbose")
        log.info("an info")
        assert capsys.readouterr().err.splitlines() == ["an info"]
    finally:
        configure_terminal("normal")


def test_events_reach_the_file_with_the_loop_cycle(tmp_path: Path) -> None:
    """A record without a cycle (an input thread's warning) gets the loop's cycle of the moment."""
    from shc_cli.events import recording

    log = logging.getLogger("shc_cli.loop.input_sources")
    with recording(tmp_path, lambda: 42):
        log.warning("warning: stdin: ignored line 'x'")
    logging.getLogger("shc_cli").warning("after the run: not recorded")
    [entry] = _events(tmp_path)
    assert entry["cycle"] == 42 and entry["level"] == "warning" and entry["event"] == "shc_cli.loop.input_sources"


def test_a_fall_is_an_event(tmp_path: Path) -> None:
    """The fall check's event names the tilt and height (the summary line says FELL; stderr does not repeat it)."""
    from shc_cli.control.controller import RobotState
    from shc_cli.events import recording
    from shc_cli.loop.physics_summary import FALL_TILT, PhysicsRecord
    from shc_cli.spec.loading import load_robot

    robot = load_robot("bullet").robot
    assert robot is not None
    backend = SimpleNamespace(world=SimpleNamespace(physics_time=0.0))
    record = PhysicsRecord(robot, backend, airborne=False)  # type: ignore[arg-type]
    out = SimpleNamespace(robot_state=RobotState.RUNNING)
    reading = SimpleNamespace(rpy=np.array([FALL_TILT + 0.1, 0.0, 0.0]), body_height=0.2, position=np.zeros(3),
                              linear_velocity=np.zeros(3))
    with recording(tmp_path):
        assert record(7, None, out, reading) == "fell"  # type: ignore[arg-type]
    [entry] = _events(tmp_path)
    assert entry["event"] == "fell" and entry["cycle"] == 7 and "tilt 0.900 rad" in str(entry["message"])


class _Value:
    """A GUI value whose setter raises ``error`` (the page's tab, closed or broken)."""

    def __init__(self, error: BaseException) -> None:
        self.error = error

    @property
    def value(self) -> float:
        return 0.0

    @value.setter
    def value(self, _: float) -> None:
        raise self.error


@pytest.mark.parametrize("closed", [True, False])
def test_view_playback_tells_a_closed_tab_from_a_bug(closed: bool, caplog: pytest.LogCaptureFixture) -> None:
    pytest.importorskip("viser")
    from websockets.exceptions import ConnectionClosedOK

    from shc_cli.view.server import RunPage

    page = RunPage.__new__(RunPage)
    page.alive, page.playing = True, True
    page.data = SimpleNamespace(run=SimpleNamespace(t=np.array([0.0, 1.0]), path=Path("run")))  # type: ignore[assignment]
    page.speed = SimpleNamespace(value=1.0)  # type: ignore[assignment]
    page.timeline = _Value(ConnectionClosedOK(None, None) if closed else ValueError("a bug"))  # type: ignore[assignment]
    with caplog.at_level(logging.ERROR, logger="shc_cli.view.server"):
        page._play()  # returns once it stops
    assert not page.alive
    assert ("playback of run stopped" in caplog.text) is (not closed) and ("a bug" in caplog.text) is (not closed)
