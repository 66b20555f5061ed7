"""Per-leg workspaces and the common walkspace (study §3.1–§3.2).

A *workplane* maps a bearing [deg] to the distance [m] a tip can travel from its identity stance
position in that direction, found by walking the tip outwards in 2 mm steps with one OpenSHC IK
step each until the IK fails or a joint reaches a limit. All legs and bearings are searched at
once as one batch of chains. The *walkspace* is the largest radius per bearing that every leg can
reach and that keeps neighbouring legs' stepping areas apart, made symmetric (b and b + 180°).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shc_cli.model import kernels
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.ik import IK_TOLERANCE

BEARING_STEP_DEG = 45
MAX_POSITION_DELTA = 0.002
"""Tip step of the search [m]."""
MAX_WORKSPACE_RADIUS = 1.0
"""Search limit and the walkspace's initial radius [m]."""
ORIGIN_TRACK_DISTANCE = 0.1
"""Nominal distance covered by the steps that bring the tip to its identity position [m]."""


def bearings(count: int = 360 // BEARING_STEP_DEG) -> list[int]:
    """Search bearings in whole degrees, ``0, 360/count, …, 360`` (360 repeats 0)."""
    if count < 1 or 360 % count:
        raise ValueError(f"bearing count {count} must divide 360")
    step = 360 // count
    return list(range(0, 361, step))


Workplane = dict[int, float]
"""Bearing [deg] → radius [m]; contains 360 as a copy of 0."""


@dataclass(frozen=True)
class LegWorkspaces:
    """Result of the workspace search.

    Attributes:
        planes: workplane of each leg (single plane at height 0) by leg id.
        default_joints: joint positions after tracking each tip to its identity position, ``(L, n)``.
    """

    planes: dict[str, Workplane]
    default_joints: FloatArray


def search_workspaces(
    chains: Chains,
    default_joints: FloatArray,
    identity_tips: FloatArray,
    time_delta: float,
    bearing_count: int = 8,
) -> LegWorkspaces:
    """Search every leg's workplane in the body's horizontal plane (OpenSHC simple mode).

    Args:
        chains: the legs (one chain per leg).
        default_joints: joint positions of the default stance, ``(L, n)`` [rad].
        identity_tips: identity tip positions in base_link, ``(L, 3)`` [m] (stance x, y at −body_clearance).
        time_delta: control period used for the IK velocity term [s].
        bearing_count: number of search directions (8 = OpenSHC's 45° steps).
    """
    legs = chains.size
    q = np.array(default_joints, dtype=float)
    tip = chains.tips(q)
    reachable = np.linalg.norm(tip - identity_tips, axis=1) <= IK_TOLERANCE

    # Bring each tip to its identity position; the joints reached become the search's defaults.
    track_steps = max(1, round(ORIGIN_TRACK_DISTANCE / MAX_POSITION_DELTA))
    _linear_search(chains, q, tip, identity_tips, identity_tips, track_steps, time_delta)
    defaults = q

    # Walk outwards from the identity position along every bearing (0° itself is not searched: 0 := 360).
    angles = bearings(bearing_count)[1:]
    per_leg = len(angles)
    index = np.repeat(np.arange(legs), per_leg)
    batch = chains.take(index)
    radians = [b / 360.0 * 2.0 * math.pi for b in angles]
    directions = np.array([[MAX_WORKSPACE_RADIUS * math.cos(a), MAX_WORKSPACE_RADIUS * math.sin(a), 0.0]
                           for a in radians])
    origin = identity_tips[index]
    far = origin + np.tile(directions, (legs, 1))
    q = defaults[index].copy()
    search_steps = round(MAX_WORKSPACE_RADIUS / MAX_POSITION_DELTA)
    distance = _linear_search(batch, q, origin, far, origin, search_steps, time_delta)

    radii = distance.reshape(legs, per_leg)
    planes: dict[str, Workplane] = {}
    for leg_index, name in enumerate(chains.names):
        if not reachable[leg_index]:
            planes[name] = dict.fromkeys(bearings(bearing_count), 0.0)
            continue
        plane = {b: float(radii[leg_index, k]) for k, b in enumerate(angles)}
        plane[0] = plane[360]
        planes[name] = dict(sorted(plane.items()))
    return LegWorkspaces(planes, defaults)


def _linear_search(
    chains: Chains,
    q: FloatArray,
    start: FloatArray,
    end: FloatArray,
    origin: FloatArray,
    steps: int,
    time_delta: float,
) -> FloatArray:
    """Move each tip target from ``start`` to ``end`` in ``steps`` IK steps, stopping a chain at its
    first failed step (``q`` is updated in place).

    Returns each chain's distance from ``origin`` at its last step [m].
    """
    distance = np.zeros(chains.size)
    kernels.linear_search_kernel(
        chains.base, chains.d, chains.theta, chains.r, chains.alpha, chains.lower, chains.upper,
        chains.max_vel, q, np.ascontiguousarray(start), np.ascontiguousarray(end), np.ascontiguousarray(origin),
        steps, float(time_delta), True, distance,
    )
    return distance


def walkspace(
    planes: dict[str, Workplane],
    default_tips: dict[str, tuple[float, float]],
    overlapping: bool = False,
) -> Workplane:
    """The common, symmetric, non-overlapping walkspace (study §3.2).

    Args:
        planes: each leg's workplane, legs in id order.
        default_tips: each leg's default tip (x, y) in the walk plane [m].
        overlapping: skip the limit that keeps neighbouring legs' areas apart.
    """
    legs = list(planes)
    keys = list(next(iter(planes.values())))
    result = dict.fromkeys(keys, MAX_WORKSPACE_RADIUS)
    if not overlapping:
        for i, leg in enumerate(legs):
            x, y = default_tips[leg]
            for neighbour in (legs[(i - 1) % len(legs)], legs[(i + 1) % len(legs)]):
                nx, ny = default_tips[neighbour]
                half = math.hypot(nx - x, ny - y) / 2.0
                towards = math.degrees(math.atan2(ny - y, nx - x))
                for bearing in keys:
                    delta = abs(int(towards) % 360 - bearing)
                    if delta < 90 or delta > 270:
                        limit = half / math.cos(math.radians(delta))
                        result[bearing] = min(result[bearing], limit)
    for leg in legs:
        for bearing in keys:
            radius = planes[leg][bearing]
            if radius < result[bearing]:
                result[bearing] = radius
                result[(bearing + 180) % 360] = radius
    result[360] = result[0]
    return result


WORKSPACE_LAYERS = 10
"""Planes between the lowest and highest reachable tip heights in volumetric mode."""


def volumetric_workspaces(
    chains: Chains,
    default_joints: FloatArray,
    identity_tips: FloatArray,
    time_delta: float,
    bearing_count: int = 8,
) -> dict[str, dict[float, Workplane]]:
    """OpenSHC's volumetric (rough-terrain) workspace: a stack of workplanes per leg (study §3.1).

    Returns, per leg, height above the identity position [m] → workplane. The lowest and highest
    reachable heights carry zero-radius planes.
    """
    out: dict[str, dict[float, Workplane]] = {}
    angles = bearings(bearing_count)[1:]
    radians = [b / 360.0 * 2.0 * math.pi for b in angles]
    directions = np.array([[MAX_WORKSPACE_RADIUS * math.cos(a), MAX_WORKSPACE_RADIUS * math.sin(a), 0.0]
                           for a in radians])
    search_steps = round(MAX_WORKSPACE_RADIUS / MAX_POSITION_DELTA)
    for leg_index, name in enumerate(chains.names):
        chain = chains.take(np.array([leg_index]))
        defaults = np.array(default_joints[leg_index : leg_index + 1], dtype=float)
        identity = identity_tips[leg_index : leg_index + 1]
        zeros = dict.fromkeys(bearings(bearing_count), 0.0)
        if np.linalg.norm(chain.tips(defaults) - identity) > IK_TOLERANCE:
            out[name] = {0.0: zeros}
            continue
        vertical = identity + np.array([[0.0, 0.0, -MAX_WORKSPACE_RADIUS], [0.0, 0.0, MAX_WORKSPACE_RADIUS]])
        q = np.repeat(defaults, 2, axis=0)
        reach = _linear_search(chain.take(np.array([0, 0])), q, np.repeat(identity, 2, axis=0), vertical,
                               np.repeat(identity, 2, axis=0), search_steps, time_delta)
        lowest, highest = -float(reach[0]), float(reach[1])
        layer_step = (highest - lowest) / WORKSPACE_LAYERS
        stack: dict[float, Workplane] = {lowest: dict(zeros), highest: dict(zeros)}
        height = int(abs(highest) / layer_step) * layer_step if layer_step > 0 else 0.0
        track_steps = max(1, round(layer_step / MAX_POSITION_DELTA)) if layer_step > 0 else 1
        while height >= lowest and layer_step > 0:
            origin = identity + np.array([[0.0, 0.0, height]])
            _linear_search(chain, defaults, chain.tips(defaults), origin, origin, track_steps, time_delta)
            batch = chain.take(np.zeros(len(angles), dtype=np.int64))
            q = np.repeat(defaults, len(angles), axis=0)
            starts = np.repeat(origin, len(angles), axis=0)
            radii = _linear_search(batch, q, starts, starts + directions, starts, search_steps, time_delta)
            plane = {b: float(radius) for b, radius in zip(angles, radii, strict=True)}
            plane[0] = plane[360]
            stack.setdefault(height, dict(sorted(plane.items())))
            height -= layer_step
        out[name] = dict(sorted(stack.items()))
    return out


def polygon_area(plane: Workplane) -> float:
    """Area of the polygon through a workplane's vertices (radius r at bearing b) [m²]."""
    keys = [b for b in plane if b != 360]
    points = [(plane[b] * math.cos(math.radians(b)), plane[b] * math.sin(math.radians(b))) for b in keys]
    twice = sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in zip(points, points[1:] + points[:1], strict=True))
    return abs(twice) / 2.0


def plane_at(stack: dict[float, Workplane], height: float) -> Workplane:
    """Workplane at ``height`` [m] of a volumetric stack, by linear interpolation between the bounding layers."""
    heights = sorted(stack)
    if height <= heights[0]:
        return stack[heights[0]]
    if height >= heights[-1]:
        return stack[heights[-1]]
    upper = next(h for h in heights if h >= height)
    lower = max(h for h in heights if h <= height)
    if upper == lower:
        return stack[upper]
    share = (height - lower) / (upper - lower)
    return {b: stack[lower][b] * (1.0 - share) + stack[upper][b] * share for b in stack[lower]}

