"""The simulated body of a robot, engine-neutral: names, masses, inertias, link and foot shapes.

Every engine simulates the bodies described here (``docs/physics-model.md`` has the details and the reasons);
the URDF (:mod:`shc_cli.backends.pybullet_.urdf`) and MJCF (:mod:`shc_cli.backends.mujoco_.mjcf`) writers only
serialise a :class:`BodyModel`, the viewer draws it and the analysis weighs it.

* the torso: a box of ``body.size`` centred at ``body.com``, mass ``body.mass`` at ``body.com``, principal
  moments ``body.inertia`` or those of the solid box (:class:`Torso`);
* per leg, the link each joint moves (:class:`Segment`): a capsule along the straight line from the joint's
  origin to the next joint's (the DH offset ``(r cos θ, r sin θ, d)``), its round ends stopping at the two
  origins, the link's mass at the segment's midpoint with the inertia of the solid capsule — or a small cube
  when the two origins nearly coincide;
* per leg a foot sphere of ``foot_radius`` **centred on the DH tip** (:class:`Foot`): the contact point lies
  ``foot_radius`` below the tip on flat ground.

:func:`body_mass` is the total mass the engines simulate (default link masses and foot spheres included). The
module imports neither an engine nor numpy: the model is a pure, deterministic function of the robot.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from shc_cli.spec.robot import DH, Joint, Leg, Robot

Vec3 = tuple[float, float, float]

GRAVITY = 9.81
"""Standard gravity [m/s²]: what every engine simulates, the IMU feels and the cost of transport divides by."""

DEFAULT_LINK_MASS = 0.1
"""Mass of a link whose joint gives no ``mass`` [kg]."""
MIN_LINK_MASS = 0.001
"""Smallest mass of a link: a ``mass = 0`` is simulated as this [kg] (Bullet needs mass to move a link)."""
DEFAULT_FOOT_RADIUS = 0.01
"""Foot sphere radius of a leg whose ``foot_radius`` is 0 [m]."""
FOOT_MASS = 0.001
"""Mass of each foot sphere, added to the robot file's masses [kg]."""
LINK_RADIUS = 0.02
"""Capsule radius of a link, before the limits of :func:`link_radius` [m]."""
RADIUS_FRACTION = 0.25
"""Largest capsule radius as a share of the link's length (so the capsule's straight part is at least half)."""
DEGENERATE_LENGTH = 0.004
"""Links shorter than this (joint origins nearly coincident) get a small cube instead of a capsule [m]."""
CUBE_SIDE = 0.02
"""Side of the cube of a degenerate link, centred on the segment's midpoint [m]."""

COLOURS: dict[str, tuple[float, float, float, float]] = {
    "body": (0.35, 0.38, 0.42, 1.0),
    "link": (0.85, 0.55, 0.15, 1.0),
    "foot": (0.12, 0.12, 0.12, 1.0),
}
"""Colours (red, green, blue, alpha) of the torso, the links and the feet."""
BASE_LINK = "base_link"
"""Name of the torso's link; its frame is shc's ``base_link`` (x forward, y left, z up)."""


@dataclass(frozen=True)
class LegNames:
    """Names of one leg's joints and links, the same in every engine and in the recordings.

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


def leg_names(robot: Robot) -> dict[str, LegNames]:
    """Names of every leg's joints and links, by leg id in id order."""
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


def hardware_joint_names(robot: Robot) -> list[str]:
    """The joints' names on the robot itself, in leg order: ``[hardware.servos]``'s ``joint`` where given (an
    imported URDF's joint names, what the robot's own driver publishes in ``/joint_states``), else
    :func:`joint_names`'s ``AR_coxa_joint``."""
    servos = robot.hardware.servos
    return [(servos[f"{leg}_{joint}"].joint if f"{leg}_{joint}" in servos else None) or f"{leg}_{joint}_joint"
            for leg, spec in robot.legs.items() for joint in spec.joints]


def foot_names(robot: Robot) -> list[str]:
    """Foot link names in leg order (``AR_foot``, …); each foot's frame is its leg's DH tip."""
    return [names.foot for names in leg_names(robot).values()]


def link_mass(joint: Joint) -> float:
    """Mass of the link a joint moves: its ``mass``, :data:`DEFAULT_LINK_MASS` if absent, at least
    :data:`MIN_LINK_MASS` [kg]."""
    mass = DEFAULT_LINK_MASS if joint.mass is None else joint.mass
    return max(mass, MIN_LINK_MASS)


def foot_radius(leg: Leg) -> float:
    """Radius of a leg's foot sphere: ``foot_radius``, :data:`DEFAULT_FOOT_RADIUS` if 0 [m]."""
    return leg.foot_radius if leg.foot_radius > 0.0 else DEFAULT_FOOT_RADIUS


def body_mass(robot: Robot) -> float:
    """Total mass of the simulated body: torso, every link (:func:`link_mass`, so a link without ``mass`` counts
    :data:`DEFAULT_LINK_MASS`) and one :data:`FOOT_MASS` per leg [kg] — what every engine simulates.

    Equal to ``robot.total_mass() + FOOT_MASS · legs`` when every joint gives a mass of at least
    :data:`MIN_LINK_MASS`.
    """
    links = sum(link_mass(j) for leg in robot.legs.values() for j in leg.joints.values())
    return robot.body.mass + links + FOOT_MASS * len(robot.legs)


def joint_offset(dh: DH) -> Vec3:
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


def capsule_inertia(mass: float, radius: float, length: float) -> Vec3:
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


def box_inertia(mass: float, size: Vec3) -> Vec3:
    """Principal moments of a solid box about its centre, axes along its edges [kg·m²]."""
    x, y, z = size
    return (mass * (y * y + z * z) / 12.0, mass * (x * x + z * z) / 12.0, mass * (x * x + y * y) / 12.0)


def sphere_inertia(mass: float, radius: float) -> float:
    """Moment of a solid sphere about any axis through its centre [kg·m²]."""
    return 2.0 * mass * radius**2 / 5.0


@dataclass(frozen=True)
class Torso:
    """The body box (link :data:`BASE_LINK`).

    Attributes:
        mass: [kg].
        com: centre of mass and of the box, in ``base_link`` [m].
        size: the box's edges x, y, z [m].
        moments: principal moments about ``com``, axes along the box's edges [kg·m²].
    """

    mass: float
    com: Vec3
    size: Vec3
    moments: Vec3


@dataclass(frozen=True)
class Segment:
    """The link a revolute joint moves, in the frame on that joint's axis (the DH frame ``k − 1`` turned by the
    joint angle). The next joint (or the foot) sits at the joint's fixed DH transform ``dh``.

    Attributes:
        joint: name of the revolute joint.
        link: name of the link.
        dh: the joint's DH parameters and limits (``min``/``max`` [rad]).
        mass: the link's mass (:func:`link_mass`) [kg].
        end: the next joint's origin, ``joint_offset(dh)`` [m].
        length: distance from the joint's origin to ``end`` [m].
        middle: centre of mass and of the shape, the segment's midpoint [m].
        shape: ``capsule`` along the segment, or ``box`` (a cube of :data:`CUBE_SIDE`) when ``length`` is below
            :data:`DEGENERATE_LENGTH`.
        radius: the capsule's radius (:func:`link_radius`) [m]; 0 for a box.
        pitch: the capsule axis' angle from z [rad]: ``Rot_z(yaw)·Rot_y(pitch)`` turns z onto the segment.
        yaw: the capsule axis' heading about z [rad].
    """

    joint: str
    link: str
    dh: Joint
    mass: float
    end: Vec3
    length: float
    middle: Vec3
    shape: Literal["capsule", "box"]
    radius: float
    pitch: float
    yaw: float

    @property
    def straight(self) -> float:
        """Length of the capsule's cylindrical part, between its ends' centres [m]."""
        return self.length - 2.0 * self.radius

    def moments(self, mass: float | None = None) -> Vec3:
        """Principal moments about ``middle`` of the shape holding ``mass`` (default: the link's), axis z along
        the capsule (turned by ``pitch``/``yaw``) or along the cube's edges [kg·m²]."""
        mass = self.mass if mass is None else mass
        if self.shape == "box":
            return box_inertia(mass, (CUBE_SIDE, CUBE_SIDE, CUBE_SIDE))
        return capsule_inertia(mass, self.radius, self.straight)


@dataclass(frozen=True)
class Foot:
    """A leg's foot: a sphere of :data:`FOOT_MASS` centred on the DH tip, the frame of link ``name``.

    Attributes:
        name: the foot link's name.
        radius: [m].
    """

    name: str
    radius: float
    mass: float = FOOT_MASS

    @property
    def moment(self) -> float:
        """Moment about any axis through the tip [kg·m²]."""
        return sphere_inertia(self.mass, self.radius)


@dataclass(frozen=True)
class LegModel:
    """One leg: its frame at ``A(base)`` in ``base_link``, its links body to tip, its foot.

    Attributes:
        id: the leg's id.
        names: its joint and link names.
        base: the fixed DH transform from ``base_link`` to the first joint's frame.
        segments: the links the joints move, body to tip.
        foot: the foot at the last joint's DH transform.
    """

    id: str
    names: LegNames
    base: DH
    segments: tuple[Segment, ...]
    foot: Foot


@dataclass(frozen=True)
class BodyModel:
    """The simulated body of a robot: torso and legs (:func:`body_model`).

    Attributes:
        name: the robot's name.
        torso: the body box.
        legs: the legs in id order.
    """

    name: str
    torso: Torso
    legs: tuple[LegModel, ...]


def _segment(leg: Leg, index: int, joint: Joint, joint_name: str, link_name: str) -> Segment:
    end = joint_offset(joint)
    length = math.dist((0.0, 0.0, 0.0), end)
    middle = (end[0] / 2.0, end[1] / 2.0, end[2] / 2.0)
    degenerate = length < DEGENERATE_LENGTH
    return Segment(
        joint=joint_name, link=link_name, dh=joint, mass=link_mass(joint), end=end, length=length, middle=middle,
        shape="box" if degenerate else "capsule", radius=0.0 if degenerate else link_radius(leg, index),
        pitch=math.atan2(math.hypot(end[0], end[1]), end[2]), yaw=math.atan2(end[1], end[0]))


def body_model(robot: Robot) -> BodyModel:
    """The simulated body of ``robot`` (deterministic: the same robot gives the same model)."""
    body = robot.body
    moments = body.inertia if body.inertia is not None else box_inertia(body.mass, body.size)
    torso = Torso(body.mass, body.com, body.size, moments)
    legs = []
    for (leg_id, leg), names in zip(robot.legs.items(), leg_names(robot).values(), strict=True):
        segments = tuple(_segment(leg, index, joint, joint_name, link_name)
                         for index, (joint, joint_name, link_name)
                         in enumerate(zip(leg.joints.values(), names.joints, names.links, strict=True)))
        legs.append(LegModel(leg_id, names, leg.base, segments, Foot(names.foot, foot_radius(leg))))
    return BodyModel(robot.name, torso, tuple(legs))
