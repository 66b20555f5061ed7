"""``--realtime``: the simulated time tracks the wall clock. The pacer's arithmetic on a stand-in clock, and a real run
watched from outside: the rows of its streamed log counted against this process's clock."""

from __future__ import annotations

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shc_cli.control.controller import Command
from shc_cli.loop import pacing
from shc_cli.loop.pacing import WallClock

ROOT = Path(__file__).parents[1]
SHC = [sys.executable, "-m", "shc_cli.cli"]


class _Clock:
    """A stand-in for ``time``: each cycle's work takes ``work`` seconds; ``sleep`` moves the clock."""

    def __init__(self, work: float) -> None:
        self.now, self.work = 100.0, work

    def perf_counter(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += seconds


def _pace(monkeypatch: pytest.MonkeyPatch, work: list[float], period: float = 0.01) -> tuple[WallClock, float]:
    """Run the pacer over cycles whose work takes the given times; returns it and the wall time elapsed."""
    clock = _Clock(0.0)
    monkeypatch.setattr(pacing, "time", clock)
    pacer = WallClock(period)
    start = clock.now
    for k, seconds in enumerate(work):
        clock.now += seconds  # the cycle's work
        pacer(k, Command(), None, None)  # type: ignore[arg-type]
    return pacer, clock.now - start


def test_cycles_shorter_than_the_period_keep_the_clock_exactly(monkeypatch: pytest.MonkeyPatch) -> None:
    pacer, wall = _pace(monkeypatch, [0.002, 0.009, 0.0] * 2000)
    assert pacer.cycles == 6000 and wall == pytest.approx(6000 * 0.01 + 0.002, abs=1e-9)
    stats = pacer.statistics()
    assert stats["realtime_ratio"] == pytest.approx(1.0, abs=1e-9)  # the first cycle's start to the last's end
    assert stats["rate_hz"] == pytest.approx(100.0) and stats["overruns"] == 0


def test_a_late_cycle_is_caught_up_and_a_slow_machine_shows_in_the_ratio(monkeypatch: pytest.MonkeyPatch) -> None:
    late, _ = _pace(monkeypatch, [0.001] * 100 + [0.03] + [0.001] * 100)  # one 3-period hiccup
    assert late.statistics()["realtime_ratio"] == pytest.approx(1.0, abs=1e-9)  # the schedule is kept
    assert late.statistics()["realtime_lag_max_ms"] == pytest.approx(20.0, abs=1e-6)  # 30 ms of work, 10 allowed
    slow, wall = _pace(monkeypatch, [0.0125] * 400)  # every cycle a quarter period too long
    ratio = slow.statistics()["realtime_ratio"]  # over the wall time from the first cycle's work done
    assert ratio == pytest.approx(400 * 0.01 / (wall - 0.0125)) and ratio == pytest.approx(0.8, rel=0.01)


@pytest.mark.slow
def test_a_realtime_simulation_tracks_the_wall_clock_seen_from_outside(tmp_path: Path) -> None:
    """The rows of the running simulation's ``log.csv``, counted by this process as they are written, grow at 100 per
    second of this process's clock (5 % here; benchmarks/bench_realtime.py measures 60 s to the 1 % goal)."""
    run = tmp_path / "run"
    log = run.with_name("run.partial") / "log.csv"
    process = subprocess.Popen([*SHC, "simulate", "--engine", "mujoco", "--realtime", "--duration", "12", "--no-plots",
                                "--out", str(run)], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    samples: list[tuple[float, int]] = []
    while process.poll() is None:
        if log.exists():
            with log.open("rb") as handle:
                rows = handle.read().count(b"\n") - 1
            if rows > 0 and (not samples or rows != samples[-1][1]):
                samples.append((time.monotonic(), rows))
        time.sleep(0.05)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 0, stderr
    summary = json.loads((run / "summary.json").read_text())
    window = [(t, rows) for t, rows in samples if rows >= 300]  # the first seconds: the file opens, pages fault in
    (t0, r0), (t1, r1) = window[0], window[-1]
    assert t1 - t0 > 8.0, (t0, t1)
    rate = (r1 - r0) / (t1 - t0)
    assert rate == pytest.approx(100.0, rel=0.05), rate
    assert summary["realtime_ratio"] == pytest.approx(1.0, rel=0.05), summary
    assert summary["realtime_ratio"] <= 1.0 + 1e-3  # never ahead of the clock
