"""Gaits for any set of legs: phase tables generated for the legs a robot has left, chosen for a static margin.

When a leg fails (issue 39) the robot's gait files no longer fit: a tripod without its front-right leg stands
on two feet half of the time. This module generates OpenSHC phase tables (:class:`~shc_cli.spec.gait.Gait`) for
any subset of a robot's legs, with no trials, from the geometry alone:

* **The candidates.** A gait of ``g`` *swing groups*: the legs are split into ``g`` ordered groups; group ``j``
  lifts off at unit ``j·a`` of a cycle of ``U = g·a`` units and swings for ``w`` units (``a ≤ w``; ``w > a`` lets
  the swings of successive groups overlap, as OpenSHC's ripple does). ``g = 2`` with three legs a group is the
  tripod, ``g = n`` with ``w = a`` the wave. The duty factor is ``β = 1 − w/U``.
* **The score.** In OpenSHC the swing lasts ``1/f`` at step frequency ``f`` whatever the gait, so at a given
  stride the body speed is ``stride·f·(1 − β)/β``: relative to the tripod's (β = ½) that is ``(1 − β)/β``
  (:attr:`PlannedGait.speed_share`).
* **The constraint.** Every stance foot moves back along the heading by one stride over its stance; at each
  instant of the cycle the stance feet's convex hull must hold the centre of mass with a margin. The centre of
  mass may be shifted (the body posed over the legs that are left): the shift that maximises the worst margin over
  the whole cycle is a linear programme (each hull edge's distance is linear in the shift), solved with SciPy's
  HiGHS. A moment with fewer than three stance feet has no area and no margin.

:func:`plan_gait` returns the fastest candidate whose worst margin reaches ``min_margin_m``, the widest margin
breaking ties. All lengths are in the walk plane, in the body frame [m].

Where no table holds on the robot's own stance positions (two failed legs on one side leave that side a single
foot: standing on the other side's three collinear feet has no area), the stance positions of the legs left may
be moved (``reach_m``, within their workspace: ``reachable``): a greedy search, each step the move of one leg by a
quarter of ``reach_m`` that most widens the margin (or speeds the gait), until a table holds.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linprog

from shc_cli.errors import ShcError
from shc_cli.spec.gait import Gait

SAMPLES_PER_UNIT = 2
"""Instants sampled per gait unit when the margin is checked (stance progress is linear inside a unit, so the
extremes of each unit, which the samples include, bound the margin)."""
MAX_SHIFT_M = 0.5
"""Largest body shift the planner considers [m] (a bound for the linear programme)."""


class GaitPlanningError(ShcError):
    """No phase table keeps the centre of mass inside the support polygon for these legs."""


@dataclass(frozen=True)
class PlannedGait:
    """A generated gait and what it was chosen for.

    Attributes:
        gait: the phase table (OpenSHC's model: stance/swing/offset units and per-leg multipliers).
        groups: the swing groups in lift-off order (leg ids).
        margin_m: the worst static margin over the cycle with the body at ``body_shift_m`` [m].
        body_shift_m: centre-of-mass offset from the body origin at each sampled instant of the cycle that gives
            ``margin_m``, ``(K, 2)`` [m] (:data:`SAMPLES_PER_UNIT` × 4 samples a group spacing).
        duty_factor: stance share of the cycle ``β``.
        stance: the stance (identity tip) position of each walking leg the margin holds for (x, y) [m]: the
            robot's own, or moved where no gait holds on it (``reach_m``).
        speed_share: body speed relative to a tripod's at the same stride and step frequency, ``(1 − β)/β``.
    """

    gait: Gait
    groups: tuple[tuple[str, ...], ...]
    margin_m: float
    body_shift_m: np.ndarray
    duty_factor: float
    stance: dict[str, tuple[float, float]]

    @property
    def speed_share(self) -> float:
        return (1.0 - self.duty_factor) / self.duty_factor


def _hull(points: np.ndarray) -> np.ndarray:
    """Counter-clockwise convex hull of ``(k, 2)`` points (Andrew's monotone chain), ``(h, 2)``."""
    pts = sorted(map(tuple, points))
    if len(pts) < 3:
        return np.array(pts)

    def cross(o: tuple[float, ...], a: tuple[float, ...], b: tuple[float, ...]) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list[tuple[float, ...]] = []
    for p in pts:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], p) <= 1e-12:
            lower.pop()
        lower.append(p)
    upper: list[tuple[float, ...]] = []
    for p in reversed(pts):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], p) <= 1e-12:
            upper.pop()
        upper.append(p)
    return np.array(lower[:-1] + upper[:-1])


def _edge_rows(hull: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inward unit normals ``(h, 2)`` and offsets ``(h,)`` of a counter-clockwise hull's edges: a point ``c`` is
    at distance ``normal·c + offset`` inside each edge's line."""
    start, end = hull, np.roll(hull, -1, axis=0)
    edge = end - start
    length = np.hypot(edge[:, 0], edge[:, 1])
    normal = np.stack([-edge[:, 1], edge[:, 0]], axis=1) / length[:, None]
    return normal, -np.einsum("ij,ij->i", normal, start)


def stance_tips(stance: Mapping[str, tuple[float, float]], groups: Sequence[Sequence[str]], swing_units: float,
                stride_m: float, heading_rad: float = 0.0) -> Iterator[np.ndarray]:
    """The stance feet (x, y) at each sampled instant of a cycle of ``len(groups)`` groups, one unit apart in
    lift-off, each swinging ``swing_units`` units (the group spacing is one unit here: ``U = g``·1 and ``w`` in
    those units may be fractional).

    Yields one ``(k, 2)`` array per instant; ``k`` < 3 means no support area.
    """
    g = len(groups)
    cycle = float(g)
    swing = swing_units
    direction = np.array([math.cos(heading_rad), math.sin(heading_rad)])
    for step in range(g * SAMPLES_PER_UNIT * 4):
        t = step / (SAMPLES_PER_UNIT * 4)
        feet = []
        for j, group in enumerate(groups):
            since_liftoff = (t - j) % cycle
            if since_liftoff < swing - 1e-12:
                continue
            progress = (since_liftoff - swing) / (cycle - swing)  # 0 at touch-down, 1 at lift-off
            for leg in group:
                x, y = stance[leg]
                feet.append(np.array([x, y]) + direction * stride_m * (0.5 - progress))
        yield np.array(feet).reshape(-1, 2)


def worst_margin(stance: Mapping[str, tuple[float, float]], groups: Sequence[Sequence[str]], swing_units: float,
                 stride_m: float, heading_rad: float = 0.0, sway: bool = True,
                 sway_stride_m: float | None = None) -> tuple[float, np.ndarray]:
    """The worst static margin over the cycle [m] with the best body shift, and that shift at each sampled instant
    ``(K, 2)`` [m] (``-inf`` when some instant has fewer than three stance feet or no shift keeps the centre of
    mass inside).

    With ``sway`` the shift may change through the cycle (the body swaying over the legs that carry it, as
    OpenSHC's auto-pose does), at most as fast as the stance feet move at a stride of ``sway_stride_m`` (default:
    ``stride_m``); without it one shift holds throughout.
    """
    rows: list[tuple[np.ndarray, np.ndarray]] = []
    for feet in stance_tips(stance, groups, swing_units, stride_m, heading_rad):
        hull = _hull(feet) if len(feet) >= 3 else feet
        if len(hull) < 3:
            return -math.inf, np.zeros((0, 2))
        rows.append(_edge_rows(hull))
    k = len(rows) if sway else 1
    # variables: (cx_0, cy_0, …, cx_{k-1}, cy_{k-1}, s); maximise s subject to s ≤ n·c_i + o for every edge
    a_rows, b_rows = [], []
    for i, (normal, offset) in enumerate(rows):
        block = np.zeros((len(normal), 2 * k + 1))
        j = i if sway else 0
        block[:, 2 * j:2 * j + 2] = -normal
        block[:, -1] = 1.0
        a_rows.append(block)
        b_rows.append(offset)
    if sway and k > 1:
        stance_span = len(groups) - swing_units
        sway_stride = stride_m if sway_stride_m is None else sway_stride_m
        step = sway_stride / stance_span / (SAMPLES_PER_UNIT * 4)  # a stance foot's travel between two samples
        for i in range(k):
            for axis in range(2):
                for sign in (1.0, -1.0):
                    row = np.zeros(2 * k + 1)
                    row[2 * i + axis] = sign
                    row[2 * ((i + 1) % k) + axis] = -sign
                    a_rows.append(row[None, :])
                    b_rows.append(np.array([step]))
    result = linprog(c=np.r_[np.zeros(2 * k), -1.0], A_ub=np.concatenate(a_rows), b_ub=np.concatenate(b_rows),
                     bounds=[(-MAX_SHIFT_M, MAX_SHIFT_M)] * (2 * k) + [(None, None)], method="highs")
    if not result.success:
        return -math.inf, np.zeros((0, 2))
    shifts = result.x[:-1].reshape(k, 2)
    return float(result.x[-1]), shifts


def _ordered_partitions(legs: Sequence[str], g: int) -> Iterator[tuple[tuple[str, ...], ...]]:
    """Every split of ``legs`` into ``g`` non-empty ordered groups, up to rotation of the order (a cycle has no
    first group): the group holding ``legs[0]`` comes first."""
    n = len(legs)
    for labels in itertools.product(range(g), repeat=n - 1):
        full = (0, *labels)
        if len(set(full)) != g:
            continue
        yield tuple(tuple(leg for leg, label in zip(legs, full, strict=True) if label == j) for j in range(g))


def _candidates(n: int) -> Iterator[tuple[int, int, int]]:
    """(groups g, units per group a, swing units w) from the fastest duty factor up: ``β = 1 − w/(g·a)``."""
    options = []
    for g in range(2, n + 1):
        for a in (1, 2):
            for w in range(a, 2 * a + 1):
                if w >= g * a:
                    continue
                options.append((1.0 - w / (g * a), g, a, w))
    for _, g, a, w in sorted(set(options)):
        yield g, a, w


def _gait(name: str, groups: Sequence[Sequence[str]], a: int, w: int) -> Gait:
    """The OpenSHC phase table of ``groups`` (group ``j`` lifts off at unit ``j·a``; see :func:`step_cycle`:
    a leg swings while ``(φ + offset) mod U`` lies in ``[trunc(stance/2), trunc(stance/2) + swing)``)."""
    units = len(groups) * a
    stance = units - w
    swing_start = math.trunc(stance * 0.5)
    offsets = {leg: (swing_start - j * a) % units for j, group in enumerate(groups) for leg in group}
    step = math.gcd(*offsets.values()) or 1
    return Gait(name=name, description=f"generated for {len(offsets)} legs: "
                + " → ".join("+".join(group) for group in groups),
                stance_phase=stance, swing_phase=w, phase_offset=step,
                offset_multiplier={leg: off // step for leg, off in offsets.items()})


def _search(stance: Mapping[str, tuple[float, float]], legs: Sequence[str], stride_m: float, heading_rad: float,
            min_margin_m: float, name: str, sway: bool, sway_stride_m: float | None,
            exhaustive: bool) -> tuple[PlannedGait | None, float]:
    """The fastest candidate holding ``min_margin_m`` (widest margin among equals), and the widest margin of any
    candidate looked at; without ``exhaustive`` the search stops after the first duty factor that holds."""
    best: PlannedGait | None = None
    widest = -math.inf
    for g, a, w in _candidates(len(legs)):
        duty = 1.0 - w / (g * a)
        if best is not None and duty > best.duty_factor + 1e-12 and not exhaustive:
            break
        for groups in _ordered_partitions(legs, g):
            margin, shift = worst_margin(stance, groups, w / a, stride_m, heading_rad, sway, sway_stride_m)
            widest = max(widest, margin)
            if margin < min_margin_m:
                continue
            if best is None or duty < best.duty_factor - 1e-12 or (
                    abs(duty - best.duty_factor) <= 1e-12 and margin > best.margin_m + 1e-12):
                best = PlannedGait(_gait(name, groups, a, w), groups, margin, shift, duty,
                                   {leg: stance[leg] for leg in legs})
    return best, widest


Reachable = Callable[[str, tuple[float, float]], bool]
"""Whether a leg's tip can stand at (x, y) in the walk plane [m]."""


def _redistributed(stance: Mapping[str, tuple[float, float]], legs: Sequence[str], stride_m: float,
                   heading_rad: float, min_margin_m: float, name: str, sway: bool, sway_stride_m: float | None,
                   reach_m: float, reachable: Reachable | None) -> PlannedGait | None:
    """Greedy moves of the walking legs' stance positions until a gait holds the margin (see the module)."""
    step = reach_m / 4.0
    current = {leg: stance[leg] for leg in legs}
    best, widest = _search(current, legs, stride_m, heading_rad, min_margin_m, name, sway, sway_stride_m, True)
    for _ in range(4 * len(legs)):
        if best is not None:
            return best
        trial_best: tuple[float, dict[str, tuple[float, float]], PlannedGait | None] | None = None
        for leg in legs:
            x0, y0 = stance[leg]
            x, y = current[leg]
            for dx, dy in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step)):
                moved = (x + dx, y + dy)
                if math.hypot(moved[0] - x0, moved[1] - y0) > reach_m + 1e-12:
                    continue
                if reachable is not None and not reachable(leg, moved):
                    continue
                trial = {**current, leg: moved}
                found, margin = _search(trial, legs, stride_m, heading_rad, min_margin_m, name, sway, sway_stride_m,
                                        True)
                score = margin + (1.0 if found is not None else 0.0)
                if trial_best is None or score > trial_best[0]:
                    trial_best = (score, trial, found)
        if trial_best is None or (trial_best[2] is None and trial_best[0] <= widest + 1e-9):
            return None
        widest, current, best = max(widest, trial_best[0]), trial_best[1], trial_best[2]
    return best


def plan_gait(stance: Mapping[str, tuple[float, float]], legs: Sequence[str], stride_m: float,
              heading_rad: float = 0.0, min_margin_m: float = 0.02, name: str = "planned",
              sway: bool = True, sway_stride_m: float | None = None, reach_m: float = 0.0,
              reachable: Reachable | None = None) -> PlannedGait:
    """The fastest generated gait for ``legs`` that keeps the worst static margin ≥ ``min_margin_m``.

    Args:
        stance: each leg's identity tip (x, y) in the body frame [m] (OpenSHC ``<LEG>_stance_position``).
        legs: the legs that walk (the others are held clear of the ground).
        stride_m: the stride along the heading [m] (a stance foot's travel relative to the body).
        heading_rad: the walking direction in the body frame [rad].
        min_margin_m: the static margin required at every instant [m].
        name: the generated gait's name.
        sway: let the body sway through the cycle (else one shift for the whole cycle).
        sway_stride_m: the stride whose stance-foot speed bounds the sway [m] (default ``stride_m``; give the
            walkspace's largest stride to let a slow walk sway as fast as a full-speed one).
        reach_m: when no gait holds on the identity stance, how far each leg's stance position may move [m]
            (0: not at all); the moves are searched greedily in steps of a quarter of it.
        reachable: tells whether a leg's tip can stand at (x, y) [m] (its workspace); default: anywhere within
            ``reach_m``.

    Raises:
        GaitPlanningError: no candidate keeps the margin (fewer than three legs, or a stride too long for them).
    """
    legs = list(legs)
    if len(legs) < 3:
        raise GaitPlanningError(f"{len(legs)} leg(s) left ({', '.join(legs) or 'none'}): a statically stable "
                                "gait needs at least three")
    best, _ = _search(stance, legs, stride_m, heading_rad, min_margin_m, name, sway, sway_stride_m, False)
    if best is None and reach_m > 0:
        best = _redistributed(stance, legs, stride_m, heading_rad, min_margin_m, name, sway, sway_stride_m, reach_m,
                              reachable)
    if best is None:
        raise GaitPlanningError(f"no gait keeps a {min_margin_m:g} m static margin on legs {', '.join(legs)} "
                                f"at a {stride_m:g} m stride; shorten the stride")
    return best


def sway_path(planned: PlannedGait, stride_m: float, heading_rad: float = 0.0, min_margin_m: float = 0.02,
              stride_shares: Sequence[float] = (0.0, 0.5, 1.0), rate_share: float = 1.0,
              max_shift_m: float = MAX_SHIFT_M) -> np.ndarray | None:
    """The smallest body sway through ``planned``'s cycle that keeps the static margin ≥ ``min_margin_m`` at every
    sampled instant, ``(K, 2)`` [m] (the centre-of-mass offset from the body origin; ``None``: none does).

    A linear programme (HiGHS): minimise the summed |shift| (L1) subject to every hull edge of the stance feet at
    each instant keeping the margin, for the walk at each of ``stride_shares`` of ``stride_m`` at once (the walker
    ramps its stride up and down, so the sway, a function of the phase alone, must hold for the shorter strides
    too), the sway moving between two samples at most ``rate_share`` × a stance foot's travel at ``stride_m``, and
    no shift beyond ``max_shift_m`` on either axis (what the legs can reach).
    """
    groups = planned.groups
    swing = planned.gait.swing_phase * len(groups) / planned.gait.base_length
    per_share = [list(stance_tips(planned.stance, groups, swing, stride_m * share, heading_rad))
                 for share in stride_shares]
    k = len(per_share[0])
    a_rows, b_rows = [], []
    for instants in per_share:
        for i, feet in enumerate(instants):
            hull = _hull(feet) if len(feet) >= 3 else feet
            if len(hull) < 3:
                return None
            normal, offset = _edge_rows(hull)
            block = np.zeros((len(normal), 4 * k))
            block[:, 2 * i:2 * i + 2] = -normal  # −n·c ≤ o − m
            a_rows.append(block)
            b_rows.append(offset - min_margin_m)
    eye = np.eye(2 * k)
    a_rows += [np.hstack([eye, -eye]), np.hstack([-eye, -eye])]  # |c| ≤ u
    b_rows += [np.zeros(2 * k), np.zeros(2 * k)]
    step = rate_share * stride_m / (len(groups) - swing) / (SAMPLES_PER_UNIT * 4) if stride_m > 0 else MAX_SHIFT_M
    for i in range(k):
        for axis in range(2):
            row = np.zeros(4 * k)
            row[2 * i + axis], row[2 * ((i + 1) % k) + axis] = 1.0, -1.0
            a_rows += [row[None, :], -row[None, :]]
            b_rows += [np.array([step]), np.array([step])]
    bounds = [(-max_shift_m, max_shift_m)] * (2 * k) + [(0.0, None)] * (2 * k)
    result = linprog(c=np.r_[np.zeros(2 * k), np.ones(2 * k)], A_ub=np.concatenate(a_rows),
                     b_ub=np.concatenate(b_rows), bounds=bounds, method="highs")
    if not result.success:
        return None
    return np.asarray(result.x[:2 * k].reshape(k, 2), dtype=float)


def sway_at(path: np.ndarray, phase: float) -> np.ndarray:
    """The sway ``path`` (:func:`sway_path`, samples evenly over one cycle) at ``phase`` ∈ [0, 1) of the cycle
    (0: the first group lifts off), linearly interpolated, (x, y) [m]."""
    k = len(path)
    position = (phase % 1.0) * k
    i = int(position) % k
    fraction = position - int(position)
    return np.asarray(path[i] * (1.0 - fraction) + path[(i + 1) % k] * fraction, dtype=float)
