"""The URDF as a tree for ``shc import urdf``: links, joints, zero-pose transforms, leg chains, leg ids, joint
names and the body's masses (:mod:`shc_cli.interop.urdf_import` describes the rules)."""

from __future__ import annotations

import fnmatch
import math
import re
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.errors import Issue, SpecError
from shc_cli.interop.urdf_import_dh import Row

FloatArray = NDArray[np.float64]


UNSUPPORTED = {"prismatic": "slides", "planar": "moves in a plane",
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

    def __init__(self, model: Any, fixed: dict[str, str] | None = None, yaw: float = 0.0,
                 base: str | None = None) -> None:
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
        self.base_note = ""
        """Why base_frame is not the root (a massless spawn or world frame), if it is not."""
        self.base_frame = self._base_frame(base)
        world = self._world()
        inverse = turn(yaw).T @ np.linalg.inv(world[self.base_frame])
        self.pose = {name: inverse @ transform for name, transform in world.items()}

    def _base_frame(self, base: str | None) -> str:
        """``base`` (``--base``); else ``base_link`` if the body has it; else the root, unless the root has no mass:
        then the body link where the moving joints meet (their parents' deepest common ancestor among the body
        links), or the heaviest body link if they meet only at the root, unless its frame is the root's."""
        if base is not None:
            if base not in self.body:
                raise SpecError([Issue(None, None, "--base", f"'{base}' is not a link of the body (the root "
                                       f"{self.root} and the links fixed to it)",
                                       f"give one of {', '.join(sorted(self.body)[:6])}")])
            return base
        if "base_link" in self.body:
            return "base_link"
        if _mass(self.links[self.root]) > 0.0 or len(self.body) == 1:
            return self.root
        parents = {j.parent for j in self.joints.values() if not self.is_fixed(j) and j.parent in self.body}
        lines = [self._ancestors(link) for link in parents]
        shared = [link for link in lines[0] if all(link in line for line in lines[1:])] if lines else []
        meet = shared[0] if shared else self.root
        how = "where the legs meet"
        if meet == self.root:
            meet = max(self.body, key=lambda link: _mass(self.links[link]))
            how = "the heaviest body link"
        if meet != self.root and not np.allclose(self._world()[meet], np.eye(4), atol=1e-9):
            self.base_note = (f"the root link {self.root} has no mass (a spawn or world frame): base_link is {meet}, "
                              f"{how} (--base LINK chooses another)")
            return meet
        return self.root

    def _ancestors(self, link: str) -> list[str]:
        """``link`` and the body links above it up to the root, nearest first."""
        out = [link]
        while out[-1] != self.root and out[-1] in self.parent_joint:
            out.append(self.parent_joint[out[-1]].parent)
        return out

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


def _mass(link: Any) -> float:
    """The link's mass, 0 without an inertial [kg]."""
    inertial = link.inertial
    return float(inertial.mass or 0.0) if inertial is not None and inertial.mass is not None else 0.0


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


