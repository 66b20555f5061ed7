"""Pacing a run to the wall clock: one control cycle per control period of real time.

Plan and simulate run as fast as they can; a ROS node (``shc ros``) and an interactive simulation
(``simulate --realtime``) must keep the controller's rate against the clock. :class:`WallClock` is an observer
of the run loop that sleeps until each cycle's due time and keeps the measured periods, so the rate held can be
reported (p50/p99/max). It never skips or repeats a cycle: a late cycle is followed at once by the next.
"""

from __future__ import annotations

import time

import numpy as np

from shc_cli.control.controller import Command, CycleOutput


class WallClock:
    """Sleeps so that cycle ``k`` ends no earlier than ``start + (k + 1)·period`` (an observer of the run loop).

    Args:
        period: the control period [s].
        resync_after: a cycle later than this many periods moves the schedule instead of bursting to catch up.
        pace: sleep to the schedule (False: only measure, when something else keeps the period — a servo bus).
    """

    def __init__(self, period: float, resync_after: float = 5.0, pace: bool = True) -> None:
        self.period, self.pace = period, pace
        self.resync = resync_after * period
        self._next: float | None = None
        self._last: float | None = None
        self._start: float | None = None
        self.periods: list[float] = []
        self.cycles = 0
        self.lag_max = 0.0
        """The furthest a cycle's end fell behind its due time [s] (before a resync moved the schedule)."""

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        now = time.perf_counter()
        if self._next is None:
            self._next = self._start = now
        self._next += self.period
        self.lag_max = max(self.lag_max, now - self._next)
        if now - self._next > self.resync:
            self._next = now  # far behind (a pause, a suspended system): start a new schedule
        delay = self._next - now
        if delay > 0 and self.pace:
            time.sleep(delay)
        end = time.perf_counter()
        if self._last is not None:
            self.periods.append(end - self._last)
        self._last = end
        self.cycles += 1
        return None

    def ratio(self) -> float | None:
        """Simulated time ÷ wall time from the first cycle to the last one's end (1: the run kept the clock;
        pauses included), or None before two cycles."""
        if self._start is None or self._last is None or self.cycles < 2:
            return None
        return self.cycles * self.period / (self._last - self._start)

    def statistics(self) -> dict[str, float | int]:
        """Measured cycle periods (p50, p99, max, mean [ms]), the mean rate [Hz], cycles later than 1.5 periods
        (overruns) and pauses (periods longer than the resync limit: a suspended system, left out of the rest); the
        simulated ÷ wall time over the whole run (:meth:`ratio`, pauses included) and the largest lag behind the
        schedule [ms]."""
        if not self.periods:
            return {}
        ratio = self.ratio()
        tracking: dict[str, float | int] = {"realtime_lag_max_ms": 1e3 * max(self.lag_max, 0.0)}
        if ratio is not None:
            tracking["realtime_ratio"] = ratio
        periods = np.asarray(self.periods)
        kept = periods[periods <= self.resync]
        if not len(kept):
            return {"pauses": len(periods), **tracking}
        return {"cycle_time_p50_ms": float(1e3 * np.percentile(kept, 50)),
                "cycle_time_p99_ms": float(1e3 * np.percentile(kept, 99)),
                "cycle_time_max_ms": float(1e3 * kept.max()), "cycle_time_mean_ms": float(1e3 * kept.mean()),
                "rate_hz": float(1.0 / kept.mean()), "overruns": int((kept > 1.5 * self.period).sum()),
                "pauses": int(len(periods) - len(kept)), **tracking}
