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
    """

    def __init__(self, period: float, resync_after: float = 5.0) -> None:
        self.period = period
        self.resync = resync_after * period
        self._next: float | None = None
        self._last: float | None = None
        self.periods: list[float] = []

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        now = time.perf_counter()
        if self._next is None:
            self._next = now
        self._next += self.period
        if now - self._next > self.resync:
            self._next = now  # far behind (a pause, a suspended system): start a new schedule
        delay = self._next - now
        if delay > 0:
            time.sleep(delay)
        end = time.perf_counter()
        if self._last is not None:
            self.periods.append(end - self._last)
        self._last = end
        return None

    def statistics(self) -> dict[str, float | int]:
        """Measured cycle periods (p50, p99, max, mean [ms]), the mean rate [Hz], cycles later than 1.5 periods
        (overruns) and pauses (periods longer than the resync limit: a suspended system, left out of the rest)."""
        if not self.periods:
            return {}
        periods = np.asarray(self.periods)
        kept = periods[periods <= self.resync]
        if not len(kept):
            return {"pauses": len(periods)}
        return {"cycle_time_p50_ms": float(1e3 * np.percentile(kept, 50)),
                "cycle_time_p99_ms": float(1e3 * np.percentile(kept, 99)),
                "cycle_time_max_ms": float(1e3 * kept.max()), "cycle_time_mean_ms": float(1e3 * kept.mean()),
                "rate_hz": float(1.0 / kept.mean()), "overruns": int((kept > 1.5 * self.period).sum()),
                "pauses": int(len(periods) - len(kept))}
