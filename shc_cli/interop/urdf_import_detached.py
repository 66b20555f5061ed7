"""Links hanging off the root by floating joints (``shc import urdf``): a CAD exporter's output.

Some exporters make the foot links (and the body itself) children of the root link through ``floating`` joints
instead of children of the tibias. A floating joint whose child carries no moving joint below it is a
*detached* part. Each is matched to the end of a leg chain (a leaf link reached through a revolute joint that
has no collision sphere of its own), nearest first by the distance between the two link frames at the zero
pose, and fixed to it where it sits; the import then reads it as that leg's foot (its sphere's centre, else its
origin). A detached part left over is refused with one line naming it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

MOVING = ("revolute", "continuous", "prismatic")
"""Joint types that make a subtree part of the robot rather than a detached part."""


def _world(joints: list[Any], root: str) -> dict[str, FloatArray]:
    """Every link's frame at the zero pose, in the root's frame."""
    children: dict[str, list[Any]] = {}
    for joint in joints:
        children.setdefault(joint.parent, []).append(joint)
    world = {root: np.eye(4)}
    stack = [root]
    while stack:
        link = stack.pop()
        for joint in children.get(link, []):
            origin = np.eye(4) if joint.origin is None else np.asarray(joint.origin, dtype=float)
            world[joint.child] = world[link] @ origin
            stack.append(joint.child)
    return world


def _below(joints: list[Any], link: str) -> list[Any]:
    """The joints of the subtree under ``link``."""
    out, stack = [], [link]
    while stack:
        parent = stack.pop()
        for joint in joints:
            if joint.parent == parent:
                out.append(joint)
                stack.append(joint.child)
    return out


def _has_sphere(link: Any) -> bool:
    return any(c.geometry is not None and c.geometry.sphere is not None for c in link.collisions or [])


def attach_detached(model: Any) -> tuple[Any, list[str], str | None]:
    """The model with each detached part fixed to the leg end it sits at (module docstring), the notes, and
    the problem if a detached part ends no leg (None if none is left over). The model is returned unchanged
    (the same object) when nothing hangs off by a floating joint."""
    import yourdfpy

    joints = list(model.robot.joints)
    detached = [j for j in joints
                if j.type == "floating" and not any(b.type in MOVING for b in _below(joints, j.child))]
    if not detached:
        return model, [], None
    cut = {j.child for j in detached}
    kept = [j for j in joints if j not in detached and not _inside(joints, j, cut)]
    parents = {j.parent for j in kept}
    links = {link.name: link for link in model.robot.links}
    world = _world(joints, str(model.base_link))
    by_child = {j.child: j for j in kept}

    def on_leg(link: str) -> bool:
        while link in by_child:
            if by_child[link].type in MOVING:
                return True
            link = by_child[link].parent
        return False

    ends = [j.child for j in kept if j.child not in parents and on_leg(j.child) and not _has_sphere(links[j.child])]
    pairs = sorted((float(np.linalg.norm(world[j.child][:3, 3] - world[end][:3, 3])), j.name, end)
                   for j in detached for end in ends if j.child in world and end in world)
    taken: dict[str, str] = {}
    used: set[str] = set()
    for _, name, end in pairs:
        if name not in taken and end not in used:
            taken[name] = end
            used.add(end)
    left = [j.child for j in detached if j.name not in taken]
    if left:
        return model, [], (f"link{'s' if len(left) > 1 else ''} {', '.join(left)} hang{'' if len(left) > 1 else 's'} "
                           "off the root by floating joints and sit at the end of no leg chain")
    for joint in detached:
        end = taken[joint.name]
        joint.type, joint.parent = "fixed", end
        joint.origin = np.linalg.inv(world[end]) @ world[joint.child]
        joint.axis, joint.limit = None, None
    rebuilt = yourdfpy.URDF(robot=model.robot, build_scene_graph=True, load_meshes=False,
                            build_collision_scene_graph=False, load_collision_meshes=False)
    shown = ", ".join(f"{j.child} → {taken[j.name]}" for j in detached[:3])
    more = f" and {len(detached) - 3} more" if len(detached) > 3 else ""
    return rebuilt, [f"links hanging off the root by floating joints are fixed, where they sit, to the leg ends "
                     f"nearest them ({shown}{more}): a CAD export's feet"], None


def _inside(joints: list[Any], joint: Any, cut: set[str]) -> bool:
    """Whether ``joint`` lies under one of the links ``cut``."""
    by_child = {j.child: j for j in joints}
    link = joint.parent
    while True:
        if link in cut:
            return True
        if link not in by_child:
            return False
        link = by_child[link].parent
