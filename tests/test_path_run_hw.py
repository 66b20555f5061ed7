"""``shc run-hw --path`` on the emulated servo bus: the follower walks the path by the odometry of the measured
joints, stops at the last waypoint, and the robot shuts down."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from shc_cli.record.runread import read_run

from .test_run_hw import _bus, _run_hw

pytestmark = pytest.mark.slow  # real time on the emulated bus


def test_run_hw_walks_a_path_and_stops_at_its_end(tmp_path: Path) -> None:
    path = tmp_path / "short.csv"
    path.write_text("x,y,yaw\n0.15,0.05,0.3\n")
    with _bus() as bus:
        result = _run_hw(bus, tmp_path / "run", "--path", str(path))
        assert result.returncode == 0, result.stderr
        assert "ended PACKED" in result.stdout
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["input"] == "path" and summary["fault"] is None and summary["stopped_by_request"]
    assert summary["path_file"] == "path.csv" and summary["final_state"] == "PACKED"
    (waypoint,) = summary["waypoints"]
    assert waypoint["reached"] and waypoint["position_error_m"] <= 0.02 and abs(waypoint["heading_error_rad"]) < 0.02
    log = read_run(tmp_path / "run")
    start = summary["path_start_cycle"]
    goal = start + round(waypoint["left_s"] / log.dt)
    walking = log.command[start:goal]
    assert np.abs(walking).max() > 0.3  # the follower's commands drove the walker …
    assert not log.command[goal + 1:].any()  # … and after the waypoint only zero (then the shut-down)
    assert (log.walk_state[start:goal] == "MOVING").any() and log.walk_state[-1] == "STOPPED"
