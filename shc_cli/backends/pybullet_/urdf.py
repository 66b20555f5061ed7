"""A PyBullet-ready URDF built from a robot file: the DH chains as links, with masses and inertias.

Every robot file describes its own physics model; no URDF is written by hand. The tree
(``docs/physics-model.md`` has the details and the reasons):

* ``base_link`` — the body: a box of ``body.size`` centred at ``body.com``, mass ``body.mass`` at
  ``body.com``, principal moments ``body.inertia`` or those of the solid box.
* per leg ``LEG``: a fixed joint ``LEG_base_joint`` from ``base_link`` to the frame link ``LEG_base``
  placed at the DH transform ``A(base)``; then for each joint ``J`` (body to tip) a revolute joint
  ``LEG_J_joint`` turning about the z axis of the previous frame, whose child link ``LEG_J_link`` has
  its frame on that axis (the DH frame ``k − 1`` turned by the joint angle). The next joint (or the
  foot) sits at the joint's fixed DH transform ``M = Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)`` in that
  frame, written exactly as ``xyz = (r cos θ, r sin θ, d)``, ``rpy = (α, 0, θ)``. Rotations about z
  commute, so ``Rot_z(q)·M = A(θ + q)``: the URDF chain is the DH chain, joint angle for joint angle.
* a fixed joint ``LEG_foot_joint`` to the link ``LEG_foot``, whose frame is the DH tip frame and which
  carries a sphere of ``foot_radius`` **centred on the tip**: the DH tip is the foot's centre, the
  contact point lies ``foot_radius`` below it on flat ground.

Link geometry is a capsule along the segment from the joint's origin to the next joint's origin (the
straight line through the DH offset ``(r cos θ, r sin θ, d)``); its round ends stop at the two origins.
Link masses sit at the segment's midpoint with the inertia of the solid capsule. Load with
``flags=pybullet.URDF_USE_INERTIA_FROM_FILE``, otherwise PyBullet replaces these inertias by ones of its
own made from the collision shapes. This module imports neither pybullet nor numpy's random state: the
output is a pure, deterministic function of the robot.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

from shc_cli.spec.robot import DH, Joint, Leg, Robot

DEFAULT_LINK_MASS = 0.1
"""Mass of a link whose joint gives no ``mass`` [kg]."""
MIN_LINK_MASS = 0.001
"""Smallest mass written for a link: a ``mass = 0`` is written as this [kg] (Bullet needs mass to move a link)."""
DEFAULT_FOOT_RADIUS = 0.01
"""Foot sphere radius of a leg whose ``foot_radius`` is 0 [m]."""
FOOT_MASS = 0.001
"""Mass of each foot sphere, added to the robot file's masses [kg]."""
ROTOR_MASS = 0.001
"""Mass of each rotor link (``[servo] armature`` > 0), taken from the link it rides on [kg]."""
ROTOR_RADIUS = 0.005
"""Radius of a rotor link's collision sphere (inside the link's capsule) [m]."""
LINK_RADIUS = 0.02
"""Capsule radius of a link, before the limits of :func:`link_radius` [m]."""
RADIUS_FRACTION = 0.25
"""Largest capsule radius as a share of the link's length (so the capsule's straight part is at least half)."""
DEGENERATE_LENGTH = 0.004
"""Links shorter than this (joint origins nearly coincident) get a small cube instead of a capsule [m]."""
CUBE_SIDE = 0.02
"""Side of the cube of a degenerate link, centred on the joint origin [m]."""
DEFAULT_EFFORT = 10.0
"""Joint effort limit when the robot has no servo section [N·m]."""
_ZERO = 1e-15
"""Numbers smaller than this in magnitude are written as 0 (sin/cos round-off)."""

COLOURS = {
    "body": (0.35, 0.38, 0.42, 1.0),
    "link": (0.85, 0.55, 0.15, 1.0),
    "foot": (0.12, 0.12, 0.12, 1.0),
}
"""Visual materials (red, green, blue, alpha)."""


@dataclass(frozen=True)
class LegNames:
    """URDF names of one leg's elements.

    Attributes:
        base_joint: fixed joint ``base_link`` → ``base``.
        base: the leg's frame link (the DH transform ``A(base)``).
        joints: revolute joints, body to tip (``LEG_J_joint``).
        links: child links of those joints (``LEG_J_link``).
        foot_joint: fixed joint from the last link to the foot.
        foot: the foot link; its frame is the DH tip.
    """

    base_joint: str
    base: str
    joints: tuple[str, ...]
    links: tuple[str, ...]
    foot_joint: str
    foot: str


BASE_LINK = "base_link"


def leg_names(robot: Robot) -> dict[str, LegNames]:
    """URDF names of every leg's joints and links, by leg id in id order."""
    return {
        leg_id: LegNames(
            base_joint=f"{leg_id}_base_joint",
            base=f"{leg_id}_base",
            joints=tuple(f"{leg_id}_{name}_joint" for name in leg.joints),
            links=tuple(f"{leg_id}_{name}_link" for name in leg.joints),
            foot_joint=f"{leg_id}_foot_joint",
            foot=f"{leg_id}_foot",
        )
        for leg_id, leg in robot.legs.items()
    }


def joint_names(robot: Robot) -> list[str]:
    """Revolute joint names in leg order, body to tip within a leg (``AR_coxa_joint``, …)."""
    return [name for names in leg_names(robot).values() for name in names.joints]


def foot_names(robot: Robot) -> list[str]:
    """Foot link names in leg order (``AR_foot``, …); each foot's frame is its leg's DH tip."""
    return [names.foot for names in leg_names(robot).values()]


def link_names(robot: Robot) -> list[str]:
    """Every link in URDF order: ``base_link``, then per leg its base frame, joint links (each followed by its rotor
    link ``LEG_J_rotor`` when the servo has an armature) and foot."""
    out = [BASE_LINK]
    rotors = _armature(robot) > 0.0
    for names in leg_names(robot).values():
        out.append(names.base)
        for link in names.links:
            out += [link, link.removesuffix("_link") + "_rotor"] if rotors else [link]
        out.append(names.foot)
    return out


def link_mass(joint: Joint) -> float:
    """Mass written for the link a joint moves: its ``mass``, :data:`DEFAULT_LINK_MASS` if absent [kg]."""
    mass = DEFAULT_LINK_MASS if joint.mass is None else joint.mass
    return max(mass, MIN_LINK_MASS)


def foot_radius(leg: Leg) -> float:
    """Radius of a leg's foot sphere: ``foot_radius``, :data:`DEFAULT_FOOT_RADIUS` if 0 [m]."""
    return leg.foot_radius if leg.foot_radius > 0.0 else DEFAULT_FOOT_RADIUS


def urdf_mass(robot: Robot) -> float:
    """Total mass of the URDF: body, every link (:func:`link_mass`) and one :data:`FOOT_MASS` per leg [kg].

    Equal to ``robot.total_mass() + FOOT_MASS · legs`` when every joint gives a mass of at least
    :data:`MIN_LINK_MASS`.
    """
    links = sum(link_mass(j) for leg in robot.legs.values() for j in leg.joints.values())
    return robot.body.mass + links + FOOT_MASS * len(robot.legs)


def joint_offset(dh: DH) -> tuple[float, float, float]:
    """Translation of the DH transform ``Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)`` [m]."""
    return (dh.r * math.cos(dh.theta), dh.r * math.sin(dh.theta), dh.d)


def link_radius(leg: Leg, index: int) -> float:
    """Capsule radius of the link moved by joint ``index`` of ``leg`` [m].

    :data:`LINK_RADIUS`, at most :data:`RADIUS_FRACTION` of the link's length, and for the last link at
    most the foot's radius — so the foot sphere, not the capsule's end, is the lowest point near the tip.
    """
    joint = list(leg.joints.values())[index]
    radius = min(LINK_RADIUS, RADIUS_FRACTION * math.dist((0.0, 0.0, 0.0), joint_offset(joint)))
    if index == len(leg.joints) - 1:
        radius = min(radius, foot_radius(leg))
    return radius


def capsule_inertia(mass: float, radius: float, length: float) -> tuple[float, float, float]:
    """Principal moments of a solid capsule about its centre of mass, axis along z [kg·m²].

    Args:
        mass: total mass [kg].
        radius: radius of the cylinder and of the two hemispherical ends [m].
        length: length of the cylindrical part (between the hemispheres' centres) [m].

    Returns:
        ``(ixx, iyy, izz)``, with ``ixx = iyy`` (across the axis) and ``izz`` about the axis. Uniform
        density: the cylinder holds ``m_c = m·V_c/V``, the two hemispheres ``m_s = m − m_c``;
        ``izz = m_c r²/2 + 2 m_s r²/5``, ``ixx = m_c (h²/12 + r²/4) + m_s (2r²/5 + h²/4 + 3hr/8)``.
    """
    cylinder = math.pi * radius**2 * length
    spheres = 4.0 / 3.0 * math.pi * radius**3
    m_c = mass * cylinder / (cylinder + spheres)
    m_s = mass - m_c
    axial = m_c * radius**2 / 2.0 + m_s * 2.0 * radius**2 / 5.0
    across = m_c * (length**2 / 12.0 + radius**2 / 4.0) + m_s * (
        2.0 * radius**2 / 5.0 + length**2 / 4.0 + 3.0 * length * radius / 8.0
    )
    return (across, across, axial)


def box_inertia(mass: float, size: tuple[float, float, float]) -> tuple[float, float, float]:
    """Principal moments of a solid box about its centre, axes along its edges [kg·m²]."""
    x, y, z = size
    return (mass * (y * y + z * z) / 12.0, mass * (x * x + z * z) / 12.0, mass * (x * x + y * y) / 12.0)


def sphere_inertia(mass: float, radius: float) -> float:
    """Moment of a solid sphere about any axis through its centre [kg·m²]."""
    return 2.0 * mass * radius**2 / 5.0


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


def _limits(robot: Robot, joint: Joint) -> tuple[float, float]:
    """Effort [N·m] and velocity [rad/s] limits: the servo's if the robot has one, else defaults."""
    servo = getattr(robot, "servo", None)
    effort = getattr(servo, "stall_torque", None)
    velocity = getattr(servo, "no_load_speed", None)
    return (DEFAULT_EFFORT if effort is None else float(effort),
            joint.max_vel if velocity is None else float(velocity))


def _body(root: ET.Element, robot: Robot) -> None:
    body = robot.body
    link = ET.SubElement(root, "link", name=BASE_LINK)
    moments = body.inertia if body.inertia is not None else box_inertia(body.mass, body.size)
    _inertial(link, body.mass, body.com, (0.0, 0.0, 0.0), moments)
    _shapes(link, "body", body.com, (0.0, 0.0, 0.0), "box", size=_vec(body.size))


def _empty_link(root: ET.Element, name: str) -> None:
    """A frame without geometry: an explicit zero inertial (PyBullet gives 1 kg to links without one)."""
    link = ET.SubElement(root, "link", name=name)
    _inertial(link, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def _segment_link(root: ET.Element, name: str, leg: Leg, index: int, joint: Joint, rotor: float = 0.0) -> None:
    """The link moved by a joint: a capsule from its origin to the next joint's, mass at the midpoint (less
    :data:`ROTOR_MASS` when the joint has a rotor link, ``rotor`` > 0)."""
    link = ET.SubElement(root, "link", name=name)
    mass = link_mass(joint) - (ROTOR_MASS if rotor > 0.0 and link_mass(joint) > 2.0 * ROTOR_MASS else 0.0)
    end = joint_offset(joint)
    length = math.dist((0.0, 0.0, 0.0), end)
    middle = (end[0] / 2.0, end[1] / 2.0, end[2] / 2.0)
    if length < DEGENERATE_LENGTH:
        side = CUBE_SIDE
        _inertial(link, mass, middle, (0.0, 0.0, 0.0), box_inertia(mass, (side, side, side)))
        _shapes(link, "link", middle, (0.0, 0.0, 0.0), "box", size=_vec((side, side, side)))
        return
    # rpy turning z onto the segment: R = Rot_z(yaw)·Rot_y(pitch) takes z to (sin p cos y, sin p sin y, cos p).
    rpy = (0.0, math.atan2(math.hypot(end[0], end[1]), end[2]), math.atan2(end[1], end[0]))
    radius = link_radius(leg, index)
    straight = length - 2.0 * radius
    _inertial(link, mass, middle, rpy, capsule_inertia(mass, radius, straight))
    _shapes(link, "link", middle, rpy, "capsule", radius=_num(radius), length=_num(straight))


def _armature(robot: Robot) -> float:
    """The servo's reflected rotor inertia [kg·m²] (0 without a ``[servo]`` section)."""
    return float(getattr(getattr(robot, "servo", None), "armature", 0.0) or 0.0)


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


def _foot_link(root: ET.Element, name: str, radius: float) -> None:
    link = ET.SubElement(root, "link", name=name)
    _inertial(link, FOOT_MASS, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (sphere_inertia(FOOT_MASS, radius),) * 3)
    _shapes(link, "foot", (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), "sphere", radius=_num(radius))


def _leg(root: ET.Element, robot: Robot, leg: Leg, names: LegNames) -> None:
    _empty_link(root, names.base)
    _fixed(root, names.base_joint, BASE_LINK, names.base, *_dh_origin(leg.base))
    parent = names.base
    origin: tuple[tuple[float, float, float], tuple[float, float, float]] = ((0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    for index, (joint, joint_name, link_name) in enumerate(zip(leg.joints.values(), names.joints, names.links,
                                                               strict=True)):
        armature = _armature(robot)
        _segment_link(root, link_name, leg, index, joint, armature)
        element = ET.SubElement(root, "joint", name=joint_name, type="revolute")
        _origin(element, *origin)
        ET.SubElement(element, "parent", link=parent)
        ET.SubElement(element, "child", link=link_name)
        ET.SubElement(element, "axis", xyz="0 0 1")
        effort, velocity = _limits(robot, joint)
        ET.SubElement(element, "limit", lower=_num(joint.min), upper=_num(joint.max),
                      effort=_num(effort), velocity=_num(velocity))
        if armature > 0.0:
            _rotor_link(root, link_name, armature)
        parent, origin = link_name, _dh_origin(joint)
    _foot_link(root, names.foot, foot_radius(leg))
    _fixed(root, names.foot_joint, parent, names.foot, *origin)


def robot_urdf(robot: Robot) -> str:
    """The URDF of ``robot`` as text (deterministic: the same robot gives the same bytes).

    Load it in PyBullet with ``flags=pybullet.URDF_USE_INERTIA_FROM_FILE``. Joint limits are the file's
    ``min``/``max``; effort and velocity limits are the servo's ``stall_torque`` and ``no_load_speed`` when
    the robot has a ``servo`` section, else :data:`DEFAULT_EFFORT` and the joint's ``max_vel``.
    """
    root = ET.Element("robot", name=robot.name)
    root.append(ET.Comment(f" Generated by shc from robot '{robot.name}'. Load with URDF_USE_INERTIA_FROM_FILE. "
                           .replace("--", "- -")))
    for name, rgba in COLOURS.items():
        ET.SubElement(ET.SubElement(root, "material", name=name), "color", rgba=_vec(rgba))
    _body(root, robot)
    for leg, names in zip(robot.legs.values(), leg_names(robot).values(), strict=True):
        _leg(root, robot, leg, names)
    ET.indent(root, space="  ")
    return '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def write_urdf(robot: Robot, path: Path) -> Path:
    """Write :func:`robot_urdf` to ``path`` (UTF-8) and return the path."""
    path.write_text(robot_urdf(robot), encoding="utf-8")
    return path
