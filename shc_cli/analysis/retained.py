"""Speed retained vs an intact reference (issue 39): how much of an intact robot's speed a run with failed legs
keeps along the commanded heading.

The heading is the velocity command's direction at the first analysed cycle, turned into the world by the body's
yaw there (a robot that drifts off it loses the speed it walks sideways). The speed along it is the median over
the window's gait cycles of each cycle's displacement along the heading over its duration (a cycle's sway and a
start-up cycle do not count against the walk).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from shc_cli.analysis import metrics
from shc_cli.record.runread import RunLog


def heading_speed(log: RunLog, window: metrics.Window) -> float:
    """The median speed along the commanded heading over the window's whole gait cycles [m/s] (NaN: no
    command or no whole cycle)."""
    rows = np.flatnonzero(metrics.window_mask(log, window))
    if len(rows) < 2:
        return math.nan
    commanded = np.flatnonzero(np.abs(log.command[rows, :2]).max(axis=1) > 0.0)
    if len(commanded) == 0:
        return math.nan
    first = rows[commanded[0]]
    vx, vy = log.command[first, :2]
    yaw = float(log.rpy[first, 2]) + math.atan2(float(vy), float(vx))
    heading = np.array([math.cos(yaw), math.sin(yaw)])
    period = max(log.summary.step_period_cycles or 1, 1)
    walked = rows[rows >= first]
    ends = walked[::period]
    if len(ends) < 2:
        return math.nan
    along = (log.position[ends[1:], :2] - log.position[ends[:-1], :2]) @ heading
    return float(np.median(along / (log.t[ends[1:]] - log.t[ends[:-1]])))


def retained(result: Mapping[str, object], log: RunLog, window: metrics.Window,
             reference_mps: float) -> dict[str, object]:
    """``result`` (one run's analysis) with ``heading_speed_mps``, ``speed_retained`` (its share of
    ``reference_mps``, the intact run's) and ``fell``."""
    speed = heading_speed(log, window)
    share = speed / reference_mps if reference_mps > 0.0 and math.isfinite(reference_mps) else math.nan
    return {**result, "heading_speed_mps": speed, "speed_retained": share, "fell": bool(log.summary.fell)}
