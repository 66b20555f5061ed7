"""``shc import urdf``: a legged robot's URDF (or xacro) → an shc robot file and a joint map.

* **Body**: the URDF's root link and every link fixed to it. shc's ``base_link`` is the URDF link
  ``base_link`` if it is one of them, else the root; the body's mass, centre of mass and principal moments
  (the diagonal of the summed inertia) are those of these links; its box is the collision box of the base
  link, else the box around the hips.
* **Legs**: the serial chains from the body to each leaf link that pass a revolute joint (``--legs auto``); a
  leaf whose moving joints are all on a longer chain (a sensor fixed to a femur) is not a leg of its own, and
  of leaves on the same joints the one with a sphere (else the deepest) is the foot. Fixed joints fold into
  the transforms. ``--legs LINK,…`` (or ``ID=LINK,…``) names the tip links instead, ``--tip PATTERN[@X,Y,Z]``
  names tip links by glob pattern and the tip point in their frame.
* **Tip**: the centre of the tip link's first collision sphere, else its frame origin (``--tip`` names it).
* **DH**: :mod:`shc_cli.interop.urdf_import_dh`: exact for any axes; URDF angle = shc angle.
* **Leg ids** by position (the mean of the leg's joint origins and tip at the zero pose: a joint's origin may
  be anywhere on its axis), clockwise from the front right: with as many legs on the right (y < 0) as on the
  left, ``AR, BR, …`` down the right side and ``…, BL, AL`` up the left
  (4 legs: AR BR BL AL, 6: AR BR CR CL BL AL, 8: AR BR CR DR DL CL BL AL); otherwise ``L1 … Ln`` in that order.
* **Joint names**: the URDF names without what all joints of the leg share (``AR_coxa_joint`` → ``coxa``), else
  ``joint1 …``.
* **Limits**: URDF ``lower``/``upper``, ``velocity`` → ``max_vel``, the most common ``effort`` and ``velocity``
  → ``servo.stall_torque`` and ``servo.no_load_speed``. **Masses**: each joint carries the links it moves
  up to the next joint of its leg; links moved by joints that are in no leg count as body (listed).
* **Stance**: candidates are tried in order and the first whose walkspace (``shc workspace``'s smallest radius)
  is within 5 % of the best is taken; every leg must reach its foot, and the swing apex a fifth of the
  clearance above it, within its limits. If the zero pose's feet stand below the hips (by at least a quarter
  of the leg's length), the candidates are the zero pose and the body lowered to 0.9 … 0.6 of the feet's depth
  (not the zero pose itself if a leg is straight there: a singular pose). Otherwise, or if none of those is
  reachable, each foot is put 0.5, 0.4, 0.6, 0.3, 0.7 or 0.2 of the leg's length out from its hip (along the
  zero pose's leg direction) with the body as many shares of a leg's length above the hips. ``--clearance``
  and ``--reach`` fix either. ``unpacked`` is the pose the IK finds there from every joint at 0.
"""

from __future__ import annotations

import csv
import fnmatch
import io
import itertools
import math
import re
import tempfile
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.errors import Issue, SpecError
from shc_cli.interop.urdf_import_dh import Axis, NearlyParallel, Row, chain_dh
from shc_cli.interop.urdf_import_source import SUGGESTED_SNAP, parse_urdf, read_source
from shc_cli.spec.toml_out import dump_toml

FloatArray = NDArray[np.float64]

STANDING = 0.25
"""The zero pose stands if every foot is at least this share of its leg's length below its hip."""
STRAIGHT = 0.97
"""A leg whose zero-pose tip is this share of its length from its hip is straight (a singular pose)."""
SWING_SHARE = 0.2
"""Swing height written, as a share of the body clearance; a stance must reach this much higher too."""
TIE = 0.95
"""Stances whose walkspace is at least this share of the best are as good: the first (most natural) is taken."""
GAITS = {4: "quad_wave", 6: "tripod", 8: "octo_alternating"}
"""Gait written for a robot with this many legs (others get ``wave``, which fits none but six legs)."""
FK_SAMPLES = 200
"""Random joint vectors per leg of the forward-kinematics check after writing."""
UNSUPPORTED = {"prismatic": "slides", "continuous": "has no limits", "planar": "moves in a plane",
               "floating": "moves freely"}
"""Joint types a leg cannot contain, and why."""


def _fail(path: Path, problem: str, fix: str) -> SpecError:
    return SpecError([Issue(path, None, "", problem, fix)])


@dataclass(frozen=True)
class TipSpec:
    """A ``--tip`` value: links matching ``pattern`` end legs; ``point`` is the tip in that link's frame [m]."""

    pattern: str
    point: tuple[float, float, float] | None

    @classmethod
    def parse(cls, text: str) -> TipSpec:
        pattern, _, point = text.partition("@")
        if not point:
            return cls(pattern, None)
        try:
            x, y, z = (float(v) for v in point.split(","))
        except ValueError:
            raise SpecError([Issue(None, None, "--tip", f"'{text}' is not LINK or LINK@X,Y,Z",
                                   "e.g. --tip '*_foot' or --tip 'AR_tarsus_link@0.173,0,0' (metres)")]) from None
        return cls(pattern, (x, y, z))


@dataclass
class LegChain:
    """One leg found in the URDF, before naming: its joints, its tip and the DH rows."""

    end: str
    joints: list[Any]
    tip_local: FloatArray
    tip_source: str
    sphere: float
    hip: FloatArray = field(default_factory=lambda: np.zeros(3))
    points: list[FloatArray] = field(default_factory=list)
    tip: FloatArray = field(default_factory=lambda: np.zeros(3))
    base: Row | None = None
    rows: list[Row] = field(default_factory=list)
    leg_id: str = ""
    names: list[str] = field(default_factory=list)
    masses: list[float] = field(default_factory=list)


@dataclass
class Imported:
    """What the import produced: the robot table tree, the legs and the notes for the file's header."""

    tree: dict[str, Any]
    legs: list[LegChain]
    base_frame: str
    notes: list[str]


# -- the URDF as a tree ----------------------------------------------------------------------------------------


class Tree:
    """Links and joints of a yourdfpy model with zero-pose transforms in the shc base frame."""

    def __init__(self, model: Any) -> None:
        self.model = model
        self.joints = {j.name: j for j in model.robot.joints}
        self.links = {link.name: link for link in model.robot.links}
        self.parent_joint = {j.child: j for j in model.robot.joints}
        self.children: dict[str, list[Any]] = {name: [] for name in self.links}
        for joint in model.robot.joints:
            self.children.setdefault(joint.parent, []).append(joint)
        self.root = str(model.base_link)
        self.skipped: list[str] = []
        while len(self.children.get(self.root, [])) == 1 and self.children[self.root][0].type in ("floating", "planar"):
            self.skipped.append(self.root)  # a 'world' link holding the robot by a free joint
            self.root = self.children[self.root][0].child
        self.body = self._fixed_set(self.root)
        self.base_frame = "base_link" if "base_link" in self.body else self.root
        world = self._world()
        inverse = np.linalg.inv(world[self.base_frame])
        self.pose = {name: inverse @ transform for name, transform in world.items()}

    def _fixed_set(self, start: str) -> list[str]:
        out, stack = [], [start]
        while stack:
            link = stack.pop()
            out.append(link)
            stack += [j.child for j in self.children.get(link, []) if j.type == "fixed"]
        return out

    def _world(self) -> dict[str, FloatArray]:
        world = {name: np.eye(4) for name in self.skipped}
        world[self.root] = np.eye(4)
        stack = [self.root]
        while stack:
            link = stack.pop()
            for joint in self.children.get(link, []):
                origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin, dtype=float)
                world[joint.child] = world[link] @ origin
                stack.append(joint.child)
        return world

    def path(self, link: str) -> list[Any]:
        """Joints from the body to ``link``, body first."""
        out = []
        while link not in self.body and link in self.parent_joint:
            joint = self.parent_joint[link]
            out.append(joint)
            link = joint.parent
        return out[::-1]

    def joint_frame(self, joint: Any) -> FloatArray:
        """The joint's frame at the zero pose (= its child link's frame) in the base frame."""
        return self.pose[joint.child]

    def leaves(self) -> list[str]:
        return [name for name in self.links
                if not self.children.get(name) and name not in self.body and name not in self.skipped]


def _sphere(link: Any) -> tuple[FloatArray, float] | None:
    """Centre (in the link frame) and radius of the link's first collision sphere."""
    for collision in link.collisions or []:
        if collision.geometry is not None and collision.geometry.sphere is not None:
            origin = np.eye(4) if collision.origin is None else np.asarray(collision.origin, dtype=float)
            return origin[:3, 3].copy(), float(collision.geometry.sphere.radius)
    return None


# -- legs ------------------------------------------------------------------------------------------------------


def _moving(path: list[Any]) -> list[Any]:
    return [joint for joint in path if joint.type != "fixed"]


def _auto_ends(tree: Tree, file: Path) -> list[str]:
    """Leaf links ending legs (module docstring)."""
    sets = {leaf: frozenset(j.name for j in _moving(tree.path(leaf))) for leaf in tree.leaves()}
    sets = {leaf: joints for leaf, joints in sets.items() if joints}
    maximal = {leaf: joints for leaf, joints in sets.items() if not any(joints < other for other in sets.values())}
    by_set: dict[frozenset[str], list[str]] = {}
    for leaf, joints in maximal.items():
        by_set.setdefault(joints, []).append(leaf)
    ends = []
    for leaves in by_set.values():
        leaves.sort(key=lambda leaf: (_sphere(tree.links[leaf]) is None, -len(tree.path(leaf)), leaf))
        ends.append(leaves[0])
    if not ends:
        raise _fail(file, f"no legs found: no chain from the body ({tree.root}) to a leaf link passes a revolute "
                    "joint", "give a URDF of a legged robot, or name the feet with --legs LINK,LINK,…")
    return ends


def _check_serial(legs: list[LegChain], file: Path) -> None:
    owner: dict[str, str] = {}
    for leg in legs:
        for joint in leg.joints:
            if joint.name in owner:
                raise _fail(file, f"the chains to {owner[joint.name]} and {leg.end} share joint {joint.name}: a leg "
                            "must be a serial chain", "name the feet with --legs LINK,LINK,… or --tip")
            owner[joint.name] = leg.end


def _chain(tree: Tree, end: str, tip: TipSpec | None, file: Path) -> LegChain:
    path = tree.path(end)
    for joint in path:
        if joint.type in UNSUPPORTED:
            raise _fail(file, f"joint {joint.name} on the leg to {end} is {joint.type} (it {UNSUPPORTED[joint.type]})"
                        ": shc legs have revolute joints only",
                        "make it revolute with <limit lower upper>, end the leg before it with --tip LINK, or "
                        "leave the leg out with --legs")
        if joint.mimic is not None:
            raise _fail(file, f"joint {joint.name} on the leg to {end} mimics {joint.mimic.joint}: shc legs have "
                        "independent joints", "leave this leg out with --legs")
        if joint.type == "revolute" and joint.limit is None:
            raise _fail(file, f"revolute joint {joint.name} has no <limit>", "give it lower and upper limits")
        if joint.type == "revolute" and not (joint.limit.lower or 0.0) < (joint.limit.upper or 0.0):
            raise _fail(file, f"revolute joint {joint.name} has lower {joint.limit.lower} >= upper "
                        f"{joint.limit.upper}", "give it a range (lower < upper), or make it fixed")
    moving = _moving(path)
    if not moving:
        raise _fail(file, f"no revolute joint between the body and {end}", "name a link of a leg")
    sphere = _sphere(tree.links[end])
    if tip is not None and tip.point is not None:
        local, source, radius = np.array(tip.point), f"the point {tip.point} in {end} (--tip)", 0.0
    elif sphere is not None:
        local, source, radius = sphere[0], f"the centre of {end}'s collision sphere", sphere[1]
    else:
        local, source, radius = np.zeros(3), f"the origin of {end}", 0.0
    return LegChain(end=end, joints=moving, tip_local=local, tip_source=source, sphere=radius)


def find_legs(tree: Tree, legs: str, tips: list[TipSpec], file: Path) -> list[tuple[str | None, LegChain]]:
    """The legs' chains, each with the id given by ``--legs ID=LINK`` (else None)."""
    named: list[tuple[str | None, str]] = []
    if legs != "auto":
        for item in (part.strip() for part in legs.split(",") if part.strip()):
            given, _, link = item.rpartition("=")
            if link not in tree.links:
                raise _fail(file, f"--legs: no link '{link}' in this URDF",
                            f"name leaf links, e.g. {', '.join(tree.leaves()[:3])}")
            named.append((given or None, link))
    elif tips:
        matched = [link for link in tree.links if any(fnmatch.fnmatchcase(link, t.pattern) for t in tips)]
        if not matched:
            raise _fail(file, f"--tip: no link matches {', '.join(t.pattern for t in tips)}",
                        f"give link names or glob patterns, e.g. {', '.join(tree.leaves()[:3])}")
        named = [(None, link) for link in matched]
    else:
        named = [(None, link) for link in _auto_ends(tree, file)]
    out: list[tuple[str | None, LegChain]] = []
    for leg_id, link in named:
        spec = next((t for t in tips if fnmatch.fnmatchcase(link, t.pattern)), None)
        out.append((leg_id, _chain(tree, link, spec, file)))
    _check_serial([chain for _, chain in out], file)
    return out


def leg_ids(hips: list[FloatArray]) -> tuple[list[str], list[int]]:
    """Ids and file order of legs at ``hips`` (module docstring): ``(ids by leg, order)``."""
    key = [(-math.atan2(float(h[1]), float(h[0]))) % (2.0 * math.pi) for h in hips]
    order = sorted(range(len(hips)), key=lambda i: key[i])
    count = len(hips)
    half = count // 2
    ids = [""] * count
    right, left = order[:half], order[half:]
    if count % 2 == 0 and 0 < half <= 26 and all(hips[i][1] < 0 for i in right) and all(hips[i][1] > 0 for i in left):
        for rank, i in enumerate(right):
            ids[i] = f"{chr(ord('A') + rank)}R"
        for rank, i in enumerate(reversed(left)):
            ids[i] = f"{chr(ord('A') + rank)}L"
    else:
        for rank, i in enumerate(order):
            ids[i] = f"L{rank + 1}"
    return ids, order


def _tokens(name: str) -> list[str]:
    return [t for t in re.split(r"[^A-Za-z0-9]+", name) if t]


def joint_names(legs: list[list[str]]) -> list[list[str]]:
    """shc joint names for each leg's URDF joint names (module docstring)."""
    short = []
    for names in legs:
        token_lists = [_tokens(name) for name in names]
        shared = set.intersection(*(set(t) for t in token_lists)) if len(names) > 1 else set()
        shared |= {"joint", "Joint", "JOINT", "jnt"}
        stripped = ["_".join(t for t in tokens if t not in shared) for tokens in token_lists]
        short.append(stripped)
    width = max(len(names) for names in legs)
    chosen = []
    for k in range(width):
        counts = Counter(names[k] for names in short if len(names) > k and names[k])
        chosen.append(counts.most_common(1)[0][0] if counts else "")
    out = []
    for names in short:
        picked = [chosen[k] or f"joint{k + 1}" for k in range(len(names))]
        picked = [re.sub(r"[^A-Za-z0-9_]", "_", name) for name in picked]
        if len(set(picked)) < len(picked) or not all(name[0].isalpha() for name in picked):
            picked = [f"joint{k + 1}" for k in range(len(names))]
        out.append(picked)
    return out


# -- masses ----------------------------------------------------------------------------------------------------


def _inertial(tree: Tree, link: str) -> tuple[float, FloatArray, FloatArray] | None:
    """Mass, centre of mass and inertia tensor (about it, base axes) of a link at the zero pose."""
    inertial = tree.links[link].inertial
    if inertial is None or inertial.mass is None or inertial.mass <= 0.0:
        return None
    origin = np.eye(4) if inertial.origin is None else np.asarray(inertial.origin, dtype=float)
    pose = tree.pose[link] @ origin
    tensor = np.zeros((3, 3)) if inertial.inertia is None else np.asarray(inertial.inertia, dtype=float)
    return float(inertial.mass), pose[:3, 3], pose[:3, :3] @ tensor @ pose[:3, :3].T


def _body(tree: Tree, extra: list[str], hips: list[FloatArray]) -> tuple[dict[str, Any], list[str]]:
    """The ``[body]`` table from the body links (and ``extra`` links moved by joints of no leg)."""
    notes = []
    parts = [p for p in (_inertial(tree, link) for link in [*tree.body, *extra]) if p is not None]
    mass = sum(p[0] for p in parts)
    body: dict[str, Any] = {}
    if mass > 0.0:
        com = np.sum([p[0] * p[1] for p in parts], axis=0) / mass
        tensor = sum(p[2] + p[0] * (np.dot(p[1] - com, p[1] - com) * np.eye(3) - np.outer(p[1] - com, p[1] - com))
                     for p in parts)
        body["mass"] = _round(mass, 6)
        body["com"] = [_round(float(v), 6) for v in com]
        body["inertia"] = [_round(float(v), 9) for v in np.diag(np.asarray(tensor))]
    else:
        notes.append("the body links have no mass: body.mass is shc's default, 1 kg")
    box = next((c for c in tree.links[tree.base_frame].collisions or []
                if c.geometry is not None and c.geometry.box is not None), None)
    if box is not None:
        body["size"] = [_round(float(v), 6) for v in box.geometry.box.size]
    else:
        spread = np.array(hips)
        size = [max(float(np.ptp(spread[:, 0])), 0.05), max(float(np.ptp(spread[:, 1])), 0.05), 0.05]
        body["size"] = [_round(v, 4) for v in size]
        notes.append("the base link has no collision box: body.size is the box around the hips, 0.05 m high")
    return body, notes


def _round(value: float, digits: int) -> float:
    out = round(value, digits)
    return 0.0 if out == 0.0 else out


DH_DIGITS = 12
"""DH values are written rounded to this many decimals (m, rad): round-off noise goes, FK moves < 1e-11 m."""


def _dh_values(row: Row) -> dict[str, float]:
    """The row rounded to :data:`DH_DIGITS`, angles in (−π, π] (−π written as π)."""
    def angle(value: float) -> float:
        wrapped = _round(math.remainder(value, 2.0 * math.pi), DH_DIGITS)
        return _round(math.pi, DH_DIGITS) if wrapped <= -_round(math.pi, DH_DIGITS) else wrapped

    return {"d": _round(row.d, DH_DIGITS), "theta": angle(row.theta), "r": _round(row.r, DH_DIGITS),
            "alpha": angle(row.alpha)}


def _moved_by(tree: Tree, link: str) -> str | None:
    """The last moving joint between the body and ``link`` (None for body links)."""
    moving = _moving(tree.path(link))
    return moving[-1].name if moving else None


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
    fractions = [0.5, 0.4, 0.6, 0.3, 0.7, 0.2]
    length, hip_z = float(np.median(lengths)), float(np.median(hips[:, 2]))
    for f_reach in [reach] if reach is not None else fractions:
        for f_height in [None] if clearance is not None else fractions:
            height = clearance if clearance is not None else f_height * length - hip_z  # type: ignore[operator]
            if height <= 0.0:
                continue
            xy = hips[:, :2] + direction * (f_reach * lengths)[:, None]
            what = (f"feet {f_reach:g} of the leg's length out from the hips"
                    + ("" if clearance is not None else f", body {f_height:g} of it above the hips"))
            candidates.append((xy, float(height), what))
    for group in groups:
        scored = [stance for stance in (_try(chains, xy, height, what, time_delta) for xy, height, what in group)
                  if stance is not None]
        if scored:
            best = max(stance.walkspace for stance in scored)
            return next(stance for stance in scored if stance.walkspace >= TIE * best)
    return None


def _try(chains: Any, xy: FloatArray, height: float, what: str, time_delta: float) -> Stance | None:
    """The stance if every leg reaches it and its swing apex (:data:`SWING_SHARE` of the clearance higher) within
    its limits, with its walkspace; None otherwise."""
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
    if not (error < 1e-4).all():
        return None
    apex = targets + np.array([0.0, 0.0, SWING_SHARE * height])
    _, lifted = solve(chains, q, apex, tolerance=1e-5, max_steps=300, dt=time_delta)
    if not (lifted < 1e-4).all():
        return None
    planes = search_workspaces(chains, q, targets, time_delta).planes
    radius = min(walkspace(planes, {leg: (float(x), float(y)) for leg, (x, y) in zip(chains.names, xy,
                                                                                      strict=True)}).values())
    return Stance([(float(x), float(y)) for x, y in xy], height, q, what, radius)


def _length(leg: LegChain) -> float:
    """Length of the leg at the zero pose: through the joint origins to the tip [m]."""
    points = [leg.hip, *leg.points, leg.tip]
    return float(sum(np.linalg.norm(b - a) for a, b in itertools.pairwise(points)))


# -- the robot -------------------------------------------------------------------------------------------------


def import_tree(model: Any, file: Path, name: str, legs: str = "auto", tips: list[TipSpec] | None = None,
                clearance: float | None = None, reach: float | None = None) -> Imported:
    """The shc robot table tree of a parsed URDF (module docstring)."""
    tree = Tree(model)
    found = find_legs(tree, legs, tips or [], file)
    notes: list[str] = []
    if tree.skipped:
        notes.append(f"the root {tree.skipped[0]} holds the robot by a free joint: the body starts at {tree.root}")
    chains = [chain for _, chain in found]
    for chain in chains:
        axes = []
        for joint in chain.joints:
            frame = tree.joint_frame(joint)
            axis = np.array([1.0, 0.0, 0.0]) if joint.axis is None else np.asarray(joint.axis, dtype=float)
            if not np.linalg.norm(axis) > 0.0:
                raise _fail(file, f"joint {joint.name} has the axis (0, 0, 0)",
                            "give it a direction, e.g. xyz=\"0 0 1\"")
            axes.append(Axis(frame[:3, 3].copy(), frame[:3, :3] @ (axis / np.linalg.norm(axis))))
        chain.tip = (tree.pose[chain.end] @ np.append(chain.tip_local, 1.0))[:3]
        chain.hip = axes[0].point
        chain.points = [a.point for a in axes[1:]]
        if len(axes) > 6:
            raise _fail(file, f"the leg to {chain.end} has {len(axes)} revolute joints; shc legs have 1 to 6",
                        "name a link nearer the body with --tip")
        try:
            chain.base, chain.rows = chain_dh(axes, chain.tip)
        except NearlyParallel as error:
            names = ["base_link z", *[j.name for j in chain.joints]]
            raise _fail(file, f"axes of {names[error.index]} and {names[error.index + 1]} are {error.angle:.2g} rad "
                        f"from parallel: the DH table would need an offset of {error.offset:.3g} m",
                        f"snap the URDF's angles with --snap {max(error.angle * 2, SUGGESTED_SNAP):.1g} or fix them")\
                from None
    on_axis = [chain.end for chain in chains if abs(chain.rows[-1].r) < 1e-6]
    if on_axis:
        notes.append(f"the tips of {', '.join(on_axis)} lie on the axes of their legs' last joints, which then do "
                     "not move them: name the tips with --tip 'LINK@X,Y,Z' (LINK may be a glob pattern)")
    ids, order = leg_ids([np.mean([chain.hip, *chain.points, chain.tip], axis=0) for chain in chains])
    for (given, chain), leg_id in zip(found, ids, strict=True):
        chain.leg_id = given or leg_id
    if legs != "auto" and all(given for given, _ in found):
        order = list(range(len(chains)))  # --legs ID=LINK,…: the order given
    chains = [chains[i] for i in order]
    if len({c.leg_id for c in chains}) < len(chains):
        raise _fail(file, "two legs have the same id", "give each leg its own id in --legs ID=LINK,…")
    for chain, names in zip(chains, joint_names([[j.name for j in c.joints] for c in chains]), strict=True):
        chain.names = names
    # Masses: every link goes to the last moving joint above it; links of no leg's joints go to the body.
    leg_joints = {j.name: (chain, k) for chain in chains for k, j in enumerate(chain.joints)}
    for chain in chains:
        chain.masses = [0.0] * len(chain.joints)
    extra, unused = [], []
    for link in tree.links:
        if link in tree.body:
            continue
        mover = _moved_by(tree, link)
        part = _inertial(tree, link)
        if mover in leg_joints:
            owner, k = leg_joints[mover]
            owner.masses[k] += part[0] if part is not None else 0.0
        else:
            extra.append(link)
    for joint in tree.joints.values():
        if joint.type != "fixed" and joint.name not in leg_joints:
            unused.append(joint.name)
    body, body_notes = _body(tree, extra, [c.hip for c in chains])
    notes += body_notes
    if unused:
        notes.append(f"URDF joints in no leg (their links count as body): {', '.join(sorted(unused))}")
    efforts = Counter(j.limit.effort for c in chains for j in c.joints if j.limit.effort)
    speeds = Counter(j.limit.velocity for c in chains for j in c.joints if j.limit.velocity)
    servo: dict[str, Any] = {"model": "from the URDF's joint limits"}
    if efforts:
        servo["stall_torque"] = float(efforts.most_common(1)[0][0])
        if len(efforts) > 1:
            notes.append(f"joint efforts differ ({', '.join(f'{e:g}' for e in sorted(efforts))} N·m): "
                         "servo.stall_torque is the most common")
    if speeds:
        servo["no_load_speed"] = float(speeds.most_common(1)[0][0])
    legs_out: dict[str, Any] = {}
    for chain in chains:
        joints = {}
        for joint_name, joint, row, mass in zip(chain.names, chain.joints, chain.rows, chain.masses, strict=True):
            entry: dict[str, Any] = {**_dh_values(row), "min": float(joint.limit.lower or 0.0),
                                     "max": float(joint.limit.upper or 0.0)}
            if joint.limit.velocity:
                entry["max_vel"] = float(joint.limit.velocity)
            entry["mass"] = _round(mass, 6)
            joints[joint_name] = entry
        assert chain.base is not None
        legs_out[chain.leg_id] = {"base": _dh_values(chain.base),
                                  "foot_radius": _round(chain.sphere, 6), "joints": joints}
    gait = GAITS.get(len(chains), "wave")
    from shc_cli.spec.loading import load_gait

    named = load_gait(gait).gait
    if named is not None and set(named.offset_multiplier) != {c.leg_id for c in chains}:
        notes.append(f"walker.gait '{gait}' names legs {', '.join(named.offset_multiplier)}, not these: write a gait "
                     "file for them (docs/robot-files.md section 5) before shc validate, plan or simulate")
    tree_out: dict[str, Any] = {"name": name, "description": f"imported from {file.name} by shc import urdf",
                                "time_delta": 0.01, "body": body, "walker": {"gait": gait}, "servo": servo,
                                "legs": legs_out}
    return Imported(tree_out, chains, tree.base_frame, notes)


def _finish(imported: Imported, clearance: float | None, reach: float | None, file: Path) -> None:
    """Add the stance, clearance, unpacked pose and swing height to the tree."""
    stance = choose_stance(imported.tree, imported.legs, clearance, reach, imported.tree["time_delta"])
    if stance is None:
        raise _fail(file, "no standing pose found that every leg reaches within its joint limits",
                    "give one with --clearance M and --reach FRACTION (of the leg's length, from the hip)")
    walker = imported.tree["walker"]
    walker["body_clearance"] = stance.clearance
    swing = round(min(max(SWING_SHARE * stance.clearance, 0.01), 0.2), 3)
    walker["swing_height"] = {"default": swing, "min": 0.01, "max": max(0.05, round(2 * swing, 3)), "step": 0.005}
    for i, chain in enumerate(imported.legs):
        leg = imported.tree["legs"][chain.leg_id]
        leg["stance"] = {"x": stance.xy[i][0], "y": stance.xy[i][1]}
        for k, joint in enumerate(leg["joints"].values()):
            joint["unpacked"] = float(np.clip(round(float(stance.unpacked[i, k]), 4), joint["min"], joint["max"]))
    imported.notes.insert(0, f"stance and body clearance: {stance.how}")
    imported.notes.insert(1, f"gait {walker['gait']}, swing height {swing:g} m (a fifth of the clearance), control "
                             "period 0.01 s, everything else shc's defaults")


def factor_legs(legs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Templates of the values legs with the same joints share; each leg keeps its stance and what differs.

    Legs with the same joint names use one template (``leg``, or ``leg_a``, ``leg_b``, … for several kinds);
    a value goes to the template when at least two of its legs have it (as ``shc import openshc`` does)."""
    from shc_cli.interop.openshc import _factor_legs

    kinds: dict[tuple[str, ...], list[str]] = {}
    for leg_id, spec in legs.items():
        kinds.setdefault(tuple(spec["joints"]), []).append(leg_id)
    templates, out = {}, {}
    for index, members in enumerate(kinds.values()):
        label = "leg" if len(kinds) == 1 else f"leg_{chr(ord('a') + index)}"
        template, factored = _factor_legs({leg_id: legs[leg_id] for leg_id in members})
        templates[label] = template["leg"]
        for leg_id, spec in factored.items():
            out[leg_id] = {**spec, "template": label}
    return templates, {leg_id: out[leg_id] for leg_id in legs}


def joint_map_csv(legs: list[LegChain]) -> str:
    """``urdf_joint,leg,joint,offset,direction``: URDF angle = offset + direction × shc angle [rad]."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["urdf_joint", "leg", "joint", "offset", "direction"])
    for chain in legs:
        for joint, name in zip(chain.joints, chain.names, strict=True):
            writer.writerow([joint.name, chain.leg_id, name, 0.0, 1])
    return buffer.getvalue()


def fk_error(model: Any, legs: list[LegChain], base_frame: str, robot: Any, samples: int = FK_SAMPLES,
             seed: int = 0) -> float:
    """Largest tip distance between the robot's DH chains and the URDF model (yourdfpy) at random joint
    vectors inside the limits, every leg [m]."""
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(samples):
        q = rng.uniform(chains.lower, chains.upper)
        cfg = {name: 0.0 for name in model.actuated_joint_names}
        for i, chain in enumerate(legs):
            for k, joint in enumerate(chain.joints):
                cfg[joint.name] = float(q[i, k])
        model.update_cfg(cfg)
        ours = chains.tips(q)
        for i, chain in enumerate(legs):
            transform = np.asarray(model.get_transform(frame_to=chain.end, frame_from=base_frame), dtype=float)
            theirs = (transform @ np.append(chain.tip_local, 1.0))[:3]
            worst = max(worst, float(np.linalg.norm(ours[i] - theirs)))
    return worst


def _tip_lines(legs: list[LegChain]) -> list[str]:
    """Header lines saying where each tip is; one line when every leg's is the same point of its own link."""
    generic = {leg.tip_source.replace(leg.end, "its leg's last link") for leg in legs}
    if len(generic) == 1:
        return [f"# Tip of every leg: {generic.pop()}."]
    return [f"# Tip of {leg.leg_id}: {leg.tip_source}." for leg in legs]


@dataclass(frozen=True)
class Result:
    """Files written and figures of one import."""

    robot_path: Path
    joint_map_path: Path
    notes: list[str]
    fk_error: float
    fk_error_unsnapped: float
    snap: float


def import_urdf(file: Path, out: Path | None = None, name: str | None = None, legs: str = "auto",
                tips: list[str] | None = None, clearance: float | None = None, reach: float | None = None,
                snap: float = 0.0, args: dict[str, str] | None = None) -> Result:
    """Write ``OUT/robots/NAME.toml`` and ``OUT/joint_map.csv`` from a URDF or xacro file; check the robot
    (``shc validate``'s checks) and its forward kinematics against the URDF before returning.

    A URDF that yourdfpy reads but whose numbers or structure the import cannot use (a link outside the tree, a
    zero-length chain, values the robot model refuses) is one line naming the file (found by
    ``tests/test_fuzz_inputs.py``)."""
    try:
        return _import_urdf(file, out, name, legs, tips, clearance, reach, snap, args)
    except (ValueError, LookupError, ArithmeticError) as error:  # pydantic's ValidationError is a ValueError
        lines = str(error).strip().splitlines()
        raise _fail(file, f"cannot import it: {type(error).__name__}: {lines[0] if lines else ''}",
                    "check the URDF's links, joints, limits and inertias (check_urdf)") from None


def _import_urdf(file: Path, out: Path | None, name: str | None, legs: str, tips: list[str] | None,
                 clearance: float | None, reach: float | None, snap: float, args: dict[str, str] | None) -> Result:
    from shc_cli.outputs import write_text
    from shc_cli.spec.loading import load_robot
    from shc_cli.validation import check_robot

    source = read_source(file, args or {}, snap)
    model = parse_urdf(file, source.snapped_text)
    robot_name = name or re.sub(r"[^A-Za-z0-9_-]", "_", str(model.robot.name or file.stem))
    out = out if out is not None else Path("imported") / robot_name
    imported = import_tree(model, file, robot_name, legs, [TipSpec.parse(t) for t in tips or []], clearance, reach)
    _finish(imported, clearance, reach, file)
    imported.tree["templates"], imported.tree["legs"] = factor_legs(imported.tree["legs"])
    tree = {key: imported.tree[key] for key in ("name", "description", "time_delta", "body", "walker", "servo",
                                                "templates", "legs")}
    header = [f"# Imported by `shc import urdf` from {file.name}. Units: m, rad, s, kg.",
              f"# base_link is the URDF link '{imported.base_frame}'. Joint angles are the URDF's (joint_map.csv).",
              *_tip_lines(imported.legs),
              *(f"# Note: {note}." for note in imported.notes)]
    if source.snap > 0.0:
        header.append(f"# rpy values within {snap:g} rad of a multiple of pi/2 snapped to it (largest change "
                      f"{source.snap:.2g} rad).")
    header.append("# Not read: visuals, meshes, transmissions, gazebo tags, dynamics (damping, friction).")
    robot_path = out / "robots" / f"{robot_name}.toml"
    map_path = out / "joint_map.csv"
    text = "\n".join(header) + "\n" + dump_toml(tree)
    with tempfile.TemporaryDirectory() as folder:  # checked before anything is written
        draft = Path(folder) / robot_path.name
        draft.write_text(text, encoding="utf-8")
        loaded = load_robot(draft)
        problems = check_robot(loaded)
        if problems:
            raise SpecError(problems)
    error = fk_error(model, imported.legs, imported.base_frame, loaded.robot)
    unsnapped = error
    if source.snap > 0.0:
        unsnapped = fk_error(parse_urdf(file, source.text), imported.legs, imported.base_frame, loaded.robot)
    write_text(robot_path, text)
    write_text(map_path, joint_map_csv(imported.legs))
    return Result(robot_path, map_path, imported.notes, error, unsnapped, source.snap)
