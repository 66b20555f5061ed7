"""What `shc view` and `shc render` draw, as numbers: the generated model's shapes and where they are.

The shapes are those of the simulated body (:mod:`shc_cli.model.body`): the body a box of
``body.size`` centred on ``body.com``, each link a capsule from its joint's origin to the next joint's (radius
:func:`~shc_cli.model.body.link_radius`), each foot a sphere of ``foot_radius`` centred on the DH
tip. Poses come from the logged joints and body pose through :meth:`Chains.frames_in_base` (numpy only), so
the viewer and the renderer draw exactly the kinematic model, for many frames at once. Lengths in metres,
angles in radians, quaternions ``(w, x, y, z)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shc_cli.analysis.metrics import rotation_rpy
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.record.summary import RunSummary
from shc_cli.spec.robot import Robot

BODY_RGB = (0.35, 0.38, 0.42)
"""Body colour (the URDF's ``body`` material)."""
LINK_RGB = (0.85, 0.55, 0.15)
"""Link colour (the URDF's ``link`` material)."""
LIMIT_RGB = (0.85, 0.10, 0.10)
"""A link whose joint is at (within :data:`LIMIT_MARGIN` of) a limit."""
FOOT_RGB = (0.12, 0.12, 0.12)
"""A foot in the air."""
CONTACT_RGB = (0.10, 0.70, 0.25)
"""A foot on the ground."""
LIMIT_MARGIN = 1e-3
"""A joint this close to a limit counts as at it [rad]."""


@dataclass(frozen=True)
class Shapes:
    """The model's fixed shapes, legs in id order, padded to ``n`` joints.

    Attributes:
        legs: leg ids.
        chains: the legs' DH chains.
        link_radius: capsule radius of each joint's link, ``(L, n)`` (0 for padding) [m].
        link_real: which ``(leg, joint)`` slots are real joints, ``(L, n)``.
        foot_radius: foot sphere radius per leg, ``(L,)`` [m].
        body_size: body box edge lengths [m].
        body_com: body box centre in base_link [m].
    """

    legs: tuple[str, ...]
    chains: Chains
    link_radius: FloatArray
    link_real: np.ndarray
    foot_radius: FloatArray
    body_size: tuple[float, float, float]
    body_com: tuple[float, float, float]


def shapes(robot: Robot) -> Shapes:
    """The shapes of ``robot``'s generated model."""
    from shc_cli.model.body import foot_radius, link_radius

    chains = Chains.from_robot(robot)
    radius = np.zeros((chains.size, chains.joints))
    real = np.zeros((chains.size, chains.joints), dtype=bool)
    for i, leg in enumerate(robot.legs.values()):
        for k in range(len(leg.joints)):
            radius[i, k] = link_radius(leg, k)
            real[i, k] = True
    feet = np.array([foot_radius(leg) for leg in robot.legs.values()])
    return Shapes(tuple(robot.legs), chains, radius, real, feet, tuple(robot.body.size),  # type: ignore[arg-type]
                  tuple(robot.body.com))  # type: ignore[arg-type]


def rpy_quaternion(rpy: FloatArray) -> FloatArray:
    """Quaternions ``(w, x, y, z)`` of roll, pitch, yaw (``Rz·Ry·Rx``), ``(..., 3)`` → ``(..., 4)``. (Matrices come
    from :func:`shc_cli.analysis.metrics.rotation_rpy`, the one roll/pitch/yaw → matrix conversion off the hot path.)"""
    half = np.asarray(rpy, dtype=float) / 2.0
    cr, sr = np.cos(half[..., 0]), np.sin(half[..., 0])
    cp, sp = np.cos(half[..., 1]), np.sin(half[..., 1])
    cy, sy = np.cos(half[..., 2]), np.sin(half[..., 2])
    return np.stack([cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
                     cr * cp * sy - sr * sp * cy], axis=-1)


def z_to(direction: FloatArray) -> FloatArray:
    """Quaternions ``(w, x, y, z)`` of the shortest rotation taking +z onto each ``direction`` ``(..., 3)``
    (zero vectors give the identity, −z a half turn about x)."""
    v = np.asarray(direction, dtype=float)
    length = np.linalg.norm(v, axis=-1, keepdims=True)
    unit = np.divide(v, length, out=np.zeros_like(v), where=length > 0.0)
    unit[(length[..., 0] == 0.0)] = (0.0, 0.0, 1.0)
    axis = np.stack([-unit[..., 1], unit[..., 0], np.zeros(unit.shape[:-1])], axis=-1)  # z × u
    sine = np.linalg.norm(axis, axis=-1)
    angle = np.arctan2(sine, unit[..., 2])  # accurate near 0 and near a half turn
    axis = np.divide(axis, sine[..., None], out=np.zeros_like(axis), where=sine[..., None] > 0.0)
    axis[sine == 0.0] = (1.0, 0.0, 0.0)
    half = angle / 2.0
    return np.concatenate([np.cos(half)[..., None], axis * np.sin(half)[..., None]], axis=-1)


@dataclass(frozen=True)
class Poses:
    """Where the shapes are at ``N`` frames, in the world.

    Attributes:
        origins: joint origins and the tip per leg, ``(N, L, n + 1, 3)``: link ``k`` runs from origin ``k`` to
            origin ``k + 1``; origin ``n`` is the foot centre (padding repeats the tip).
        body_position: base_link position, ``(N, 3)``.
        body_quaternion: base_link orientation ``(w, x, y, z)``, ``(N, 4)``.
        body_rotation: base_link orientation as matrices, ``(N, 3, 3)``.
    """

    origins: FloatArray
    body_position: FloatArray
    body_quaternion: FloatArray
    body_rotation: FloatArray

    @property
    def feet(self) -> FloatArray:
        """Foot centres, ``(N, L, 3)``."""
        return np.asarray(self.origins[:, :, -1])


def poses(shape: Shapes, joints: FloatArray, position: FloatArray, rpy: FloatArray) -> Poses:
    """World poses of every shape for joints ``(N, L, n)``, body positions ``(N, 3)`` and orientations ``(N, 3)``."""
    frames = shape.chains.frames_in_base(np.asarray(joints, dtype=float))[..., :3, 3]  # (N, L, n + 1, 3)
    rotation = rotation_rpy(np.asarray(rpy, dtype=float))
    world = np.einsum("nij,nlkj->nlki", rotation, frames) + np.asarray(position)[:, None, None, :]
    return Poses(world, np.asarray(position, dtype=float), rpy_quaternion(rpy), rotation)


def at_limit(shape: Shapes, joints: FloatArray) -> np.ndarray:
    """Which joints are within :data:`LIMIT_MARGIN` of a limit, ``(..., L, n)`` (padding never)."""
    chains = shape.chains
    hit = (joints <= chains.lower + LIMIT_MARGIN) | (joints >= chains.upper - LIMIT_MARGIN)
    return np.asarray(hit & shape.link_real)


def workplane_outline(plane: dict[int, float], centre: tuple[float, float], z: float = 0.0,
                      samples: int = 1) -> FloatArray:
    """A workplane (bearing [deg] → radius [m]) as a closed outline around ``centre``, ``(K, 3)``."""
    bearings = sorted(b for b in plane if b < 360)
    points = []
    for b in bearings:
        angle = math.radians(b)
        points.append((centre[0] + plane[b] * math.cos(angle), centre[1] + plane[b] * math.sin(angle), z))
    points.append(points[0])
    return np.array(points)


@dataclass(frozen=True)
class Box:
    """A terrain box: centre and edge lengths [m], pitch about y [rad], RGB."""

    centre: tuple[float, float, float]
    size: tuple[float, float, float]
    pitch: float
    rgb: tuple[float, float, float]


TERRAIN_RGB = (0.62, 0.55, 0.47)
GROUND_RGB = (0.82, 0.82, 0.80)


@dataclass(frozen=True)
class TerrainShapes:
    """A run's terrain as drawable shapes.

    Attributes:
        text: the ``--terrain`` text (``flat`` when the run does not say).
        boxes: blocks, ramp and stair boxes.
        mesh: a height field as ``(vertices (V, 3), faces (F, 3))``, or ``None``.
    """

    text: str
    boxes: list[Box]
    mesh: tuple[FloatArray, np.ndarray] | None = None


def terrain_shapes(summary: RunSummary, robot: Robot | None = None) -> TerrainShapes:
    """The terrain a run walked on, from its summary (``terrain``, ``seed``), as the simulation built it (the level
    terrains scaled to ``robot``, docs/terrains.md). A terrain that cannot be rebuilt (a height-field file no longer
    there) is drawn flat."""
    from shc_cli.backends.terrain import FEATURE_START_X, Terrain, parse_terrain, robot_scale
    from shc_cli.errors import ShcError

    text = summary.terrain or "flat"
    scale = 1.0 if robot is None else robot_scale(robot.walker.body_clearance)
    try:
        terrain = Terrain(parse_terrain(text), summary.seed or 0, scale=scale)
        raw = terrain.boxes()
    except (ShcError, OSError, ValueError):
        return TerrainShapes(text, [])
    out = []
    low, high = terrain.spec.low, terrain.spec.high
    for box in raw:
        light = 1.0
        if terrain.spec.kind == "blocks":
            light = 0.75 + 0.5 * (0.5 if high <= low else (box.size[2] - low) / (high - low))
        rgb = tuple(min(1.0, c * light) for c in TERRAIN_RGB)
        out.append(Box(tuple(box.center), tuple(box.size), float(box.pitch), rgb))  # type: ignore[arg-type]
    mesh = None
    if terrain.spec.kind == "heightfield":
        mesh = heightfield_mesh(np.array(terrain.spec.heights, dtype=float), terrain.spec.cell, FEATURE_START_X)
    return TerrainShapes(text, out, mesh)


def heightfield_mesh(heights: FloatArray, cell: float, start_x: float) -> tuple[FloatArray, np.ndarray]:
    """Triangles of a height field ``heights[i, j]`` at ``x = start_x + i·cell``, ``y = (j − (ny − 1)/2)·cell``,
    each cell split along its (i+1, j)–(i, j+1) diagonal as PyBullet does; faces counter-clockwise from above."""
    nx, ny = heights.shape
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    vertices = np.column_stack([start_x + i.ravel() * cell, (j.ravel() - (ny - 1) / 2.0) * cell, heights.ravel()])
    index = (i * ny + j)[:-1, :-1].ravel()
    a, b, c, d = index, index + ny, index + 1, index + ny + 1  # (i, j), (i+1, j), (i, j+1), (i+1, j+1)
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([b, d, c])])
    return vertices, faces.astype(np.uint32)
