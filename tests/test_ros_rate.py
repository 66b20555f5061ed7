"""``/desired_joint_states`` of ``shc ros`` and ``shc ros2`` at the control rate over a walk, to a reliable subscriber
that is not shc (rospy, rclpy): ``benchmarks/bench_ros_rate.py``'s measurement, shortened. The rate is measured with
the messages' header stamps (the node's clock when it published), so a loaded subscriber does not count against it."""

from __future__ import annotations

import importlib.util
import os
import shutil
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).parents[1]
SECONDS = 15.0


def _bench() -> ModuleType:
    spec = importlib.util.spec_from_file_location("bench_ros_rate", ROOT / "benchmarks" / "bench_ros_rate.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _needs(available: bool, what: str) -> None:
    if not available:
        if os.environ.get("CI"):
            pytest.fail(f"{what} missing: .ci/run installs it")
        pytest.skip(f"{what} is not installed")


@pytest.mark.slow
@pytest.mark.serial  # holds 100 Hz against the wall clock
@pytest.mark.parametrize("ros", ["1", "2"])
def test_desired_joint_states_at_the_control_rate_and_none_lost(ros: str, tmp_path: Path) -> None:
    if ros == "1":
        _needs(shutil.which("roscore") is not None, "Debian's ROS 1 (roscore)")
    else:
        _needs(importlib.util.find_spec("rclpy") is not None, "the ros2 extra (rclpy)")
    figures = _bench()._run(ros, SECONDS, tmp_path)
    assert figures["lost"] == 0 and figures["messages"] == figures["cycles"] > SECONDS * 100, figures
    if ros == "1":
        assert figures["seq_gaps"] == 0, figures
    assert figures["window_messages"] > SECONDS * 95, figures
    assert figures["stamp_rate_hz"] == pytest.approx(100.0, rel=0.01), figures
    # the "no interval over three periods" is not met on a loaded machine (docs/performance.md): this only
    # catches a freeze
    assert figures["stamp_max_interval_ms"] < 500.0, figures
