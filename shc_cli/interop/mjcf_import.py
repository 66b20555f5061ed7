"""``shc import mjcf``: a legged robot's MJCF → an shc robot file, with MuJoCo's own loader for the kinematics.

MuJoCo compiles the file (includes, defaults, ``euler``/``axisangle``/``quat`` orientations, ``ref`` and
``range``); its compiled model is written as a URDF that keeps every MuJoCo body frame, and that URDF goes
through ``shc import urdf`` (:mod:`shc_cli.interop.urdf_import`): the same checks, notes, stance search and
servo map. The tips are then checked against MuJoCo's own forward kinematics (``mj_kinematics``) at random
joint vectors.

* **Robot**: the body under the world body with a free joint (else the one with the most bodies below it); a
  free joint is the robot's, not a leg's. Other bodies under the world body are left out (a note names them).
* **Frames**: a body with joints is the URDF link at its last joint's anchor (``jnt_pos``), in the body's
  orientation; a body with several joints gets one link per joint (``BODY__JOINT``). Geoms and the inertial
  move with their body.
* **Joints**: a hinge is revolute (angle 0 at ``qpos0``, MuJoCo's ``ref``; limits ``range − ref``; a hinge
  without ``range`` continuous), a slide prismatic, a ball floating (refused in a leg).
* **Geoms**: spheres, boxes, cylinders and capsules (as cylinders) are the URDF's geometry, collision if their
  ``contype`` or ``conaffinity`` is not 0, else visual; meshes and planes are not written (missing mesh files are
  left out with a note: :func:`load`).
* **Effort**: the joint's ``actuatorfrcrange``, else its actuator's ``forcerange``, else a motor's ``ctrlrange``
  times its gear. MJCF has no speed limit: shc's default ``max_vel`` is used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.errors import Issue, SpecError

FloatArray = NDArray[np.float64]
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3
"""mjtJoint values."""
SHAPES = {2: "sphere", 3: "capsule", 5: "cylinder", 6: "box"}
"""mjtGeom values written as URDF geometry."""


def _fail(path: Path, problem: str, fix: str) -> SpecError:
    return SpecError([Issue(path, None, "", problem, fix)])


def load(path: Path) -> tuple[Any, list[str]]:
    """MuJoCo's compiled model of ``path`` and the notes on how it was loaded (one line if MuJoCo refuses it).

    Mesh or texture files the MJCF names but that are not there (a description copied without its assets, a
    repository whose large meshes did not come with it) do not stop the import, which reads neither: the file is
    compiled again without its mesh geoms, meshes and textures (:func:`_without_meshes`) and a note names the
    missing file."""
    import mujoco

    if not path.is_file():
        raise _fail(path, "file not found", "check the path")
    try:
        return mujoco.MjModel.from_xml_path(str(path)), []
    except ValueError as error:
        lines = str(error).strip().splitlines()
        first = lines[0] if lines else "error"
        model = _without_meshes(path) if "Error opening file" in first else first
        if isinstance(model, str):  # refused for another reason (with its meshes left out, that reason)
            raise _fail(path, f"MuJoCo cannot load it: {model}",
                        "check the MJCF (python -m mujoco.viewer opens it)") from None
        missing = first.split("Error opening file", 1)[1].strip(" :'\"")
        return model, [f"a file it names is missing ({missing}): loaded without its mesh geoms, meshes and textures "
                       "(the import reads none; a body's mass or inertia from its meshes is then lost)"]


def _without_meshes(path: Path) -> object:
    """``path`` compiled with every mesh geom, mesh and texture deleted (MuJoCo's MjSpec; materials keep their
    colours), or the first line of MuJoCo's error if it still fails."""
    import mujoco

    try:
        spec = mujoco.MjSpec.from_file(str(path))
        for geom in [g for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH]:
            spec.delete(geom)
        for mesh in list(spec.meshes):
            spec.delete(mesh)
        for texture in list(spec.textures):  # image files go missing with the meshes
            spec.delete(texture)
        for material in spec.materials:
            material.textures = [""] * len(material.textures)
        return spec.compile()
    except (ValueError, RuntimeError) as error:
        lines = str(error).strip().splitlines()
        return lines[0] if lines else "error"


def _frame(pos: Any, quat: Any) -> FloatArray:
    import mujoco

    out = np.eye(4)
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, np.asarray(quat, dtype=np.float64))
    out[:3, :3] = matrix.reshape(3, 3)
    out[:3, 3] = pos
    return out


def _shift(vector: Any) -> FloatArray:
    out = np.eye(4)
    out[:3, 3] = vector
    return out


def _origin(transform: FloatArray) -> str:
    """``<origin>`` of a homogeneous transform (URDF rpy: R = Rz(yaw)·Ry(pitch)·Rx(roll))."""
    r = transform[:3, :3]
    pitch = math.atan2(-r[2, 0], math.hypot(r[0, 0], r[1, 0]))
    if math.hypot(r[0, 0], r[1, 0]) < 1e-12:
        roll, yaw = math.atan2(-r[1, 2], r[1, 1]), 0.0
    else:
        roll, yaw = math.atan2(r[2, 1], r[2, 2]), math.atan2(r[1, 0], r[0, 0])
    xyz = " ".join(repr(float(v)) for v in transform[:3, 3])
    return f'<origin xyz="{xyz}" rpy="{roll!r} {pitch!r} {yaw!r}"/>'


@dataclass(frozen=True)
class Converted:
    """The URDF of an MJCF file, and what the FK check needs: each URDF link's MuJoCo body and the link frame in
    that body's frame."""

    urdf: str
    body_of: dict[str, int]
    link_in_body: dict[str, FloatArray]
    notes: list[str]


def _name(model: Any, kind: Any, index: int, fallback: str) -> str:
    import mujoco

    return mujoco.mj_id2name(model, kind, index) or f"{fallback}{index}"


def _effort(model: Any, joint: int) -> float | None:
    if model.jnt_actfrclimited[joint]:
        return float(np.abs(model.jnt_actfrcrange[joint]).max())
    for actuator in range(model.nu):
        if model.actuator_trntype[actuator] != 0 or model.actuator_trnid[actuator, 0] != joint:
            continue
        if model.actuator_forcelimited[actuator]:
            return float(np.abs(model.actuator_forcerange[actuator]).max())
        if model.actuator_ctrllimited[actuator] and model.actuator_biastype[actuator] == 0:
            return float(np.abs(model.actuator_ctrlrange[actuator]).max() * abs(model.actuator_gear[actuator, 0]))
    return None


def convert(path: Path, model: Any) -> Converted:
    """The URDF text of the compiled ``model`` (module docstring)."""
    import mujoco

    body_kind, joint_kind = mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_JOINT
    children: dict[int, list[int]] = {}
    for body in range(1, model.nbody):
        children.setdefault(int(model.body_parentid[body]), []).append(body)

    def below(body: int) -> list[int]:
        out, stack = [], [body]
        while stack:
            out.append(stack.pop())
            stack += children.get(out[-1], [])
        return out

    tops = children.get(0, [])
    if not tops:
        raise _fail(path, "no body under the world body", "give the MJCF of a robot")
    free = [b for b in tops if any(model.jnt_type[j] == FREE for j in range(model.njnt) if model.jnt_bodyid[j] == b)]
    root = free[0] if free else max(tops, key=lambda b: len(below(b)))
    notes = []
    others = [_name(model, body_kind, b, "body") for b in tops if b != root]
    if others:
        notes.append(f"bodies under the world body that are not the robot are left out: {', '.join(others)}")
    lines = [f'<?xml version="1.0"?>\n<robot name="{path.stem}">']
    body_of: dict[str, int] = {}
    link_in_body: dict[str, FloatArray] = {}
    anchor: dict[int, FloatArray] = {}
    for body in below(root):
        name = _name(model, body_kind, body, "body")
        joints = [j for j in range(model.njnt) if model.jnt_bodyid[j] == body and model.jnt_type[j] != FREE]
        if body == root:
            joints = []
        anchor[body] = _shift(model.jnt_pos[joints[-1]]) if joints else np.eye(4)
        body_of[name], link_in_body[name] = body, anchor[body]
        parent = int(model.body_parentid[body])
        into = np.linalg.inv(anchor[parent]) @ _frame(model.body_pos[body], model.body_quat[body]) \
            if body != root else np.eye(4)
        previous = _name(model, body_kind, parent, "body")
        for k, joint in enumerate(joints):
            joint_name = _name(model, joint_kind, joint, "joint")
            link = name if k == len(joints) - 1 else f"{name}__{joint_name}"
            if link != name:
                body_of[link], link_in_body[link] = body, _shift(model.jnt_pos[joint])
                lines.append(f'  <link name="{link}"/>')
            origin = (into if k == 0 else _shift(-model.jnt_pos[joints[k - 1]])) @ _shift(model.jnt_pos[joint])
            lines.append(_joint_xml(model, joint, joint_name, previous, link, origin))
            previous = link
        lines.append(_link_xml(model, body, name, anchor[body]))
        if not joints and body != root:
            lines.append(f'  <joint name="{name}_fixed" type="fixed"><parent link="{previous}"/><child link="{name}"/>'
                         f"{_origin(into)}</joint>")
    lines.append("</robot>\n")
    return Converted("\n".join(lines), body_of, link_in_body, notes)


def _joint_xml(model: Any, joint: int, name: str, parent: str, child: str, origin: FloatArray) -> str:
    kind = int(model.jnt_type[joint])
    zero = float(model.qpos0[model.jnt_qposadr[joint]]) if kind in (HINGE, SLIDE) else 0.0
    urdf_type = {HINGE: "revolute", SLIDE: "prismatic", BALL: "floating"}[kind]
    limit = ""
    effort = _effort(model, joint)
    effort_text = f' effort="{effort!r}"' if effort is not None else ""
    if kind in (HINGE, SLIDE) and model.jnt_limited[joint]:
        lower, upper = (float(v) - zero for v in model.jnt_range[joint])
        limit = f'<limit lower="{lower!r}" upper="{upper!r}"{effort_text}/>'
    elif kind == HINGE:
        urdf_type = "continuous"
        limit = f"<limit{effort_text}/>" if effort_text else ""
    axis = " ".join(repr(float(v)) for v in model.jnt_axis[joint])
    return (f'  <joint name="{name}" type="{urdf_type}"><parent link="{parent}"/><child link="{child}"/>'
            f'{_origin(origin)}<axis xyz="{axis}"/>{limit}</joint>')


def _link_xml(model: Any, body: int, name: str, anchor: FloatArray) -> str:
    out = [f'  <link name="{name}">']
    back = np.linalg.inv(anchor)
    if model.body_mass[body] > 0.0:
        ixx, iyy, izz = (repr(float(v)) for v in model.body_inertia[body])
        out.append(f"    <inertial>{_origin(back @ _frame(model.body_ipos[body], model.body_iquat[body]))}"
                   f'<mass value="{float(model.body_mass[body])!r}"/>'
                   f'<inertia ixx="{ixx}" ixy="0" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>')
    for geom in range(model.ngeom):
        if model.geom_bodyid[geom] != body or int(model.geom_type[geom]) not in SHAPES:
            continue
        shape, size = SHAPES[int(model.geom_type[geom])], model.geom_size[geom]
        text = {"sphere": f'<sphere radius="{float(size[0])!r}"/>',
                "capsule": f'<cylinder radius="{float(size[0])!r}" length="{2 * float(size[1])!r}"/>',
                "cylinder": f'<cylinder radius="{float(size[0])!r}" length="{2 * float(size[1])!r}"/>',
                "box": f'<box size="{" ".join(repr(2 * float(v)) for v in size)}"/>'}[shape]
        role = "collision" if model.geom_contype[geom] or model.geom_conaffinity[geom] else "visual"
        placed = back @ _frame(model.geom_pos[geom], model.geom_quat[geom])
        out.append(f"    <{role}>{_origin(placed)}<geometry>{text}</geometry></{role}>")
    out.append("  </link>")
    return "\n".join(out)


def mujoco_fk_error(model: Any, converted: Converted, robot: Any, tips: dict[str, tuple[str, FloatArray]],
                    base: str, yaw: float, samples: int = 200, seed: int = 0) -> float:
    """Largest distance between the robot file's tips and MuJoCo's ``mj_kinematics`` at random joint vectors
    inside the limits [m]; ``tips`` maps each leg's first URDF joint to its tip link and point in that link."""
    import mujoco

    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    servos = robot.hardware.servos
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    turn = np.array([[math.cos(yaw), math.sin(yaw), 0.0], [-math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    legs = list(robot.legs.items())
    worst = 0.0
    for _ in range(samples):
        q = rng.uniform(chains.lower, chains.upper)
        data.qpos[:] = model.qpos0
        for i, (leg_id, spec) in enumerate(legs):
            for k, joint in enumerate(spec.joints):
                index = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, str(servos[f"{leg_id}_{joint}"].joint))
                data.qpos[model.jnt_qposadr[index]] = model.qpos0[model.jnt_qposadr[index]] + q[i, k]
        mujoco.mj_kinematics(model, data)

        def frame(link: str) -> FloatArray:
            body = converted.body_of[link]
            return _world(data, body) @ converted.link_in_body[link]

        inverse = np.linalg.inv(frame(base))
        ours = chains.tips(q)
        for i, (leg_id, spec) in enumerate(legs):
            end, point = tips[str(servos[f"{leg_id}_{next(iter(spec.joints))}"].joint)]
            theirs = turn @ (inverse @ frame(end) @ np.append(point, 1.0))[:3]
            worst = max(worst, float(np.linalg.norm(ours[i] - theirs)))
    return worst


def _world(data: Any, body: int) -> FloatArray:
    out = np.eye(4)
    out[:3, :3] = np.asarray(data.xmat[body]).reshape(3, 3)
    out[:3, 3] = data.xpos[body]
    return out


def import_mjcf(file: Path, out: Path | None = None, name: str | None = None, legs: str = "auto",
                tips: list[str] | None = None, clearance: float | None = None, reach: float | None = None,
                snap: float = 0.0, forward: float | None = None,
                base: str | None = None, overwrite: bool = False) -> tuple[Any, float, list[str]]:
    """Write ``OUT/robots/NAME.toml`` from an MJCF file (module docstring): the URDF import's result, the largest
    tip difference to MuJoCo's forward kinematics [m] and the conversion's notes."""
    from shc_cli.interop.urdf_import import import_urdf
    from shc_cli.spec.loading import load_robot

    model, loading = load(file)
    converted = convert(file, model)
    converted.notes[:0] = loading
    result = import_urdf(file, out, name, legs, tips, clearance, reach, snap, None, forward, base,
                         given=converted.urdf, command="mjcf", overwrite=overwrite)
    robot = load_robot(result.robot_path).robot
    error = mujoco_fk_error(model, converted, robot, result.tips, result.base_frame, result.yaw)
    return result, error, converted.notes
