"""Where a leg's tip is when its link frame sits on the last joint's axis (``shc import urdf``): the far end of the
link's mesh, else of its collision or visual primitives; the ``--tip`` hint otherwise."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.interop.urdf_import_clean import (
    ON_AXIS,
)
from shc_cli.interop.urdf_import_dh import Axis
from shc_cli.interop.urdf_import_tree import LegChain, Tree

FloatArray = NDArray[np.float64]


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


def primitive_ends(link: Any) -> list[FloatArray]:
    """Both ends of each cylinder (along its axis) and box (along its longest side) of the link's collision and
    visual geometry, in the link's frame [m]."""
    out: list[FloatArray] = []
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
            out += [(origin @ np.append(sign * half, 1.0))[:3] for sign in (1.0, -1.0)]
    return out


def primitive_tip(tree: Tree, link: str, axis: Axis) -> tuple[FloatArray, str] | None:
    """The end of ``link``'s cylinders and boxes (:func:`primitive_ends`) farthest from ``axis`` (in base_link,
    with how it was found), for a leg whose link frame sits on its last joint's axis and that has no mesh; None
    if it has no such geometry off the axis."""
    ends = [(tree.pose[link] @ np.append(end, 1.0))[:3] for end in primitive_ends(tree.links[link])]
    if not ends:
        return None
    best = max(ends, key=lambda point: _off_axis(point, axis))
    if _off_axis(best, axis) < ON_AXIS:
        return None
    return best, (f"the end of {link}'s collision or visual geometry farthest from its joint's axis (the link's frame "
                  "is on the axis)")


def _tip_hint(tree: Tree, legs: list[LegChain]) -> str:
    """The ``--tip`` option that names the far end of the legs' last links (from their collision or visual
    geometry, else twice their centre of mass), with a glob pattern when the links' names share an end."""
    leg = legs[0]
    link = tree.links[leg.end]
    joint = leg.joints[-1]
    axis = np.array([1.0, 0.0, 0.0]) if joint.axis is None else np.asarray(joint.axis, dtype=float)
    axis = axis / np.linalg.norm(axis)
    candidates = primitive_ends(link)
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


