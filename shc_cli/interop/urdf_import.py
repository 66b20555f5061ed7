"""``shc import urdf``: a legged robot's URDF (or xacro) → an shc robot file with its servo map.

* **Body**: the URDF's root link and every link fixed to it. shc's ``base_link`` is the URDF link
  ``base_link`` if it is one of them, else the root; the body's mass, centre of mass and principal moments
  (the diagonal of the summed inertia) are those of these links; its box is the collision box of the base
  link, else the box around the hips.
* **Legs**: the serial chains from the body to each leaf link that pass a revolute joint (``--legs auto``); a
  leaf whose moving joints are all on a longer chain (a sensor fixed to a femur) is not a leg of its own, and
  of leaves on the same joints the one with a sphere (else the deepest) is the foot. Fixed joints fold into
  the transforms. ``--legs LINK,…`` (or ``ID=LINK,…``) names the tip links instead, ``--tip PATTERN[@X,Y,Z]``
  names tip links by glob pattern and the tip point in their frame.
* **Tip**: the centre of the tip link's first collision sphere, else its frame origin (``--tip`` names it); a
  frame origin on the last joint's axis (a tibia frame on the knee and no foot frame) is replaced by the point of
  the link's mesh farthest from that axis, else the import is refused with the ``--tip`` that would fix it.
* **What is not a leg** (:mod:`shc_cli.interop.urdf_import_clean`): sensor stand-ins and dummy foot joints are
  fixed, head and camera chains left out, placeholder inertias and speed limits replaced (and named), and a
  body frame whose +x points at a leg turned a quarter (``--forward`` chooses). Axes less than
  :data:`AUTO_SNAP` from parallel are snapped without being asked.
* **Servo map**: ``[hardware.servos]`` (:mod:`shc_cli.interop.servo_map`): ids numbered, each joint's URDF name.
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
  zero pose's leg direction) with the body as many shares of a leg's length above the hips, then (a knee
  limit that keeps the leg nearly straight) 0.75 … 0.9 out with the body 0.05 … 0.7 of it above the
  hips. ``--clearance`` and ``--reach`` fix either (a stance they ask for that a leg cannot take is refused
  naming the leg, the joint limit and the range that stands). ``unpacked`` is the pose the IK finds there
  from every joint at 0, else (a zero pose far from any stance: legs straight up) from each leg's pose nearest
  its foot among :data:`SEED_POSES` spread over its joint ranges.
"""

from __future__ import annotations

import fnmatch
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
from shc_cli.interop.servo_map import servo_table, with_check_note
from shc_cli.interop.urdf_import_clean import (
    ON_AXIS,
    SERVO_MASS,
    dummy_tail,
    forward_turn,
    leg_chains,
    placeholders,
    stub_joints,
)
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
FRACTIONS = [0.5, 0.4, 0.6, 0.3, 0.7, 0.2]
"""Shares of the leg's length tried for the stance's reach and the body's height (most natural first)."""
FAR = [0.75, 0.8, 0.85, 0.9]
"""Reaches tried when none of :data:`FRACTIONS` stands (a knee limit that keeps the leg nearly straight)."""
HEIGHTS = [round(0.05 * k, 2) for k in range(1, 15)]
"""Body heights tried with the reaches of :data:`FAR`, as shares of the leg's length (a narrow band may fit)."""
SEED_POSES = 729
"""Joint vectors per leg the stance search may start its IK from when OpenSHC's initial pose does not reach."""
GAITS = {4: "quad_wave", 6: "tripod", 8: "octo_alternating"}
"""Gait written for a robot with this many legs (others get ``wave``, which fits none but six legs)."""
AUTO_SNAP = 0.001
"""Snap tolerance used without being asked when two axes are nearly parallel [rad] (1.57 is 0.0008 from π/2)."""
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
    yaw: float = 0.0
    """The shc body frame is base_frame turned by this about z [rad]."""
    refusal: tuple[str, str] | None = None
    """Why (problem, fix) the robot cannot be written though its chains could be traced."""


# -- the URDF as a tree ----------------------------------------------------------------------------------------


class Tree:
    """Links and joints of a yourdfpy model with zero-pose transforms in the shc base frame."""

    def __init__(self, model: Any, fixed: dict[str, str] | None = None, yaw: float = 0.0) -> None:
        self.model = model
        self.fixed = dict(fixed or {})
        """Moving joints taken as fixed at 0: ``{name: why}`` (:mod:`shc_cli.interop.urdf_import_clean`)."""
        self.yaw = yaw
        """The shc body frame is base_link turned by this about its z axis [rad]."""
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
        inverse = turn(yaw).T @ np.linalg.inv(world[self.base_frame])
        self.pose = {name: inverse @ transform for name, transform in world.items()}

    def _fixed_set(self, start: str) -> list[str]:
        out, stack = [], [start]
        while stack:
            link = stack.pop()
            out.append(link)
            stack += [j.child for j in self.children.get(link, []) if self.is_fixed(j)]
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

    def is_fixed(self, joint: Any) -> bool:
        return joint.type == "fixed" or joint.name in self.fixed

    def moving(self, path: list[Any]) -> list[Any]:
        return [joint for joint in path if not self.is_fixed(joint)]

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


def turn(yaw: float) -> FloatArray:
    """Homogeneous rotation by ``yaw`` about z [rad]."""
    out = np.eye(4)
    out[:2, :2] = [[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]]
    return out


def _sphere(link: Any) -> tuple[FloatArray, float] | None:
    """Centre (in the link frame) and radius of the link's first collision sphere."""
    for collision in link.collisions or []:
        if collision.geometry is not None and collision.geometry.sphere is not None:
            origin = np.eye(4) if collision.origin is None else np.asarray(collision.origin, dtype=float)
            return origin[:3, 3].copy(), float(collision.geometry.sphere.radius)
    return None


# -- legs ------------------------------------------------------------------------------------------------------


def _auto_ends(tree: Tree, file: Path) -> list[str]:
    """Leaf links ending legs (module docstring)."""
    sets = {leaf: frozenset(j.name for j in tree.moving(tree.path(leaf))) for leaf in tree.leaves()}
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
    for joint in tree.moving(path):
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
    moving = tree.moving(path)
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
    moving = tree.moving(tree.path(link))
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
    return None


def _seeds(chains: Any) -> tuple[FloatArray, FloatArray]:
    """Joint vectors spread over every leg's limits (about :data:`SEED_POSES` of them, the same share of each
    joint's range for every leg) and their tips: ``(q (G, B, n) [rad], tips (G, B, 3) [m])``."""
    steps = max(2, round(SEED_POSES ** (1.0 / chains.joints)))
    shares = np.linspace(0.0, 1.0, steps + 2)[1:-1]  # inside the limits, not on them
    grid = np.array(list(itertools.product(shares, repeat=chains.joints)))
    q = chains.lower[None] + grid[:, None, :] * (chains.upper - chains.lower)[None]
    return q, np.array([chains.tips(pose) for pose in q])


def _try(chains: Any, xy: FloatArray, height: float, what: str, time_delta: float,
         seeds: tuple[FloatArray, FloatArray] | None = None) -> Stance | None:
    """The stance if every leg reaches it and its swing apex (:data:`SWING_SHARE` of the clearance higher) within
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
                clearance: float | None = None, reach: float | None = None, forward: float | None = None,
                stubs: dict[str, str] | None = None) -> Imported:
    """The shc robot table tree of a parsed URDF (module docstring).

    ``forward``: the turn of the shc body frame from base_link about z [rad] (None: π/2 if the legs' layout says
    the URDF's +x is not forward, :func:`~shc_cli.interop.urdf_import_clean.forward_turn`, else 0)."""
    stubs = stub_joints(model.robot.joints) if stubs is None else stubs
    tree = Tree(model, stubs, forward or 0.0)
    found = find_legs(tree, legs, tips or [], file)
    notes: list[str] = [f"{joint} is taken as fixed: {why}" for joint, why in stubs.items()]
    if tree.skipped:
        notes.append(f"the root {tree.skipped[0]} holds the robot by a free joint: the body starts at {tree.root}")
    for _, chain in found:
        _trace(tree, chain, file, notes)
    if legs == "auto" and not tips:
        kept = leg_chains([len(c.joints) for _, c in found], [_length(c) for _, c in found])
        if len(kept) < len(found):
            notes.append("chains left out as not legs (their links count as body): "
                         + ", ".join(f"{c.end} ({len(c.joints)} joints)" for i, (_, c) in enumerate(found)
                                     if i not in kept))
            found = [found[i] for i in kept]
    chains = [chain for _, chain in found]
    on_axis = [chain for chain in chains if abs(chain.rows[-1].r) < ON_AXIS]
    refusal = None
    if on_axis:
        refusal = (f"the tip of the leg to {on_axis[0].end} ({on_axis[0].tip_source}) lies on the axis of "
                   f"{on_axis[0].joints[-1].name}, which then does not move it (a link frame on the joint axis and no "
                   "foot frame after it)", f"name the tip point with {_tip_hint(tree, on_axis)}")
    if forward is None and legs == "auto":
        yaw = forward_turn([np.mean([c.hip, *c.points, c.tip], axis=0) for c in chains])
        if yaw:
            again = import_tree(model, file, name, legs, tips, clearance, reach, yaw, stubs)
            quarter = abs(abs(yaw) - math.pi / 2) < 1e-9
            way = (f"base_link's {'+y' if yaw > 0 else '-y'}" if quarter else
                   f"{math.degrees(yaw):g} deg from base_link's +x towards {'+y' if yaw > 0 else '-y'}, halfway "
                   "between two legs")
            again.notes.append(f"the URDF's +x points at a leg (legs straight ahead and behind): shc's forward is "
                               f"{way} (--forward +x keeps the URDF's)")
            return again
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
        if not tree.is_fixed(joint) and joint.name not in leg_joints:
            unused.append(joint.name)
    body, body_notes = _body(tree, extra, [c.hip for c in chains])
    notes += body_notes
    parts = [p for p in (_inertial(tree, link) for link in tree.links) if p is not None]
    found_placeholders = placeholders(
        [p[0] for p in parts], [float(np.linalg.eigvalsh(p[2]).max()) for p in parts], [_length(c) for c in chains],
        [float(j.limit.velocity) for c in chains for j in c.joints if j.limit.velocity],
        [float(j.limit.effort) for c in chains for j in c.joints if j.limit.effort])
    notes += found_placeholders.notes
    if found_placeholders.masses:
        for chain in chains:
            chain.masses = [SERVO_MASS] * len(chain.joints)
        body.pop("com", None)
        body.pop("inertia", None)
        body["mass"] = _round(SERVO_MASS * sum(len(c.joints) for c in chains), 6)
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
    if found_placeholders.speed is not None:
        servo["no_load_speed"] = found_placeholders.speed
    if found_placeholders.torque is not None:
        servo["stall_torque"] = found_placeholders.torque
    legs_out: dict[str, Any] = {}
    for chain in chains:
        joints = {}
        for joint_name, joint, row, mass in zip(chain.names, chain.joints, chain.rows, chain.masses, strict=True):
            entry: dict[str, Any] = {**_dh_values(row), "min": float(joint.limit.lower or 0.0),
                                     "max": float(joint.limit.upper or 0.0)}
            if found_placeholders.speed is not None:
                entry["max_vel"] = found_placeholders.speed
            elif joint.limit.velocity:
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
    return Imported(tree_out, chains, tree.base_frame, notes, tree.yaw, refusal)


def _trace(tree: Tree, chain: LegChain, file: Path, notes: list[str]) -> None:
    """The chain's axes, tip and DH rows; dummy joints at its foot become fixed (``tree.fixed``)."""
    axes = []
    for joint in chain.joints:
        frame = tree.joint_frame(joint)
        axis = np.array([1.0, 0.0, 0.0]) if joint.axis is None else np.asarray(joint.axis, dtype=float)
        if not np.linalg.norm(axis) > 0.0:
            raise _fail(file, f"joint {joint.name} has the axis (0, 0, 0)", "give it a direction, e.g. xyz=\"0 0 1\"")
        axes.append(Axis(frame[:3, 3].copy(), frame[:3, :3] @ (axis / np.linalg.norm(axis))))
    chain.tip = (tree.pose[chain.end] @ np.append(chain.tip_local, 1.0))[:3]
    dummies = dummy_tail([a.point for a in axes], [a.direction for a in axes], chain.tip)
    if dummies:
        for joint in chain.joints[-dummies:]:
            tree.fixed[joint.name] = "a joint at the foot whose axis passes through the tip (it moves nothing)"
        notes.append(f"{', '.join(j.name for j in chain.joints[-dummies:])} at the foot of the leg to {chain.end} "
                     "pass through the tip: taken as fixed")
        chain.joints, axes = chain.joints[:-dummies], axes[:-dummies]
    if chain.tip_source.startswith("the origin of") and _off_axis(chain.tip, axes[-1]) < ON_AXIS:
        found = _mesh_tip(tree, chain.end, axes[-1], file)
        if found is not None:
            chain.tip, chain.tip_source = found
            chain.tip_local = (np.linalg.inv(tree.pose[chain.end]) @ np.append(chain.tip, 1.0))[:3]
    chain.hip = axes[0].point
    chain.points = [a.point for a in axes[1:]]
    if len(axes) > 6:
        raise _fail(file, f"the leg to {chain.end} has {len(axes)} revolute joints; shc legs have 1 to 6",
                    "name a link nearer the body with --tip")
    try:
        chain.base, chain.rows = chain_dh(axes, chain.tip)
    except NearlyParallel as error:
        names = ["base_link z", *[j.name for j in chain.joints]]
        raise NeedsSnap(f"axes of {names[error.index]} and {names[error.index + 1]} are {error.angle:.2g} rad from "
                        f"parallel: the DH table would need an offset of {error.offset:.3g} m",
                        max(error.angle * 2, SUGGESTED_SNAP)) from None


def _off_axis(point: FloatArray, axis: Axis) -> float:
    """Distance of ``point`` from the line of ``axis`` [m]."""
    offset = point - axis.point
    return float(np.linalg.norm(offset - np.dot(offset, axis.direction) * axis.direction))


def _mesh_tip(tree: Tree, link: str, axis: Axis, file: Path) -> tuple[FloatArray, str] | None:
    """The vertex of ``link``'s collision (else visual) meshes farthest from ``axis`` (in base_link, with how it
    was found), for a leg whose link frame sits on its last joint's axis; None if no mesh file is found."""
    import trimesh

    from shc_cli.interop.urdf_import_source import find_package

    best: tuple[float, FloatArray, str] | None = None
    for shape in [*(tree.links[link].collisions or []), *(tree.links[link].visuals or [])]:
        mesh = shape.geometry.mesh if shape.geometry is not None else None
        if mesh is None or not mesh.filename:
            continue
        name = str(mesh.filename)
        path: Path | None
        if name.startswith("package://"):
            package, _, rest = name[len("package://"):].partition("/")
            folder = find_package(package, file.resolve().parent)
            path = folder / rest if folder is not None else None
        else:
            path = file.parent / name.removeprefix("file://")
        if path is None or not path.is_file():
            continue
        try:
            loaded = trimesh.load(str(path), force="mesh")
        except (ValueError, OSError):
            continue
        vertices = np.asarray(getattr(loaded, "vertices", np.zeros((0, 3))), dtype=np.float64)
        if vertices.size == 0:
            continue
        scale = np.ones(3) if mesh.scale is None else np.broadcast_to(np.asarray(mesh.scale, dtype=float), (3,))
        origin = np.eye(4) if shape.origin is None else np.asarray(shape.origin, dtype=float)
        placed = (tree.pose[link] @ origin @ np.column_stack([vertices * scale, np.ones(len(vertices))]).T).T[:, :3]
        offsets = placed - axis.point
        distance = np.linalg.norm(offsets - np.outer(offsets @ axis.direction, axis.direction), axis=1)
        k = int(np.argmax(distance))
        if best is None or distance[k] > best[0]:
            best = (float(distance[k]), placed[k], f"the point of {link}'s mesh {path.name} farthest from its joint's "
                                                   "axis (the link's frame is on the axis)")
    return None if best is None or best[0] < ON_AXIS else (best[1], best[2])


class NeedsSnap(Exception):
    """Two axes of a leg are nearly parallel: the URDF needs snapping (by at least ``snap`` rad) to import."""

    def __init__(self, problem: str, snap: float) -> None:
        super().__init__(problem)
        self.problem, self.snap = problem, snap


def _tip_hint(tree: Tree, legs: list[LegChain]) -> str:
    """The ``--tip`` option that names the far end of the legs' last links (from their collision or visual
    geometry, else twice their centre of mass), with a glob pattern when the links' names share an end."""
    leg = legs[0]
    link = tree.links[leg.end]
    joint = leg.joints[-1]
    axis = np.array([1.0, 0.0, 0.0]) if joint.axis is None else np.asarray(joint.axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    candidates: list[FloatArray] = []
    for shape in [*(link.collisions or []), *(link.visuals or [])]:
        origin = np.eye(4) if shape.origin is None else np.asarray(shape.origin, dtype=float)
        geometry = shape.geometry
        half = None
        if geometry is not None and geometry.cylinder is not None:
            half = np.array([0.0, 0.0, float(geometry.cylinder.length) / 2])
        elif geometry is not None and geometry.box is not None:
            size = np.asarray(geometry.box.size, dtype=float)
            half = np.where(size == size.max(), size / 2, 0.0)
        if half is not None:
            candidates += [(origin @ np.append(sign * half, 1.0))[:3] for sign in (1.0, -1.0)]
    if not candidates and link.inertial is not None and link.inertial.origin is not None:
        candidates.append(2.0 * np.asarray(link.inertial.origin, dtype=float)[:3, 3])
    names = [chain.end for chain in legs]
    suffix = names[0]
    while suffix and not all(n.endswith(suffix) for n in names):
        suffix = suffix[1:]
    pattern = f"*{suffix}" if len(names) > 1 and len(suffix) >= 3 else names[0]
    if not candidates:
        return f"--tip '{pattern}@X,Y,Z' (the foot's point in {leg.end}'s frame, metres: measure it)"
    best = max(candidates, key=lambda p: float(np.linalg.norm(p - np.dot(p, axis) * axis)))
    return (f"--tip '{pattern}@{best[0]:.4g},{best[1]:.4g},{best[2]:.4g}' (the far end of {leg.end}'s geometry; "
            "check it, in metres in that link's frame)")


def _finish(imported: Imported, clearance: float | None, reach: float | None, file: Path) -> None:
    """Add the stance, clearance, unpacked pose and swing height to the tree."""
    stance = choose_stance(imported.tree, imported.legs, clearance, reach, imported.tree["time_delta"])
    if stance is None and (clearance is not None or reach is not None):
        raise _fail(file, *_why_not(imported, clearance, reach))
    if stance is None:
        raise _fail(file, "no standing pose found that every leg reaches within its joint limits, with the feet "
                    f"{min(FRACTIONS):g}–{max(FAR):g} of the leg's length out and the body "
                    f"{min(HEIGHTS):g}–{max(HEIGHTS):g} of it above the hips",
                    "check the legs' joint limits, or give a stance with --clearance M and --reach FRACTION")
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
                                           f"reach {reach:g}" if reach is not None else "") if part)
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


def fk_error(model: Any, legs: list[LegChain], base_frame: str, robot: Any, samples: int = FK_SAMPLES,
             seed: int = 0, yaw: float = 0.0) -> float:
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
            transform = turn(yaw).T @ np.asarray(model.get_transform(frame_to=chain.end, frame_from=base_frame),
                                                 dtype=float)
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
    notes: list[str]
    fk_error: float
    fk_error_unsnapped: float
    snap: float
    pose_path: Path | None = None
    """The auto-pose set written for the robot (a quadruped walking quad_wave), if any."""


def import_urdf(file: Path, out: Path | None = None, name: str | None = None, legs: str = "auto",
                tips: list[str] | None = None, clearance: float | None = None, reach: float | None = None,
                snap: float = 0.0, args: dict[str, str] | None = None, forward: float | None = None) -> Result:
    """Write ``OUT/robots/NAME.toml`` (its ``[hardware.servos]`` the servo map, to check) from a URDF or xacro
    file; check the robot
    (``shc validate``'s checks) and its forward kinematics against the URDF before returning.

    A URDF that yourdfpy reads but whose numbers or structure the import cannot use (a link outside the tree, a
    zero-length chain, values the robot model refuses) is one line naming the file (found by
    ``tests/test_fuzz_inputs.py``)."""
    try:
        return _import_urdf(file, out, name, legs, tips, clearance, reach, snap, args, forward)
    except (ValueError, LookupError, ArithmeticError) as error:  # pydantic's ValidationError is a ValueError
        lines = str(error).strip().splitlines()
        raise _fail(file, f"cannot import it: {type(error).__name__}: {lines[0] if lines else ''}",
                    "check the URDF's links, joints, limits and inertias (check_urdf)") from None


def _import_urdf(file: Path, out: Path | None, name: str | None, legs: str, tips: list[str] | None,
                 clearance: float | None, reach: float | None, snap: float, args: dict[str, str] | None,
                 forward: float | None) -> Result:
    from shc_cli.outputs import write_text
    from shc_cli.spec.loading import load_gait, load_robot
    from shc_cli.validation import check_robot

    source = read_source(file, args or {}, snap)
    model = parse_urdf(file, source.snapped_text)
    robot_name = name or re.sub(r"[^A-Za-z0-9_-]", "_", str(model.robot.name or file.stem))
    out = out if out is not None else Path("imported") / robot_name
    tip_specs = [TipSpec.parse(t) for t in tips or []]
    try:
        imported = import_tree(model, file, robot_name, legs, tip_specs, clearance, reach, forward)
    except NeedsSnap as needed:
        if snap > 0.0 or needed.snap > AUTO_SNAP:
            raise _fail(file, needed.problem, f"snap the URDF's angles with --snap {needed.snap:.1g} or fix them")\
                from None
        snap = AUTO_SNAP
        source = read_source(file, args or {}, snap)
        model = parse_urdf(file, source.snapped_text)
        try:
            imported = import_tree(model, file, robot_name, legs, tip_specs, clearance, reach, forward)
        except NeedsSnap as still:
            raise _fail(file, still.problem, "fix the URDF's angles (snapping them by "
                        f"{AUTO_SNAP:g} rad did not make the axes parallel)") from None
        imported.notes.append(f"{needed.problem}: angles within {AUTO_SNAP:g} rad of a multiple of pi/2 snapped "
                              "(--snap)")
    if imported.refusal is not None:
        raise _fail(file, *imported.refusal)
    _finish(imported, clearance, reach, file)
    imported.tree["templates"], imported.tree["legs"] = factor_legs(imported.tree["legs"])
    imported.tree["hardware"] = servo_table(
        {c.leg_id: c.names for c in imported.legs}, imported.tree["servo"].get("stall_torque"),
        {f"{c.leg_id}_{name}": joint.name for c in imported.legs for name, joint in zip(c.names, c.joints,
                                                                                      strict=True)})
    sway = _sway(imported, robot_name)
    keys = ("name", "description", "time_delta", "body", "walker", "pose", "servo", "templates", "legs", "hardware")
    tree: dict[str, Any] = {key: imported.tree[key] for key in keys if key in imported.tree}
    header = [f"# Imported by `shc import urdf` from {file.name}. Units: m, rad, s, kg.",
              f"# base_link is the URDF link '{imported.base_frame}'"
              + (f" turned {math.degrees(imported.yaw):g} deg about z (forward)" if imported.yaw else "")
              + ". Joint angles are the URDF's; [hardware.servos] names each joint's URDF joint.",
              *_tip_lines(imported.legs),
              *(f"# Note: {note}." for note in imported.notes)]
    if source.snap > 0.0:
        header.append(f"# rpy values within {snap:g} rad of a multiple of pi/2 snapped to it (largest change "
                      f"{source.snap:.2g} rad).")
    header.append("# Not read: visuals, meshes (but a foot's, when its link frame is on the knee axis), transmissions, "
                  "gazebo tags, dynamics (damping, friction).")
    robot_path = out / "robots" / f"{robot_name}.toml"
    text = "\n".join(header) + "\n" + with_check_note(dump_toml(tree))
    pose_path = out / "poses" / sway[0] if sway is not None else None
    with tempfile.TemporaryDirectory() as folder:  # checked before anything is written
        draft = Path(folder) / "robots" / robot_path.name
        draft.parent.mkdir()
        draft.write_text(text, encoding="utf-8")
        loaded = load_robot(draft)
        problems = check_robot(loaded)
        if sway is not None:
            from shc_cli.spec.autopose import compatibility_issues, load_pose_set

            (Path(folder) / "poses").mkdir()
            (Path(folder) / "poses" / sway[0]).write_text(sway[1], encoding="utf-8")
            gait = load_gait(loaded.robot.walker.gait).gait
            problems += compatibility_issues(load_pose_set(POSES_FROM_ROBOT + sway[0], draft.parent), gait,
                                             list(loaded.robot.legs))
        if problems:
            raise SpecError(problems)
    error = fk_error(model, imported.legs, imported.base_frame, loaded.robot, yaw=imported.yaw)
    unsnapped = error
    if source.snap > 0.0:
        unsnapped = fk_error(parse_urdf(file, source.text), imported.legs, imported.base_frame, loaded.robot,
                             yaw=imported.yaw)
    if pose_path is not None and sway is not None:
        write_text(pose_path, sway[1])
    write_text(robot_path, text)
    return Result(robot_path, imported.notes, error, unsnapped, source.snap, pose_path)


POSES_FROM_ROBOT = "../poses/"
"""Where the robot file finds the pose set the import writes (``OUT/poses/``, relative to ``OUT/robots/``)."""


def _sway(imported: Imported, robot_name: str) -> tuple[str, str] | None:
    """A quadruped walking ``quad_wave``: auto posing on, with a body-sway set sized for its stance (file name
    and text; :mod:`shc_cli.spec.sway`); ``None`` for any other robot."""
    from shc_cli.spec.sway import quad_wave_sway_toml, sway_amplitude

    if imported.tree["walker"]["gait"] != "quad_wave":
        return None
    amplitude = sway_amplitude(leg["stance"]["y"] for leg in imported.tree["legs"].values())
    file_name = f"{robot_name}_quad_wave.toml"
    imported.tree["pose"] = {"auto": True, "auto_pose_type": POSES_FROM_ROBOT + file_name}
    imported.notes.append(f"auto posing on: the body sways {amplitude:g} m sideways towards the three standing "
                          f"feet (poses/{file_name}, a third of the feet's lateral half-spread)")
    return file_name, quad_wave_sway_toml(f"{robot_name}_quad_wave", amplitude, robot_name)
