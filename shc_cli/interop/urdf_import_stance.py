"""The standing pose of an imported robot (``shc import urdf``; the rules are in
:mod:`shc_cli.interop.urdf_import`'s docstring, **Stance**)."""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.interop.urdf_import_tree import Imported, LegChain, _fail

FloatArray = NDArray[np.float64]


STANDING = 0.25
"""The zero pose stands if every foot is at least this share of its leg's length below its hip."""
STRAIGHT = 0.97
"""A leg whose zero-pose tip is this share of its length from its hip is straight (a singular pose)."""
SWING_SHARE = 0.2
"""Swing height written, as a share of the body clearance; a stance must reach this much higher too."""
TIE = 0.95
"""Stances whose walkspace is at least this share of the best are as good: the first (most natural) is taken."""
FRACTIONS = [0.5, 0.4, 0.6, 0.3, 0.7, 0.2]
"""Shares of the leg's length tried for the stance's reach and the body's height (most natural first)."""
FAR = [0.75, 0.8, 0.85, 0.9]
"""Reaches tried when none of :data:`FRACTIONS` stands (a knee limit that keeps the leg nearly straight)."""
HEIGHTS = [round(0.05 * k, 2) for k in range(1, 15)]
"""Body heights tried with the reaches of :data:`FAR`, as shares of the leg's length (a narrow band may fit)."""
GROUND = 1e-4
"""A stance whose joints (the DH frames on their axes) are more than this below the feet is refused [m]."""
MIN_SWING = 0.01
"""Smallest swing height written [m] (``walker.swing_height.min``)."""
JOINT_SHARES = (0.3, 0.5, 0.7)
"""Shares of each joint's range whose feet are tried as stances when none of the reach and height search
stands (narrow limits)."""
JOINT_GRID_JOINTS = 3
"""How many joints of a leg (from the hip) :data:`JOINT_SHARES` are spread over; the rest sit at the centre."""
SEED_POSES = 729
"""Joint vectors per leg the stance search may start its IK from when OpenSHC's initial pose does not reach."""


# -- stance ----------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Stance:
    """The standing pose: per-leg stance (x, y) [m], body clearance [m], unpacked joints [rad], how it was chosen
    and its walkspace (the smallest radius over the bearings) [m]."""

    xy: list[tuple[float, float]]
    clearance: float
    unpacked: FloatArray
    how: str
    walkspace: float
    swing: float | None = None
    """Swing height the legs' limits allow, when less than :data:`SWING_SHARE` of the clearance [m]."""


def choose_stance(robot_tree: dict[str, Any], legs: list[LegChain], clearance: float | None,
                  reach: float | None, time_delta: float) -> Stance | None:
    """The standing pose (module docstring); None if no candidate is reachable by every leg."""
    from shc_cli.model.chains import Chains
    from shc_cli.spec.robot import Robot

    stub = {**robot_tree, "legs": {leg.leg_id: {**robot_tree["legs"][leg.leg_id], "stance": {"x": 0.0, "y": 0.0}}
                                   for leg in legs}}
    chains = Chains.from_robot(Robot.model_validate(stub))
    lengths = np.array([_length(leg) for leg in legs])
    hips = np.array([leg.hip for leg in legs])
    zero_tips = np.array([leg.tip for leg in legs])
    drop = hips[:, 2] - zero_tips[:, 2]
    candidates: list[tuple[FloatArray, float, str]] = []
    if clearance is None and reach is None and (drop >= STANDING * lengths).all():
        # Legs straight at the zero pose (common for quadrupeds) stand at a singularity: lower the body first.
        straight = bool((np.linalg.norm(zero_tips - hips, axis=1) >= STRAIGHT * lengths).any())
        depth, hip_z = float(drop.mean()), float(hips[:, 2].mean())
        for share in ([] if straight else [1.0]) + [0.9, 0.8, 0.7, 0.6]:
            what = ("the URDF's zero pose" if share == 1.0 else
                    f"the zero pose's feet, the body lowered to {share:g} of their depth below the hips")
            candidates.append((zero_tips[:, :2], share * depth - hip_z, what))
    groups = [candidates]
    candidates = []
    groups.append(candidates)
    # The search (also the fallback of a zero pose no leg can stand in).
    outward = zero_tips[:, :2] - hips[:, :2]
    norms = np.linalg.norm(outward, axis=1)
    fallback = hips[:, :2] / np.maximum(np.linalg.norm(hips[:, :2], axis=1), 1e-9)[:, None]
    direction = np.where((norms > 0.1 * lengths)[:, None], outward / np.maximum(norms, 1e-9)[:, None], fallback)
    length, hip_z = float(np.median(lengths)), float(np.median(hips[:, 2]))
    for reaches in ([[reach]] if reach is not None else [FRACTIONS, FAR]):
        for f_reach in reaches:
            for f_height in [None] if clearance is not None else FRACTIONS if reaches is FRACTIONS else HEIGHTS:
                height = clearance if clearance is not None else f_height * length - hip_z  # type: ignore[operator]
                if height <= 0.0:
                    continue
                xy = hips[:, :2] + direction * (f_reach * lengths)[:, None]
                what = (f"feet {f_reach:g} of the leg's length out from the hips"
                        + ("" if clearance is not None else f", body {f_height:g} of it above the hips"))
                candidates.append((xy, float(height), what))
        if reach is None and reaches is FRACTIONS:
            candidates = []
            groups.append(candidates)
    seeds = _seeds(chains)
    for group in groups:
        scored = [stance for stance in (_try(chains, xy, height, what, time_delta, seeds)
                                        for xy, height, what in group) if stance is not None]
        if scored:
            best = max(stance.walkspace for stance in scored)
            return next(stance for stance in scored if stance.walkspace >= TIE * best)
    if clearance is not None or reach is not None:
        return None
    for group_poses in _joint_poses(chains):  # narrow limits: the feet where poses inside the limits put them
        scored = []
        for q, what in group_poses:
            tips = chains.tips(q)
            height = float(np.median(-tips[:, 2]))
            if height <= 0.0:
                continue
            with_pose = ((q[None], tips[None]) if seeds is None else
                         (np.concatenate([seeds[0], q[None]]), np.concatenate([seeds[1], tips[None]])))
            lifts = tuple(lift for lift in (0.5 * SWING_SHARE * height, MIN_SWING) if lift >= MIN_SWING)
            stance = _try(chains, tips[:, :2], height, what, time_delta, with_pose, lifts)
            if stance is not None:
                scored.append(stance)
        if scored:
            best = max(stance.walkspace for stance in scored)
            return next(stance for stance in scored if stance.walkspace >= TIE * best)
    return None


def _joint_poses(chains: Any) -> list[list[tuple[FloatArray, str]]]:
    """Joint vectors inside the limits whose feet are stances to try when no stance of the reach and height
    search stands (narrow limits): every joint at the centre of its range, then (a group) the first
    :data:`JOINT_GRID_JOINTS` joints at each of :data:`JOINT_SHARES` of theirs, the others at the centre."""
    def at(shares: tuple[float, ...]) -> FloatArray:
        full = np.full(chains.joints, 0.5)
        full[:len(shares)] = shares
        return np.asarray(chains.lower + full[None] * (chains.upper - chains.lower), dtype=np.float64)

    centre = [(at(()), "the feet where every joint is at the centre of its limits")]
    count = min(chains.joints, JOINT_GRID_JOINTS)
    grid = [(at(shares), "the feet where the joints are at " + ", ".join(f"{s:g}" for s in shares)
             + " of their ranges" + (", the rest at the centre" if count < chains.joints else ""))
            for shares in itertools.product(JOINT_SHARES, repeat=count) if set(shares) != {0.5}]
    return [centre, grid]


def _seeds(chains: Any) -> tuple[FloatArray, FloatArray]:
    """Joint vectors spread over every leg's limits (about :data:`SEED_POSES` of them, the same share of each
    joint's range for every leg) and their tips: ``(q (G, B, n) [rad], tips (G, B, 3) [m])``."""
    steps = max(2, round(SEED_POSES ** (1.0 / chains.joints)))
    shares = np.linspace(0.0, 1.0, steps + 2)[1:-1]  # inside the limits, not on them
    grid = np.array(list(itertools.product(shares, repeat=chains.joints)))
    q = chains.lower[None] + grid[:, None, :] * (chains.upper - chains.lower)[None]
    return q, np.array([chains.tips(pose) for pose in q])


def _try(chains: Any, xy: FloatArray, height: float, what: str, time_delta: float,
         seeds: tuple[FloatArray, FloatArray] | None = None, lifts: tuple[float, ...] = ()) -> Stance | None:
    """The stance if every leg reaches it with no joint below its feet, and its swing apex
    (:data:`SWING_SHARE` of the clearance higher, else the first of ``lifts`` [m] that every leg reaches) within
    its limits, with its walkspace; None otherwise. The IK starts from OpenSHC's initial pose (every joint at 0
    within its limits), else (a zero pose far from any standing pose: legs straight up) from each leg's pose of
    ``seeds`` whose tip is nearest its foot."""
    from shc_cli.model.ik import solve
    from shc_cli.model.workspace import search_workspaces, walkspace

    xy, height = np.round(xy, 4), round(height, 4)
    if height <= 0.0:
        return None
    spread = np.linalg.norm(xy[:, None] - xy[None], axis=2) + np.eye(len(xy))
    if spread.min() < 0.03:
        return None
    targets = np.column_stack([xy, np.full(len(xy), -height)])
    q, error = solve(chains, chains.default_joints(), targets, tolerance=1e-5, max_steps=600, dt=time_delta)
    if not (error < 1e-4).all() and seeds is not None:
        nearest = np.linalg.norm(seeds[1] - targets[None], axis=2).argmin(axis=0)
        start = seeds[0][nearest, np.arange(len(targets))]
        q, error = solve(chains, start, targets, tolerance=1e-5, max_steps=600, dt=time_delta)
    if not (error < 1e-4).all():
        return None
    joints_z = chains.frames_in_base(q[None])[0][:, 1:-1, 2, 3]
    if joints_z.size and float(joints_z.min()) < -height - GROUND:
        return None  # a knee (a joint's axis point) below the feet: the link would stand in the ground
    swing = None
    for lift in (SWING_SHARE * height, *lifts):
        apex = targets + np.array([0.0, 0.0, lift])
        _, lifted = solve(chains, q, apex, tolerance=1e-5, max_steps=300, dt=time_delta)
        if (lifted < 1e-4).all():
            swing = None if lift == SWING_SHARE * height else lift
            break
    else:
        return None
    planes = search_workspaces(chains, q, targets, time_delta).planes
    radius = min(walkspace(planes, {leg: (float(x), float(y)) for leg, (x, y) in zip(chains.names, xy,
                                                                                      strict=True)}).values())
    return Stance([(float(x), float(y)) for x, y in xy], height, q, what, radius, swing)


def _length(leg: LegChain) -> float:
    """Length of the leg at the zero pose: through the joint origins to the tip [m]."""
    points = [leg.hip, *leg.points, leg.tip]
    return float(sum(np.linalg.norm(b - a) for a, b in itertools.pairwise(points)))


def _finish(imported: Imported, clearance: float | None, reach: float | None, file: Path) -> None:
    """Add the stance, clearance, unpacked pose and swing height to the tree."""
    stance = choose_stance(imported.tree, imported.legs, clearance, reach, imported.tree["time_delta"])
    if stance is None and (clearance is not None or reach is not None):
        raise _fail(file, *_why_not(imported, clearance, reach))
    if stance is None:
        problem, fix = _why_not(imported, None, None)
        raise _fail(file, "no standing pose found that every leg reaches within its joint limits, with the feet "
                    f"{min(FRACTIONS):g}–{max(FAR):g} of the leg's length out and the body "
                    f"{min(HEIGHTS):g}–{max(HEIGHTS):g} of it above the hips, nor where poses across the joint "
                    f"ranges put them: {problem}", f"{fix}, or check the legs' joint limits")
    walker = imported.tree["walker"]
    walker["body_clearance"] = stance.clearance
    swing = round(min(max(SWING_SHARE * stance.clearance, MIN_SWING), 0.2), 3)
    why = "a fifth of the clearance"
    if stance.swing is not None:
        swing, why = round(stance.swing, 3), "as high as every leg's joint limits lift the foot from the stance"
    walker["swing_height"] = {"default": swing, "min": MIN_SWING, "max": max(0.05, round(2 * swing, 3)),
                              "step": 0.005}
    for i, chain in enumerate(imported.legs):
        leg = imported.tree["legs"][chain.leg_id]
        leg["stance"] = {"x": stance.xy[i][0], "y": stance.xy[i][1]}
        for k, joint in enumerate(leg["joints"].values()):
            joint["unpacked"] = float(np.clip(round(float(stance.unpacked[i, k]), 4), joint["min"], joint["max"]))
    imported.notes.insert(0, f"stance and body clearance: {stance.how}")
    imported.notes.insert(1, f"gait {walker['gait']}, swing height {swing:g} m ({why}), control period 0.01 s, "
                             "everything else shc's defaults")


def _why_not(imported: Imported, clearance: float | None, reach: float | None) -> tuple[str, str]:
    """Problem and fix of a stance the user asked for that a leg cannot take: the leg, the joint limit in the
    way, and the range of the other value (or of the one given) that stands."""
    from shc_cli.model.chains import Chains
    from shc_cli.model.ik import solve
    from shc_cli.spec.robot import Robot

    legs = imported.legs
    stub = {**imported.tree, "legs": {leg.leg_id: {**imported.tree["legs"][leg.leg_id],
                                                   "stance": {"x": 0.0, "y": 0.0}} for leg in legs}}
    chains = Chains.from_robot(Robot.model_validate(stub))
    lengths = np.array([_length(leg) for leg in legs])
    hips = np.array([leg.hip for leg in legs])
    outward = np.array([leg.tip[:2] - leg.hip[:2] for leg in legs])
    norms = np.linalg.norm(outward, axis=1)
    fallback = hips[:, :2] / np.maximum(np.linalg.norm(hips[:, :2], axis=1), 1e-9)[:, None]
    direction = np.where((norms > 0.1 * lengths)[:, None], outward / np.maximum(norms, 1e-9)[:, None], fallback)
    hip_z = float(np.median(hips[:, 2]))
    length = float(np.median(lengths))

    def attempt(f_reach: float, height: float) -> tuple[FloatArray, FloatArray]:
        targets = np.column_stack([hips[:, :2] + direction * (f_reach * lengths)[:, None],
                                   np.full(len(legs), -height)])
        return solve(chains, chains.default_joints(), targets, tolerance=1e-5, max_steps=600)

    f_reach = reach if reach is not None else 0.5
    height = clearance if clearance is not None else 0.3 * length - hip_z
    q, error = attempt(f_reach, height)
    worst = int(np.argmax(error))
    leg = legs[worst]
    lower, upper = chains.lower[worst], chains.upper[worst]
    at = [k for k in range(len(leg.joints)) if min(abs(q[worst, k] - lower[k]), abs(q[worst, k] - upper[k])) < 1e-3]
    limit = (", ".join(f"{leg.names[k]} at its {'lower' if abs(q[worst, k] - lower[k]) < 1e-3 else 'upper'} limit "
                       f"{lower[k] if abs(q[worst, k] - lower[k]) < 1e-3 else upper[k]:.3g} rad" for k in at)
             or "out of reach")
    asked = " and ".join(part for part in (f"clearance {clearance:g} m" if clearance is not None else "",
                                           f"reach {reach:g}" if reach is not None else "") if part) or \
        f"the feet {f_reach:g} of its length out and the body {height:.3g} m below the base"
    problem = f"leg {leg.leg_id} cannot stand with {asked} ({limit}, {error[worst] * 1000:.0f} mm short)"
    works: list[float] = []
    if clearance is not None:
        for share in np.arange(0.1, 0.96, 0.05):
            if (attempt(float(share), clearance)[1] < 1e-4).all():
                works.append(float(share))
        if works:
            return problem, (f"with clearance {clearance:g} m every leg stands at --reach {min(works):.2g} to "
                             f"{max(works):.2g}")
    heights = [float(h) for h in np.arange(0.01, 1.5 * length, 0.005)]
    works = [h for h in heights if (attempt(f_reach, h)[1] < 1e-4).all()]
    if works:
        return problem, f"with reach {f_reach:g} every leg stands at --clearance {min(works):.3g} to {max(works):.3g} m"
    return problem, "give a smaller --reach or --clearance, or widen that joint's limits"

