"""The URDF of a robot file, for PyBullet: the writer of the simulated body of :mod:`shc_cli.model.body`.

Every robot file describes its own physics model; no URDF is written by hand. The tree
(``docs/physics-model.md`` has the details and the reasons):

* ``base_link`` — the torso (:class:`~shc_cli.model.body.Torso`).
* per leg ``LEG``: a fixed joint ``LEG_base_joint`` from ``base_link`` to the frame link ``LEG_base``
  placed at the DH transform ``A(base)``; then for each joint ``J`` (body to tip) a revolute joint
  ``LEG_J_joint`` turning about the z axis of the previous frame, whose child link ``LEG_J_link`` has
  its frame on that axis (the DH frame ``k − 1`` turned by the joint angle). The next joint (or the
  foot) sits at the joint's fixed DH transform ``M = Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)`` in that
  frame, written exactly as ``xyz = (r cos θ, r sin θ, d)``, ``rpy = (α, 0, θ)``. Rotations about z
  commute, so ``Rot_z(q)·M = A(θ + q)``: the URDF chain is the DH chain, joint angle for joint angle.
  The link's shape, mass and inertia are its :class:`~shc_cli.model.body.Segment`'s.
* a fixed joint ``LEG_foot_joint`` to the link ``LEG_foot``, whose frame is the DH tip frame and which
  carries the foot sphere (:class:`~shc_cli.model.body.Foot`) **centred on the tip**.
* with a servo ``armature``, a rotor link per joint (PyBullet has no joint armature: :func:`_rotor_link`).

Load with ``flags=pybullet.URDF_USE_INERTIA_FROM_FILE``, otherwise PyBullet replaces these inertias by ones of its
own made from the collision shapes. This module imports neither pybullet nor numpy's random state: the
output is a pure, deterministic function of the robot.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from shc_cli.model.body import (
    BASE_LINK,
    COLOURS,
    CUBE_SIDE,
    LegModel,
    Segment,
    Torso,
    body_model,
    joint_offset,
    leg_names,
)
from shc_cli.spec.robot import DH, Robot

ROTOR_MASS = 0.001
"""Mass of each rotor link (``[servo] armature`` > 0), taken from the link it rides on [kg]."""
ROTOR_RADIUS = 0.005
"""Radius of a rotor link's collision sphere (inside the link's capsule) [m]."""
_ZERO = 1e-15
"""Numbers smaller than this in magnitude are written as 0 (sin/cos round-off)."""


def link_names(robot: Robot) -> list[str]:
    """Every link in URDF order: ``base_link``, then per leg its base frame, joint links (each followed by its rotor
    link ``LEG_J_rotor`` when the servo has an armature) and foot."""
    out = [BASE_LINK]
    rotors = robot.servo.armature > 0.0
    for names in leg_names(robot).values():
        out.append(names.base)
        for link in names.links:
            out += [link, link.removesuffix("_link") + "_rotor"] if rotors else [link]
        out.append(names.foot)
    return out


# -- XML --------------------------------------------------------------------------------------------------------


def _num(value: float) -> str:
    """Shortest exact text of a float (``repr``), tiny round-off written as 0."""
    value = float(value)
    return "0" if abs(value) < _ZERO else repr(value)


def _vec(values: tuple[float, ...]) -> str:
    return " ".join(_num(v) for v in values)


def _origin(parent: ET.Element, xyz: tuple[float, float, float], rpy: tuple[float, float, float]) -> None:
    ET.SubElement(parent, "origin", xyz=_vec(xyz), rpy=_vec(rpy))


def _inertial(link: ET.Element, mass: float, com: tuple[float, float, float],
              rpy: tuple[float, float, float], moments: tuple[float, float, float]) -> None:
    inertial = ET.SubElement(link, "inertial")
    _origin(inertial, com, rpy)
    ET.SubElement(inertial, "mass", value=_num(mass))
    ixx, iyy, izz = moments
    ET.SubElement(inertial, "inertia", ixx=_num(ixx), ixy="0", ixz="0", iyy=_num(iyy), iyz="0", izz=_num(izz))


def _shape(link: ET.Element, tag: str, material: str, xyz: tuple[float, float, float],
           rpy: tuple[float, float, float], geometry: str, **attributes: str) -> None:
    """A visual (with ``material``) or collision element holding one geometry."""
    element = ET.SubElement(link, tag)
    _origin(element, xyz, rpy)
    ET.SubElement(ET.SubElement(element, "geometry"), geometry, dict(attributes))
    if tag == "visual":
        ET.SubElement(element, "material", name=material)


def _shapes(link: ET.Element, material: str, xyz: tuple[float, float, float],
            rpy: tuple[float, float, float], geometry: str, **attributes: str) -> None:
    for tag in ("visual", "collision"):
        _shape(link, tag, material, xyz, rpy, geometry, **attributes)


def _fixed(robot: ET.Element, name: str, parent: str, child: str,
           xyz: tuple[float, float, float], rpy: tuple[float, float, float]) -> None:
    joint = ET.SubElement(robot, "joint", name=name, type="fixed")
    _origin(joint, xyz, rpy)
    ET.SubElement(joint, "parent", link=parent)
    ET.SubElement(joint, "child", link=child)


def _dh_origin(dh: DH) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """``xyz, rpy`` of ``Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)``: rotation ``Rot_z(θ)·Rot_x(α)`` = rpy (α, 0, θ)."""
    return joint_offset(dh), (dh.alpha, 0.0, dh.theta)


def _torso(root: ET.Element, torso: Torso) -> None:
    link = ET.SubElement(root, "link", name=BASE_LINK)
    _inertial(link, torso.mass, torso.com, (0.0, 0.0, 0.0), torso.moments)
    _shapes(link, "body", torso.com, (0.0, 0.0, 0.0), "box", size=_vec(torso.size))


def _empty_link(root: ET.Element, name: str) -> None:
    """A frame without geometry: an explicit zero inertial (PyBullet gives 1 kg to links without one)."""
    link = ET.SubElement(root, "link", name=name)
    _inertial(link, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def _segment_link(root: ET.Element, segment: Segment, armature: float) -> None:
    """The link a joint moves, less :data:`ROTOR_MASS` when the joint has a rotor link (``armature`` > 0) and the
    link is heavy enough to give it (more than twice that; else the rotor adds its mass)."""
    link = ET.SubElement(root, "link", name=segment.link)
    mass = segment.mass - (ROTOR_MASS if armature > 0.0 and segment.mass > 2.0 * ROTOR_MASS else 0.0)
    if segment.shape == "box":
        side = (CUBE_SIDE, CUBE_SIDE, CUBE_SIDE)
        _inertial(link, mass, segment.middle, (0.0, 0.0, 0.0), segment.moments(mass))
        _shapes(link, "link", segment.middle, (0.0, 0.0, 0.0), "box", size=_vec(side))
        return
    rpy = (0.0, segment.pitch, segment.yaw)  # Rot_z(yaw)·Rot_y(pitch) turns z onto the segment
    _inertial(link, mass, segment.middle, rpy, segment.moments(mass))
    _shapes(link, "link", segment.middle, rpy, "capsule", radius=_num(segment.radius), length=_num(segment.straight))


def _rotor_link(root: ET.Element, link_name: str, armature: float) -> None:
    """The servo's rotor inertia reflected through the gearbox (PyBullet has no joint armature): a link fixed to
    the joint's link on the joint axis with inertia ``armature`` about it (a thin disc, half of it across). An
    approximation: the joints closer to the body also feel it (a real rotor spins ``N`` times faster only relative to
    its housing, so its inertia matters to its own joint alone)."""
    name = link_name.removesuffix("_link") + "_rotor"
    link = ET.SubElement(root, "link", name=name)
    across = armature / 2.0  # a thin disc: PyBullet refuses (zeroes) moments that break I_x + I_y ≥ I_z
    _inertial(link, ROTOR_MASS, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (across, across, armature))
    # PyBullet zeroes the inertia of a link without collision geometry: a small sphere inside the joint's capsule
    _shape(link, "collision", "link", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), "sphere", radius=_num(ROTOR_RADIUS))
    _fixed(root, name + "_joint", link_name, name, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def _leg(root: ET.Element, robot: Robot, leg: LegModel) -> None:
    names = leg.names
    _empty_link(root, names.base)
    _fixed(root, names.base_joint, BASE_LINK, names.base, *_dh_origin(leg.base))
    parent = names.base
    origin: tuple[tuple[float, float, float], tuple[float, float, float]] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    servo = robot.servo
    for segment in leg.segments:
        _segment_link(root, segment, servo.armature)
        element = ET.SubElement(root, "joint", name=segment.joint, type="revolute")
        _origin(element, *origin)
        ET.SubElement(element, "parent", link=parent)
        ET.SubElement(element, "child", link=segment.link)
        ET.SubElement(element, "axis", xyz="0 0 1")
        ET.SubElement(element, "limit", lower=_num(segment.dh.min), upper=_num(segment.dh.max),
                      effort=_num(servo.stall_torque), velocity=_num(servo.no_load_speed))
        if servo.armature > 0.0:
            _rotor_link(root, segment.link, servo.armature)
        parent, origin = segment.link, _dh_origin(segment.dh)
    foot = ET.SubElement(root, "link", name=leg.foot.name)
    _inertial(foot, leg.foot.mass, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (leg.foot.moment,) * 3)
    _shapes(foot, "foot", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), "sphere", radius=_num(leg.foot.radius))
    _fixed(root, names.foot_joint, parent, names.foot, *origin)


def robot_urdf(robot: Robot) -> str:
    """The URDF of ``robot`` as text (deterministic: the same robot gives the same bytes).

    Load it in PyBullet with ``flags=pybullet.URDF_USE_INERTIA_FROM_FILE``. Joint limits are the file's
    ``min``/``max``; effort and velocity limits are the servo's ``stall_torque`` and ``no_load_speed``.
    """
    model = body_model(robot)
    root = ET.Element("robot", name=robot.name)
    root.append(ET.Comment(f" Generated by shc from robot '{robot.name}'. Load with URDF_USE_INERTIA_FROM_FILE. "
                           .replace("--", "- -")))
    for name, rgba in COLOURS.items():
        ET.SubElement(ET.SubElement(root, "material", name=name), "color", rgba=_vec(rgba))
    _torso(root, model.torso)
    for leg in model.legs:
        _leg(root, robot, leg)
    ET.indent(root, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_urdf(robot: Robot, path: Path) -> Path:
    """Write :func:`robot_urdf` to ``path`` (UTF-8) and return the path."""
    path.write_text(robot_urdf(robot), encoding="utf-8")
    return path
