"""MJCF text for MuJoCo, built in code from the robot file and the terrain: the same model PyBullet loads.

The robot is the simulated body of :mod:`shc_cli.model.body` (docs/physics-model.md) — DH transforms, capsule
radii, masses, inertias, foot spheres — written as MJCF, as the URDF writer writes it for PyBullet, so both engines
simulate the same bodies (``tests/test_engines.py`` checks both engines' foot frames against the DH tips):

* ``base_link``: the body box, mass and inertia at ``body.com``; a free joint ``root`` unless held in the air.
* per leg and joint ``LEG_J_link`` with the hinge ``LEG_J_joint`` (axis z of its frame, range ``min``/``max``);
  the first sits at the DH transform ``A(base)`` in ``base_link``, each next one at the previous joint's fixed
  DH transform ``M = Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)``. URDF's zero-mass leg frame link ``LEG_base``
  is folded into the first joint's placement.
* ``LEG_foot``: a body without joint at the tip, the foot sphere centred on it and a touch sensor ``LEG_touch``
  whose site encloses the sphere (the foot's contact normal forces).
* one actuator per joint (``LEG_J_servo``), the servo of :mod:`shc_cli.backends.mujoco_.world`.

Terrain: the infinite ground plane, every box of :meth:`Terrain.boxes` as a static geom, a height field as an
``hfield``. Robot geoms are in group 1 and collide only with terrain geoms (group 0): no self-collision, as in
PyBullet. Friction is mapped to PyBullet's combined contact (docs/physics-model.md): PyBullet multiplies the two
bodies' coefficients, MuJoCo takes the larger, so every geom gets ``friction²``; the cone is elliptic (isotropic, as
Bullet's) and the friction impedance 10 × the normal one, so loaded feet hold as Bullet's rigid friction does
(:data:`FRICTION_CONE`, :data:`FRICTION_IMPEDANCE_RATIO`). Restitution is not mapped: MuJoCo's
only stand-in, an under-damped contact spring, bounces every contact at every speed, while PyBullet gives no
restitution below its 0.2 m/s threshold — where a walking foot lands. The under-damped spring made ATHENA slip back
down the 10° ramp (0.009 against PyBullet's 0.039 m/s); PyBullet walks it the same with restitution 0.5 and 0
(1.182 and 1.181 m in 30 s), so critically damped contacts are the faithful mapping.

MJCF built in code rather than compiled from the generated URDF: MuJoCo's URDF reader has no capsules
(PyBullet's ``<capsule>`` extension), no actuators, sensors, contact filters or solver options, so those would
have to be patched into the compiled model anyway; MJCF text states all of it in one place, is deterministic
(same robot, same bytes) and readable (``shc_cli.backends.mujoco_.mjcf.robot_mjcf``).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from typing import Any

import numpy as np

from shc_cli.backends.terrain import FEATURE_RGBA, FEATURE_START_X, GROUND_RGBA, Terrain
from shc_cli.model.body import COLOURS, CUBE_SIDE, GRAVITY, BodyModel, Segment, body_model, joint_names, joint_offset
from shc_cli.spec.robot import DH, Robot

TOUCH_SHARE = 1.5
"""Radius of a foot's touch-sensor site as a share of the foot radius: contact points lie inside the sphere (half
the penetration below its surface), the site catches them and nothing of the next link, whose contacts do not
count anyway (a touch sensor sees only its own body's contacts)."""
CONTACT_TIME_CONSTANT = 0.005
"""MuJoCo contact ``solref`` time constant [s]: stiff contacts, ≥ 2 physics steps at 400 Hz."""
FRICTION_CONE = "elliptic"
"""MuJoCo's friction cone. Bullet bounds the friction along the contact's sliding direction by ``μ·N`` (its first
friction direction follows the relative velocity), the same in every direction; MuJoCo's pyramidal cone bounds
``|f_x| + |f_y| ≤ μ·N`` in the contact frame's axes (0.71 μ on a diagonal), the elliptic cone ``|f_t| ≤ μ·N``
in every direction, as Bullet."""
FRICTION_IMPEDANCE_RATIO = 10.0
"""MuJoCo ``impratio``: the friction constraints' impedance over the normal one's. At 1 a soft contact's friction is
as soft as its normal force, so a loaded foot creeps under any tangential load (downhill on a ramp, the stance's
internal forces when standing), where Bullet's rigid friction constraint holds it; 10 stops that creep (measured in
docs/physics-model.md, "The cross-engine matrix")."""
STAND_TIME_CONSTANT = 0.005
"""Time constant of the stand's weld [s]."""
ROBOT_GROUP = 1
"""Geom group of the robot (the height ray sees only group 0, the terrain)."""


@dataclass(frozen=True)
class Options:
    """How the world is built.

    Attributes:
        timestep: physics step [s].
        base_height: height of ``base_link`` at spawn [m].
        fixed_base: no free joint: the body is held in the air.
        stand: a weld ``stand`` holds the body where it spawns until deactivated.
        friction: PyBullet-style friction of feet and terrain (contact coefficient ``friction²``).
        restitution: PyBullet-style restitution of feet and terrain: not applied (MuJoCo has no restitution
            coefficient, and PyBullet applies none below :data:`RESTITUTION_THRESHOLD_MPS`, where walking feet land;
            every contact stays critically damped, docs/physics-model.md).
    """

    timestep: float
    base_height: float
    fixed_base: bool = False
    stand: bool = False
    friction: float = 0.9
    restitution: float = 0.0


def _num(value: float) -> str:
    value = float(value)
    return "0" if abs(value) < 1e-15 else repr(value)


def _vec(values: tuple[float, ...] | list[float] | np.ndarray) -> str:
    return " ".join(_num(v) for v in values)


def _qmul(a: tuple[float, float, float, float], b: tuple[float, float, float, float]) -> tuple[float, ...]:
    """Hamilton product of quaternions (w, x, y, z)."""
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def _axis_quat(axis: int, angle: float) -> tuple[float, float, float, float]:
    q = [math.cos(angle / 2.0), 0.0, 0.0, 0.0]
    q[1 + axis] = math.sin(angle / 2.0)
    return (q[0], q[1], q[2], q[3])


def dh_quat(dh: DH) -> tuple[float, ...]:
    """Rotation of ``Rot_z(θ)·Rot_x(α)`` as a quaternion (w, x, y, z)."""
    return _qmul(_axis_quat(2, dh.theta), _axis_quat(0, dh.alpha))


RESTITUTION_THRESHOLD_MPS = 0.2
"""Bullet's restitution velocity threshold [m/s] (``btContactSolverInfo::m_restitutionVelocityThreshold``, which
PyBullet leaves at its default): a contact approaching slower than this gets no restitution at all."""


def robot_mjcf(robot: Robot, terrain: Terrain, options: Options) -> str:
    """The MJCF text of ``robot`` on ``terrain`` (deterministic: the same inputs give the same bytes)."""
    root = ET.Element("mujoco", model=robot.name)
    ET.SubElement(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="false")
    ET.SubElement(root, "option", timestep=_num(options.timestep), gravity=_vec((0.0, 0.0, -GRAVITY)),
                  integrator="implicitfast", cone=FRICTION_CONE, impratio=_num(FRICTION_IMPEDANCE_RATIO))
    mu = options.friction * options.friction
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", friction=f"{_num(mu)} 0.005 0.0001",
                  solref=f"{_num(CONTACT_TIME_CONSTANT)} 1", condim="3")
    ET.SubElement(ET.SubElement(root, "visual"), "global", offwidth="1280", offheight="720")
    asset = ET.SubElement(root, "asset")
    world = ET.SubElement(root, "worldbody")
    _terrain(asset, world, terrain)
    model = body_model(robot)
    _robot(world, model, armature(robot), options)
    if options.stand and not options.fixed_base:
        equality = ET.SubElement(root, "equality")
        ET.SubElement(equality, "weld", name="stand", body1="base_link", solref=f"{_num(STAND_TIME_CONSTANT)} 1")
    _actuators(root, robot)
    sensors = ET.SubElement(root, "sensor")
    for leg in model.legs:
        ET.SubElement(sensors, "touch", name=leg.foot.name.replace("_foot", "_touch"), site=f"{leg.foot.name}_site")
    if len(asset) == 0:
        root.remove(asset)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode") + "\n"


def _terrain(asset: ET.Element, world: ET.Element, terrain: Terrain) -> None:
    """Terrain geoms: group 0, colliding with the robot only (contype 1, conaffinity 2)."""
    common: dict[str, Any] = {"contype": "1", "conaffinity": "2", "group": "0"}
    ET.SubElement(world, "geom", name="ground", type="plane", size="0 0 1", rgba=_vec(GROUND_RGBA), **common)
    for index, box in enumerate(terrain.boxes()):
        quat = _axis_quat(1, box.pitch)
        ET.SubElement(world, "geom", name=f"terrain_{index}", type="box", pos=_vec(box.center),
                      quat=_vec(quat), size=_vec(tuple(s / 2.0 for s in box.size)), rgba=_vec(FEATURE_RGBA), **common)
    if terrain.field is not None:
        field, cell = terrain.field, terrain.spec.cell
        nx, ny = field.shape
        top = max(float(field.max()), 1e-6)
        # MuJoCo's elevation: nrow × ncol, the first row at +y (as an image's top line), columns along +x; / top.
        rows = field.T[::-1] / top
        ET.SubElement(asset, "hfield", name="field", nrow=str(ny), ncol=str(nx),
                      size=_vec(((nx - 1) * cell / 2.0, (ny - 1) * cell / 2.0, top, 0.01)),
                      elevation=" ".join(_num(v) for v in rows.ravel()))
        ET.SubElement(world, "geom", name="field", type="hfield", hfield="field",
                      pos=_vec((FEATURE_START_X + (nx - 1) * cell / 2.0, 0.0, 0.0)), rgba=_vec(FEATURE_RGBA),
                      **common)


def _rgba(part: str) -> str:
    """The colour of ``part`` (:data:`~shc_cli.model.body.COLOURS`) as MJCF text."""
    return " ".join(f"{c:g}" for c in COLOURS[part])


def _robot(world: ET.Element, model: BodyModel, armature: float, options: Options) -> None:
    common: dict[str, Any] = {"contype": "2", "conaffinity": "1", "group": str(ROBOT_GROUP)}
    torso = model.torso
    base = ET.SubElement(world, "body", name="base_link", pos=_vec((0.0, 0.0, options.base_height)))
    if not options.fixed_base:
        ET.SubElement(base, "freejoint", name="root")
    ET.SubElement(base, "inertial", pos=_vec(torso.com), mass=_num(torso.mass), diaginertia=_vec(torso.moments))
    ET.SubElement(base, "geom", name="body", type="box", pos=_vec(torso.com),
                  size=_vec(tuple(s / 2.0 for s in torso.size)), rgba=_rgba("body"), **common)
    ET.SubElement(base, "site", name="imu", pos="0 0 0", size="0.01")
    for leg in model.legs:
        parent = base
        pos, quat = joint_offset(leg.base), dh_quat(leg.base)
        for segment in leg.segments:
            body = ET.SubElement(parent, "body", name=segment.link, pos=_vec(pos), quat=_vec(quat))
            ET.SubElement(body, "joint", name=segment.joint, type="hinge", axis="0 0 1",
                          range=f"{_num(segment.dh.min)} {_num(segment.dh.max)}", armature=_num(armature))
            _segment(body, segment, common)
            parent, pos, quat = body, segment.end, dh_quat(segment.dh)
        foot = ET.SubElement(parent, "body", name=leg.foot.name, pos=_vec(pos), quat=_vec(quat))
        ET.SubElement(foot, "inertial", pos="0 0 0", mass=_num(leg.foot.mass), diaginertia=_vec((leg.foot.moment,) * 3))
        ET.SubElement(foot, "geom", name=f"{leg.id}_foot_geom", type="sphere", size=_num(leg.foot.radius),
                      rgba=_rgba("foot"), **common)
        ET.SubElement(foot, "site", name=f"{leg.foot.name}_site", type="sphere",
                      size=_num(TOUCH_SHARE * leg.foot.radius))


def _segment(body: ET.Element, segment: Segment, common: dict[str, Any]) -> None:
    """Mass, inertia and shape of the link a joint moves."""
    middle = segment.middle
    if segment.shape == "box":
        ET.SubElement(body, "inertial", pos=_vec(middle), mass=_num(segment.mass), diaginertia=_vec(segment.moments()))
        ET.SubElement(body, "geom", type="box", pos=_vec(middle), size=_vec((CUBE_SIDE / 2.0,) * 3), rgba=_rgba("link"),
                      **common)
        return
    quat = _qmul(_axis_quat(2, segment.yaw), _axis_quat(1, segment.pitch))
    ET.SubElement(body, "inertial", pos=_vec(middle), quat=_vec(quat), mass=_num(segment.mass),
                  diaginertia=_vec(segment.moments()))
    end = np.array(segment.end)
    unit = end / segment.length
    start, stop = unit * segment.radius, end - unit * segment.radius
    ET.SubElement(body, "geom", type="capsule", fromto=_vec((*start, *stop)), size=_num(segment.radius),
                  rgba=_rgba("link"), **common)


def _actuators(root: ET.Element, robot: Robot) -> None:
    """One actuator per joint: for ``position`` servos a velocity actuator within ± the stall torque, driven by the
    position loop every physics step; for ``pd`` servos a position actuator of the servo model's stiffness and
    damping within ± its torque limit (:meth:`~shc_cli.backends.servo.ServoModel.gains`); for ``dynamixel`` servos a
    torque motor that the world drives every physics step with :meth:`~shc_cli.backends.servo.ServoModel.torque` (as
    PyBullet does): the model's PWM and current limits are not one force range, so a position actuator clipped at
    the stall torque would be weaker than the model when back-driven (up to ``torque_constant·current_limit``) and
    stronger while moving (the torque–speed line)."""
    from shc_cli.backends.servo import ServoModel

    servo = robot.servo
    actuators = ET.SubElement(root, "actuator")
    limit = f"{_num(-servo.stall_torque)} {_num(servo.stall_torque)}"
    gains = ServoModel(servo).gains() if servo.control == "pd" else None
    for joint_name in joint_names(robot):
        name = joint_name.removesuffix("_joint") + "_servo"
        if servo.control == "dynamixel":
            ET.SubElement(actuators, "motor", name=name, joint=joint_name, gear="1")
        elif gains is not None:
            ET.SubElement(actuators, "position", name=name, joint=joint_name, kp=_num(gains.stiffness),
                          kv=_num(gains.damping),
                          forcerange=f"{_num(-gains.torque_limit)} {_num(gains.torque_limit)}")
        else:
            ET.SubElement(actuators, "velocity", name=name, joint=joint_name, kv=_num(velocity_stiffness(robot)),
                          forcerange=limit)


VELOCITY_ERROR_AT_STALL = 0.1
"""The position servo's velocity loop reaches the stall torque at this share of the no-load speed (PyBullet's
velocity-motor constraint is exact up to the stall torque; stiffer loops clamp more often, see :func:`armature`)."""
ARMATURE_PER_NM = 0.00025
"""Reflected rotor inertia per N·m of stall torque [kg·m²/(N·m)]: a geared servo's rotor inertia times the gear
ratio squared, e.g. ≈ 1e-7 kg·m² × 225² ≈ 0.002 kg·m² for an 8.4 N·m MX-106 (pending the servo/gearbox model)."""


def velocity_stiffness(robot: Robot) -> float:
    """Gain of the servo's velocity loop [N·m·s/rad]: the stall torque at :data:`VELOCITY_ERROR_AT_STALL` of the
    no-load speed."""
    servo = robot.servo
    return servo.stall_torque / (VELOCITY_ERROR_AT_STALL * servo.no_load_speed)


def armature(robot: Robot) -> float:
    """Reflected rotor inertia of every joint [kg·m²]: the servo's ``armature`` if the robot file gives one, else
    :data:`ARMATURE_PER_NM` × stall torque.

    MuJoCo integrates a clamped actuator explicitly: at 400 Hz the stall torque on a light link without it
    (the Bullet tarsus: 0.0008 kg·m² about its joint) changes the speed by ``h·τ/I`` ≈ 27 rad/s in one step and
    the joint chatters between ± the limit. PyBullet's motor, a solver constraint, needs none.
    """
    given = float(getattr(robot.servo, "armature", 0.0))
    return given if given > 0.0 else ARMATURE_PER_NM * robot.servo.stall_torque
