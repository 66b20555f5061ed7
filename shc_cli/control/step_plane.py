"""The step-plane input: footholds, swing clearance and body height from a height map (issue 40).

OpenSHC has the input and nothing that feeds it: in rough-terrain mode a known step plane under a foot shifts that
leg's swing target along the walk-plane normal onto it ("proactive" target shifting, study §5.7, §8.4), and its
code leaves the range sensor that would give it as a TODO. Here a :class:`TerrainMap` — a robot-centred 2.5-D grid
of terrain heights and the body's pose in the grid's frame, as a depth sensor and the odometry make it — comes in
with the cycle's :class:`~shc_cli.control.controller.Command` (the controller stays pure), and
:meth:`StepPlanes.update` turns it into the walker's per-leg inputs (:attr:`WalkController.step_plane`):

* **landing height**: each leg's target is shifted along the vertical by the map's height under it minus the
  target's own height in the map frame (the step plane of OpenSHC's proactive shift, from the map, not from a
  touch);
* **away from edges**: a target whose cell lies within ``edge_margin`` of a height change above ``edge_step``
  moves to the nearest cell (at most ``max_shift`` away) whose surroundings are level, and lands on the highest
  point around it;
* **swing height from obstacles**: before a leg lifts off, its clearance is the walker's swing height or, if
  higher, the highest point of the map along the straight path from the foot to its target above the higher end,
  plus ``clearance_margin`` (at most ``max_clearance``; less than ``edge_step`` above is noise); kept for the swing;
* **body height and pitch**: with the input the walk plane (which carries the body, study §7.6) is the plane
  through the legs' shifted targets — the predicted footholds, as ATHENA takes the plane of the feet — its slope
  clamped to ``max_slope``, raised to the highest ground under the body's footprint and ``lookahead`` ahead of it
  (:attr:`StepPlanes.body_floor`) when that is more than ``edge_step`` above it.

Unknown cells (never seen) leave a leg blind: no shift, the walker's swing height. The kernels are compiled: the
per-cycle cost is a few µs (``benchmarks/bench_height_map.py``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from shc_cli.model.jit import njit


@njit(cache=True)
def _surroundings(heights, radius):  # type: ignore[no-untyped-def]
    """Each known cell's highest height and height span over the known cells within ``radius`` cells (an unknown
    cell: nan and inf)."""
    n, m = heights.shape
    top = np.full((n, m), np.nan)
    span = np.full((n, m), np.inf)
    for i in range(n):
        for j in range(m):
            if math.isnan(heights[i, j]):
                continue
            high, low = -np.inf, np.inf
            for a in range(max(0, i - radius), min(n, i + radius + 1)):
                for b in range(max(0, j - radius), min(m, j + radius + 1)):
                    h = heights[a, b]
                    if not math.isnan(h):
                        high = max(high, h)
                        low = min(low, h)
            top[i, j] = high
            span[i, j] = high - low
    return top, span


@njit(cache=True)
def _cell(x, y, cell, ci, cj, half):  # type: ignore[no-untyped-def]
    return math.floor(x / cell + 0.5) - ci + half, math.floor(y / cell + 0.5) - cj + half


@njit(cache=True)
def _height(top, x, y, cell, ci, cj, half):  # type: ignore[no-untyped-def]
    i, j = _cell(x, y, cell, ci, cj, half)
    if 0 <= i < top.shape[0] and 0 <= j < top.shape[1]:
        return top[i, j]
    return math.nan


@njit(cache=True)
def _footholds(  # type: ignore[no-untyped-def]
    heights, top, span, cell, ci, cj, targets, tips, walker_targets, walker_tips, swinging, swing_height, edge_step,
    reach, clearance_margin, max_clearance, yaw, offsets, clearances, references,
):
    """Per leg: the target shift into ``offsets`` (walk-plane frame) and, for legs not ``swinging``, the swing
    clearance into ``clearances``. ``targets`` and ``tips`` (L, 3) are in the map frame (their x, y are used),
    ``walker_targets`` and ``walker_tips`` in the walk-plane frame (their z is used)."""
    n = top.shape[0]
    half = n // 2
    legs = targets.shape[0]
    # Each foot's map height minus its walk-plane height where it stands (kept through its swing: where it lifted
    # off): the step from there to the target is the map's height difference.
    total, count = 0.0, 0
    for leg in range(legs):
        if not swinging[leg]:
            h = _height(heights, tips[leg, 0], tips[leg, 1], cell, ci, cj, half)
            if not math.isnan(h):
                references[leg] = h - walker_tips[leg, 2]
        if not math.isnan(references[leg]):
            total += references[leg]
            count += 1
    c, s = math.cos(yaw), math.sin(yaw)
    for leg in range(legs):
        if swinging[leg] and math.isnan(clearances[leg]):  # (a map that arrives mid-swing)
            clearances[leg] = swing_height
        offsets[leg, 0] = offsets[leg, 1] = offsets[leg, 2] = 0.0
        if count == 0:
            if not swinging[leg]:
                clearances[leg] = swing_height
            continue
        reference = references[leg] if not math.isnan(references[leg]) else total / count
        tx, ty = targets[leg, 0], targets[leg, 1]
        i0, j0 = _cell(tx, ty, cell, ci, cj, half)
        if not (0 <= i0 < n and 0 <= j0 < n) or math.isnan(top[i0, j0]):  # not seen: blind
            if not swinging[leg]:
                clearances[leg] = swing_height
            continue
        best_i, best_j, best = -1, -1, np.inf
        if span[i0, j0] <= edge_step:
            best_i, best_j = i0, j0  # level already: stay
        else:
            for di in range(-reach, reach + 1):
                for dj in range(-reach, reach + 1):
                    i, j = i0 + di, j0 + dj
                    if 0 <= i < n and 0 <= j < n and span[i, j] <= edge_step:
                        distance = di * di + dj * dj
                        if distance < best:
                            best_i, best_j, best = i, j, distance
        dx = dy = 0.0
        landing = math.nan
        if best_i >= 0:
            dx, dy = (best_i - i0) * cell, (best_j - j0) * cell
            landing = top[best_i, best_j]
        else:
            landing = top[i0, j0]  # no level cell near: land on the highest point around the target
        dz = landing - (walker_targets[leg, 2] + reference)
        if abs(dz) <= edge_step:  # the map's noise, not a step
            dz = 0.0
        offsets[leg, 0] = c * dx + s * dy
        offsets[leg, 1] = -s * dx + c * dy
        offsets[leg, 2] = dz
        if swinging[leg]:
            continue
        fx, fy = tx + dx, ty + dy
        peak = -np.inf
        for k in range(1, 9):  # the straight path from the foot to its landing point
            share = k / 9.0
            h = _height(top, tips[leg, 0] + share * (fx - tips[leg, 0]), tips[leg, 1] + share * (fy - tips[leg, 1]),
                        cell, ci, cj, half)
            if not math.isnan(h):
                peak = max(peak, h)
        higher = max(walker_tips[leg, 2] + reference, walker_targets[leg, 2] + reference + dz)
        clearances[leg] = swing_height
        if peak - higher > edge_step:  # an obstacle, not the map's noise
            clearances[leg] = min(max(swing_height, peak - higher + clearance_margin),
                                  max(max_clearance, swing_height))


@njit(cache=True)
def _footprint_top(heights, cell, ci, cj, x, y, yaw, back, front, half_width):  # type: ignore[no-untyped-def]
    """The highest known height under a rectangle ``back`` behind to ``front`` ahead of (x, y) along ``yaw`` and
    ``half_width`` either side (-inf if none is known)."""
    n = heights.shape[0]
    half = n // 2
    c, s = math.cos(yaw), math.sin(yaw)
    reach = max(back, front, half_width) * 1.5
    i_low, j_low = _cell(x - reach, y - reach, cell, ci, cj, half)
    i_high, j_high = _cell(x + reach, y + reach, cell, ci, cj, half)
    top = -np.inf
    for i in range(max(0, i_low), min(n, i_high + 1)):
        for j in range(max(0, j_low), min(n, j_high + 1)):
            h = heights[i, j]
            if math.isnan(h):
                continue
            dx = (ci + i - half) * cell - x
            dy = (cj + j - half) * cell - y
            along, across = c * dx + s * dy, -s * dx + c * dy
            if -back <= along <= front and abs(across) <= half_width:
                top = max(top, h)
    return top


@njit(cache=True)
def _step_plane(  # type: ignore[no-untyped-def]
    heights, top, span, cell, ci, cj, position, rotation, body_position, body_rotation, walker_targets, walker_tips,
    progress, swing_height, vx, vy, swing_s, edge_step, reach, clearance_margin, max_clearance, back, front,
    half_width, offsets, clearances, references,
):
    """One cycle of :meth:`StepPlanes.update` in one call: the walk-plane points in the map frame (targets where
    they will be at touchdown), :func:`_footholds`, and the body's floor (returned; -inf: unknown)."""
    legs = walker_targets.shape[0]
    transform = np.empty((3, 3))  # walk-plane frame → map frame: rotation · body_rotationᵀ (no BLAS in kernels)
    shift = np.empty(3)
    for i in range(3):
        for j in range(3):
            transform[i, j] = (rotation[i, 0] * body_rotation[j, 0] + rotation[i, 1] * body_rotation[j, 1]
                               + rotation[i, 2] * body_rotation[j, 2])
    for i in range(3):
        shift[i] = position[i] - (transform[i, 0] * body_position[0] + transform[i, 1] * body_position[1]
                                  + transform[i, 2] * body_position[2])
    targets = np.empty((legs, 3))
    tips = np.empty((legs, 3))
    swinging = np.empty(legs, dtype=np.bool_)
    for leg in range(legs):
        swinging[leg] = progress[leg] >= 0.0
        lead = swing_s * (1.0 - progress[leg]) if swinging[leg] else swing_s
        ahead = (walker_targets[leg, 0] + lead * vx, walker_targets[leg, 1] + lead * vy, walker_targets[leg, 2])
        for i in range(3):
            targets[leg, i] = (transform[i, 0] * ahead[0] + transform[i, 1] * ahead[1] + transform[i, 2] * ahead[2]
                               + shift[i])
            tips[leg, i] = (transform[i, 0] * walker_tips[leg, 0] + transform[i, 1] * walker_tips[leg, 1]
                            + transform[i, 2] * walker_tips[leg, 2] + shift[i])
    yaw = math.atan2(rotation[1, 0], rotation[0, 0])
    _footholds(heights, top, span, cell, ci, cj, targets, tips, walker_targets, walker_tips, swinging, swing_height,
               edge_step, reach, clearance_margin, max_clearance, yaw, offsets, clearances, references)
    total, count = 0.0, 0
    for leg in range(legs):
        if not math.isnan(references[leg]):
            total += references[leg]
            count += 1
    if count == 0 or back <= 0.0:
        return -np.inf
    return _footprint_top(heights, cell, ci, cj, position[0], position[1], yaw, back, front, half_width) \
        - total / count


@dataclass(frozen=True, eq=False)
class TerrainMap:
    """A robot-centred grid of terrain heights and the body's pose in its frame (one scan's fused map).

    Attributes:
        heights: ``(n, n)`` heights [m] (``nan``: never seen), x index along +x; cell (i, j) is centred on
            ``((centre_i + i − n//2)·cell, (centre_j + j − n//2)·cell)``.
        cell: side of a cell [m].
        centre: the map's middle cell in whole cells of its frame.
        position: the body's position in the map's frame [m].
        rotation: the body's orientation (body → map frame, 3×3).
    """

    heights: np.ndarray
    cell: float
    centre: tuple[int, int]
    position: np.ndarray
    rotation: np.ndarray
    _levels: dict[int, tuple[np.ndarray, np.ndarray]] = field(default_factory=dict, repr=False)

    def levels(self, radius: int) -> tuple[np.ndarray, np.ndarray]:
        """Each cell's highest height and height span within ``radius`` cells (computed once per map)."""
        if radius not in self._levels:
            self._levels[radius] = _surroundings(np.asarray(self.heights, dtype=float), radius)
        return self._levels[radius]

    def height_at(self, x: float, y: float) -> float:
        """The height of the cell under (x, y) in the map's frame; ``nan`` if unknown or outside."""
        half = self.heights.shape[0] // 2
        i, j = _cell(float(x), float(y), self.cell, self.centre[0], self.centre[1], half)
        if 0 <= i < self.heights.shape[0] and 0 <= j < self.heights.shape[1]:
            return float(self.heights[i, j])
        return math.nan


@dataclass(frozen=True)
class StepPlaneSettings:
    """How the map shapes the steps (the robot file's ``[perception]`` values) [m]."""

    edge_margin: float = 0.05
    edge_step: float = 0.03
    max_shift: float = 0.1
    clearance_margin: float = 0.04
    max_clearance: float = 0.25
    max_slope: float = 0.25
    body_length: float = 0.0
    body_width: float = 0.0
    lookahead: float = 0.1


class StepPlanes:
    """The walker's step-plane input from each cycle's map (see the module's text).

    Args:
        legs: number of legs.
        settings: the robot file's values.
    """

    def __init__(self, legs: int, settings: StepPlaneSettings) -> None:
        self.settings = settings
        self.offsets = np.zeros((legs, 3))
        self.clearances = np.full(legs, np.nan)
        self.references = np.full(legs, np.nan)
        self._cell, self._radius, self._reach = 0.0, 0, 0
        self.body_floor = -np.inf
        """The highest ground under the body's footprint (and ``lookahead`` ahead of it) in the walk-plane frame
        [m] (-inf: not seen): the walker keeps the body at least its clearance above it."""

    def update(self, terrain: TerrainMap, walker_targets: np.ndarray, walker_tips: np.ndarray,
               body_position: np.ndarray, body_rotation: np.ndarray, progress: np.ndarray,
               swing_height: float, velocity: tuple[float, float] = (0.0, 0.0),
               swing_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """This cycle's (offsets ``(L, 3)``, clearances ``(L,)``) for the walker; sets :attr:`body_floor`.

        Args:
            terrain: the map and the body's pose in it.
            walker_targets: each leg's swing target before the shift, walk-plane frame ``(L, 3)``.
            walker_tips: each leg's walker tip, walk-plane frame ``(L, 3)``.
            body_position: the body pose's position in the walk-plane frame (the controller's current pose).
            body_rotation: its rotation (body → walk-plane frame).
            progress: each leg's swing progress this cycle (0…1; negative: in stance). A swinging leg keeps the
                clearance it had at lift-off.
            swing_height: the walker's swing height [m].
            velocity: the body's desired velocity (x, y) in the walk-plane frame [m/s] and ``swing_s`` a swing's
                duration [s]: a target is looked up where it will be in the map when its foot lands (the body
                moves on meanwhile; a stance leg's as if it lifted off now).
        """
        s = self.settings
        if terrain.cell != self._cell:  # (the whole cells of the margins, once per map resolution)
            self._cell = terrain.cell
            self._radius = max(0, math.ceil(s.edge_margin / terrain.cell - 1e-9))
            self._reach = max(0, round(s.max_shift / terrain.cell))
        top, span = terrain.levels(self._radius)
        self.body_floor = _step_plane(
            terrain.heights, top, span, terrain.cell, terrain.centre[0], terrain.centre[1], terrain.position,
            terrain.rotation, body_position, body_rotation, walker_targets, walker_tips, progress, swing_height,
            velocity[0], velocity[1], swing_s, s.edge_step, self._reach, s.clearance_margin, s.max_clearance,
            s.body_length / 2.0, s.body_length / 2.0 + s.lookahead, s.body_width / 2.0, self.offsets,
            self.clearances, self.references)
        return self.offsets, self.clearances
