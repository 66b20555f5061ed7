"""Did a run that was commanded to walk get anywhere? A flag for the run's summary and its one-line report.

A robot stuck at an obstacle or walking on the spot still steps, draws power and logs every cycle; without a
word on the terminal its run looks like any other. :func:`progress_fields` compares the path the body travelled
with the path the controller commanded (its desired velocity after the limits, integrated over the same window)
and :func:`progress_note` turns a summary's flag into the words the summary line prints.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from shc_cli.record.summary import RunSummary

NO_PROGRESS_SHARE = 0.25
"""A run makes no progress when its body travelled less than this share of the commanded path [ratio]."""
MIN_COMMANDED_DISTANCE_M = 0.05
"""Below this commanded path length [m] (standing, turning on the spot, a short run) the flag stays off."""


def cycle_path_length(xy: ArrayLike, period: int) -> float:
    """Length [m] of a horizontal body path ``xy`` ``(N, 2)`` [m] sampled once per gait cycle (``period`` rows;
    its last point included): it follows a curved path but not the body's sway within a step, which on a robot
    pushing against an obstacle can add up to more than the whole commanded path."""
    import numpy as np

    points = np.asarray(xy, dtype=float).reshape(-1, 2)
    if len(points) < 2:
        return 0.0
    picked = points[::max(int(period), 1)]
    if len(points) - 1 != (len(picked) - 1) * max(int(period), 1):
        picked = np.vstack([picked, points[-1:]])
    return float(np.linalg.norm(np.diff(picked, axis=0), axis=1).sum())


def progress_fields(walked_m: float, commanded_speed_mps: float, window_s: float) -> dict[str, Any]:
    """The summary's ``commanded_distance_m`` (mean commanded speed × window) [m], ``walked_share`` (``walked_m``,
    the body's path per :func:`cycle_path_length`, over that; ``None`` when nothing was commanded) and
    ``no_progress`` (walking was commanded and the body travelled less than :data:`NO_PROGRESS_SHARE` of it)."""
    commanded = max(commanded_speed_mps, 0.0) * max(window_s, 0.0)
    share = float(walked_m / commanded) if commanded > 1e-9 else None
    stuck = bool(commanded >= MIN_COMMANDED_DISTANCE_M and share is not None and share < NO_PROGRESS_SHARE)
    return {"commanded_distance_m": float(commanded), "walked_share": share, "no_progress": stuck}


def progress_note(summary: RunSummary) -> str:
    """``", NO PROGRESS (walked 11% of the 1.20 m commanded)"`` for a summary flagged by :func:`progress_fields`,
    else ``""`` — appended to the plan / simulate summary line."""
    if not summary.no_progress:
        return ""
    share = summary.walked_share or 0.0
    return (f", NO PROGRESS (walked {share:.0%} of the {summary.commanded_distance_m or 0.0:.2f} m "
            "commanded)")
