"""The terrain's bodies in a PyBullet client (the geometry itself is :mod:`shc_cli.backends.terrain`).

Ramps, stairs and blocks are boxes merged into ONE body with one compound collision shape, loaded from a
generated single-link URDF: PyBullet's ``createCollisionShapeArray`` silently keeps only the first 16 shapes and
``createMultiBody`` only 127 links (measured with pybullet 3.2.7), while a URDF link takes any number of
``<collision>`` elements. Boxes give exact surfaces (ray hits agree with :meth:`Terrain.height_at` to float
precision). ``pybullet`` is imported inside the functions that need it so the CLI starts fast.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

from shc_cli.backends.pybullet_.quiet import quiet_stdout
from shc_cli.backends.terrain import FEATURE_RGBA, FEATURE_START_X, GROUND_RGBA, Box, Terrain, TerrainSpec

# -- building --------------------------------------------------------------------------------------------------


def _boxes_urdf(boxes: list[Box], shade: tuple[float, float] | None) -> str:
    """A single fixed link holding every box as a ``<collision>`` (and a ``<visual>``) element."""

    def number(value: float) -> str:
        return repr(float(value))

    lines = ['<?xml version="1.0"?>', '<robot name="terrain">', '<link name="terrain">',
             '<inertial><mass value="0"/><inertia ixx="0" ixy="0" ixz="0" iyy="0" iyz="0" izz="0"/></inertial>']
    for box in boxes:
        origin = f'<origin xyz="{" ".join(map(number, box.center))}" rpy="0 {number(box.pitch)} 0"/>'
        geometry = f'<geometry><box size="{" ".join(map(number, box.size))}"/></geometry>'
        light = 1.0
        if shade is not None:  # blocks: lighter the higher, to tell them apart in the GUI
            low, high = shade
            light = 0.75 + 0.5 * (0.5 if high <= low else (box.size[2] - low) / (high - low))
        color = " ".join(f"{min(1.0, c * light):.3f}" for c in FEATURE_RGBA[:3]) + " 1"
        lines.append(f"<collision>{origin}{geometry}</collision>")  # one element a line: long lines fail to load
        lines.append(f'<visual>{origin}{geometry}<material name=""><color rgba="{color}"/></material></visual>')
    lines += ["</link>", "</robot>", ""]
    return "\n".join(lines)


def build_terrain(client_id: int, spec: TerrainSpec, friction: float, restitution: float, seed: int,
                  scale: float = 1.0) -> Terrain:
    """Create the terrain's bodies in PyBullet client ``client_id``; returns them with the analytic height.

    Args:
        client_id: An open PyBullet client.
        spec: The terrain (from :func:`parse_terrain`).
        friction: Lateral friction of every terrain body.
        restitution: Restitution of every terrain body.
        seed: Seed of the block heights (``numpy.random.default_rng(seed)``); the same seed gives the same
            terrain. Unused by the other terrains.
        scale: The robot's scale of the level terrains (:func:`~shc_cli.backends.terrain.robot_scale`).
    """
    import pybullet as p

    terrain = Terrain(spec, seed, scale=scale)
    c = client_id
    with quiet_stdout():
        plane = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=c)
        plane_visual = p.createVisualShape(p.GEOM_PLANE, rgbaColor=list(GROUND_RGBA), physicsClientId=c)
        bodies = [p.createMultiBody(0.0, plane, plane_visual, physicsClientId=c)]
        boxes = terrain.boxes()
        if boxes:
            shade = (terrain.spec.low, terrain.spec.high) if terrain.spec.kind == "blocks" else None
            with tempfile.TemporaryDirectory(prefix="shc-terrain-") as folder:
                path = Path(folder) / "terrain.urdf"
                path.write_text(_boxes_urdf(boxes, shade), encoding="utf-8")
                bodies.append(p.loadURDF(str(path), useFixedBase=True, physicsClientId=c))
        if terrain.spec.kind == "heightfield":
            bodies.append(_build_heightfield(c, terrain))
    for body in bodies:
        for link in range(-1, p.getNumJoints(body, physicsClientId=c)):
            p.changeDynamics(body, link, lateralFriction=friction, restitution=restitution, physicsClientId=c)
    terrain.body_ids = tuple(bodies)
    return terrain


def _build_heightfield(c: int, terrain: Terrain) -> int:
    """A PyBullet height field: rows = samples along x; the shape is centred on the middle of its extent."""
    import pybullet

    assert terrain.field is not None
    field, cell = terrain.field, terrain.spec.cell
    nx, ny = field.shape
    low, high = float(field.min()), float(field.max())
    shape = pybullet.createCollisionShape(
        pybullet.GEOM_HEIGHTFIELD, meshScale=[cell, cell, 1.0], heightfieldData=field.T.ravel().tolist(),
        numHeightfieldRows=nx, numHeightfieldColumns=ny, physicsClientId=c)
    centre = [FEATURE_START_X + (nx - 1) * cell / 2.0, 0.0, (low + high) / 2.0]
    body = int(pybullet.createMultiBody(0.0, shape, basePosition=centre, physicsClientId=c))
    pybullet.changeVisualShape(body, -1, rgbaColor=list(FEATURE_RGBA), physicsClientId=c)
    return body
