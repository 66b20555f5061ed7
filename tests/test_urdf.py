"""The generated URDF: PyBullet's forward kinematics equals shc's DH chains, masses and names as documented."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from shc_cli.backends.pybullet_ import urdf
from shc_cli.backends.pybullet_.world import quiet_stdout
from shc_cli.model import body as model
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import bundled, load_robot
from shc_cli.spec.robot import Robot

with quiet_stdout():  # importing pybullet prints its build time
    import pybullet as p

ROBOTS = bundled("robots")


def robot_named(name: str) -> Robot:
    robot = load_robot(name).robot
    return robot


@contextmanager
def loaded(robot: Robot, folder: Path, fixed: bool = True) -> Iterator[tuple[int, int]]:
    """``(client, body)``: the robot's URDF in a DIRECT client, base_link frame at the origin, unrotated."""
    path = urdf.write_urdf(robot, folder / f"{robot.name}.urdf")
    with quiet_stdout():
        client = p.connect(p.DIRECT)
        body = p.loadURDF(str(path), [0.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0], useFixedBase=fixed,
                          flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
    try:
        yield client, body
    finally:
        p.disconnect(physicsClientId=client)


def indices(client: int, body: int) -> tuple[dict[str, int], dict[str, int]]:
    """Joint index by joint name and by child link name (a PyBullet link's index is its joint's)."""
    count = p.getNumJoints(body, physicsClientId=client)
    infos = [p.getJointInfo(body, j, physicsClientId=client) for j in range(count)]
    return {i[1].decode(): i[0] for i in infos}, {i[12].decode(): i[0] for i in infos}


def random_joints(chains: Chains, rng: np.random.Generator) -> np.ndarray:
    q = rng.uniform(chains.lower, chains.upper)
    for leg, count in enumerate(chains.joint_count):
        q[leg, count:] = 0.0
    return np.asarray(q)


@pytest.mark.parametrize("name", ROBOTS)
def test_feet_follow_the_dh_chains(name: str, tmp_path: Path) -> None:
    """At random joint angles each foot link's frame is the DH tip: position to 1e-6 m, orientation too."""
    robot = robot_named(name)
    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(7)
    with loaded(robot, tmp_path) as (client, body):
        joints, links = indices(client, body)
        feet = [links[f] for f in model.foot_names(robot)]
        position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=client)
        inertial = p.getDynamicsInfo(body, -1, physicsClientId=client)[3]
        assert np.allclose(np.subtract(position, inertial), 0.0, atol=1e-12)  # base_link frame at the origin
        assert np.allclose(orientation, (0.0, 0.0, 0.0, 1.0))
        for _ in range(20):
            q = random_joints(chains, rng)
            for leg, names in enumerate(model.leg_names(robot).values()):
                for k, joint in enumerate(names.joints):
                    p.resetJointState(body, joints[joint], float(q[leg, k]), physicsClientId=client)
            tips = chains.tip_transforms(q)
            for leg, link in enumerate(feet):
                state = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=client)
                frame_position, frame_orientation = state[4], state[5]  # the URDF link frame, not the COM
                assert np.allclose(frame_position, tips[leg, :3, 3], rtol=0.0, atol=1e-6), (name, leg, q[leg])
                rotation = np.reshape(p.getMatrixFromQuaternion(frame_orientation), (3, 3))
                assert np.allclose(rotation, tips[leg, :3, :3], rtol=0.0, atol=1e-6)
            assert np.allclose(chains.tips(q), tips[:, :3, 3], atol=1e-12)


@pytest.mark.parametrize("name", ROBOTS)
def test_masses(name: str, tmp_path: Path) -> None:
    """Bullet's masses sum to the robot file's total plus one FOOT_MASS per leg; every link has its own."""
    robot = robot_named(name)
    with loaded(robot, tmp_path, fixed=False) as (client, body):  # a fixed base reports mass 0
        count = p.getNumJoints(body, physicsClientId=client)
        masses = {(p.getJointInfo(body, j, physicsClientId=client)[12].decode() if j >= 0 else "base_link"):
                  p.getDynamicsInfo(body, j, physicsClientId=client)[0] for j in range(-1, count)}
    assert sum(masses.values()) == pytest.approx(model.body_mass(robot), abs=1e-9)
    assert masses["base_link"] == pytest.approx(robot.body.mass)
    if all(j.mass is not None for leg in robot.legs.values() for j in leg.joints.values()):
        expected = robot.total_mass() + model.FOOT_MASS * len(robot.legs)
        assert sum(masses.values()) == pytest.approx(expected, abs=1e-9)
    for leg_id, leg in robot.legs.items():
        names = model.leg_names(robot)[leg_id]
        assert masses[names.base] == 0.0
        assert masses[names.foot] == model.FOOT_MASS
        for joint, link in zip(leg.joints.values(), names.links, strict=True):  # a rotor link takes its mass
            rotor = masses.get(link.removesuffix("_link") + "_rotor", 0.0)
            assert rotor == (urdf.ROTOR_MASS if robot.servo.armature > 0.0 else 0.0)
            assert masses[link] + rotor == pytest.approx(model.link_mass(joint))


def test_bullet_mass_is_the_openshc_urdf_mass() -> None:
    """Bullet: 7.2 kg body (6 kg box + 6 base motors) + 6 x 1.028 kg legs = 13.37 kg (study §13.2)."""
    robot = robot_named("bullet_openshc")
    assert robot.total_mass() == pytest.approx(13.36821)
    assert model.body_mass(robot) == pytest.approx(13.36821 + 6 * model.FOOT_MASS)


def test_body_mass_counts_default_links_and_feet() -> None:
    """openshc_default gives no link masses: the engines simulate 1 kg body + 18 links x 0.1 kg + 6 feet x 0.001 kg
    = 2.806 kg, while ``total_mass()`` (the file's masses) is 1 kg."""
    robot = robot_named("openshc_default")
    assert robot.total_mass() == pytest.approx(1.0)
    assert model.body_mass(robot) == pytest.approx(1.0 + 18 * 0.1 + 6 * 0.001, abs=1e-12)


def test_inertias_in_bullet(tmp_path: Path) -> None:
    """PyBullet reads the inertias of the file: the body box, a capsule about its midpoint, the foot sphere."""
    robot = robot_named("bullet_openshc")
    leg = robot.legs["AR"]
    names = model.leg_names(robot)["AR"]
    with loaded(robot, tmp_path, fixed=False) as (client, body):
        _, links = indices(client, body)
        base = p.getDynamicsInfo(body, -1, physicsClientId=client)
        femur = p.getDynamicsInfo(body, links[names.links[2]], physicsClientId=client)
        foot = p.getDynamicsInfo(body, links[names.foot], physicsClientId=client)
    assert np.allclose(base[2], model.box_inertia(7.2, (0.6, 0.14, 0.101)), rtol=1e-9)
    assert np.allclose(base[3], robot.body.com)
    radius = model.link_radius(leg, 2)
    assert np.allclose(femur[2], model.capsule_inertia(0.4, radius, 0.114 - 2 * radius), rtol=1e-9)
    assert np.allclose(femur[3], (0.057, 0.0, 0.0))  # the segment's midpoint
    assert np.allclose(foot[2], [model.sphere_inertia(model.FOOT_MASS, 0.0125)] * 3, rtol=1e-9)


def test_capsule_inertia_formula() -> None:
    """The closed form equals the inertia of a densely sampled solid capsule (and the cylinder/sphere limits)."""
    radius, length, mass = 0.02, 0.07, 0.3
    step = 0.0005
    axis = np.arange(-length / 2 - radius + step / 2, length / 2 + radius, step)
    across = np.arange(-radius + step / 2, radius, step)
    x, y, z = np.meshgrid(across, across, axis, indexing="ij")
    beyond = np.clip(np.abs(z) - length / 2, 0.0, None)
    inside = x**2 + y**2 + beyond**2 <= radius**2
    x, y, z = x[inside], y[inside], z[inside]
    point = mass / x.size
    sampled = (point * np.sum(y**2 + z**2), point * np.sum(x**2 + z**2), point * np.sum(x**2 + y**2))
    assert np.allclose(model.capsule_inertia(mass, radius, length), sampled, rtol=2e-3)
    assert np.allclose(model.capsule_inertia(mass, radius, 0.0), [model.sphere_inertia(mass, radius)] * 3)
    long = model.capsule_inertia(mass, 1e-6, 1.0)
    assert long[0] == pytest.approx(mass / 12.0, rel=1e-5)


@pytest.mark.parametrize("name", ROBOTS)
def test_names_and_xml(name: str, tmp_path: Path) -> None:
    """Revolute joints are LEG_J_joint in leg/joint order; the text is XML; every link has an inertial."""
    robot = robot_named(name)
    text = urdf.robot_urdf(robot)
    assert text == urdf.robot_urdf(robot_named(name))  # deterministic
    root = ET.fromstring(text)
    assert root.tag == "robot"
    revolute = [j.get("name") for j in root.iter("joint") if j.get("type") == "revolute"]
    expected = [f"{leg_id}_{joint}_joint" for leg_id, leg in robot.legs.items() for joint in leg.joints]
    assert revolute == expected == model.joint_names(robot)
    assert [link.get("name") for link in root.iter("link")] == urdf.link_names(robot)
    assert all(link.find("inertial") is not None for link in root.iter("link"))
    with loaded(robot, tmp_path) as (client, body):
        joints, links = indices(client, body)
        order = sorted((i, n) for n, i in joints.items()
                       if p.getJointInfo(body, i, physicsClientId=client)[2] == p.JOINT_REVOLUTE)
        assert [n for _, n in order] == expected
        info = {n: p.getJointInfo(body, i, physicsClientId=client) for n, i in joints.items()}
        servo = robot.servo
        for leg_id, leg in robot.legs.items():
            for joint_id, joint in leg.joints.items():
                lower, upper, effort, velocity = info[f"{leg_id}_{joint_id}_joint"][8:12]
                assert (lower, upper) == (joint.min, joint.max)
                assert (effort, velocity) == (servo.stall_torque, servo.no_load_speed)
        assert set(model.foot_names(robot)) <= set(links)


def test_foot_sphere_is_centred_on_the_tip() -> None:
    """The foot sphere's centre is the tip (contact = tip − radius on flat ground); default radius if 0."""
    for name in ROBOTS:
        robot = robot_named(name)
        root = ET.fromstring(urdf.robot_urdf(robot))
        links = {link.get("name"): link for link in root.iter("link")}
        for leg_id, leg in robot.legs.items():
            foot = links[f"{leg_id}_foot"]
            sphere = foot.find("collision/geometry/sphere")
            origin = foot.find("collision/origin")
            assert sphere is not None and origin is not None
            radius = leg.foot_radius or model.DEFAULT_FOOT_RADIUS
            assert float(sphere.get("radius", "nan")) == radius
            assert origin.get("xyz") == "0 0 0"
            # the last link's capsule is no wider than the foot, so the foot is lowest near the tip
            assert model.link_radius(leg, len(leg.joints) - 1) <= radius


def test_degenerate_link_is_a_cube(bullet: Robot, tmp_path: Path) -> None:
    """A joint with no DH offset (two coincident joint origins) gets a small cube; FK still matches."""
    leg = bullet.legs["AR"]
    joints = dict(leg.joints)
    joints["coxat"] = joints["coxat"].model_copy(update={"d": 0.0, "r": 0.0})
    robot = bullet.model_copy(update={"legs": {"AR": leg.model_copy(update={"joints": joints})}})
    root = ET.fromstring(urdf.robot_urdf(robot))
    link = next(link for link in root.iter("link") if link.get("name") == "AR_coxat_link")
    assert link.find("collision/geometry/box") is not None
    chains = Chains.from_robot(robot)
    q = random_joints(chains, np.random.default_rng(1))
    with loaded(robot, tmp_path) as (client, body):
        joints_by_name, links = indices(client, body)
        for k, name in enumerate(model.joint_names(robot)):
            p.resetJointState(body, joints_by_name[name], float(q[0, k]), physicsClientId=client)
        state = p.getLinkState(body, links["AR_foot"], computeForwardKinematics=True, physicsClientId=client)
    assert np.allclose(state[4], chains.tips(q)[0], atol=1e-6)


def test_holds_a_pose_under_gravity(bullet: Robot, tmp_path: Path) -> None:
    """Fixed base, servos at the unpacked pose: after 1 s of physics the joints are there and nothing is NaN."""
    target = np.array([[j.unpacked for j in leg.joints.values()] for leg in bullet.legs.values()])
    with loaded(bullet, tmp_path) as (client, body):
        p.setGravity(0.0, 0.0, -9.81, physicsClientId=client)
        p.setTimeStep(1.0 / 240.0, physicsClientId=client)
        joints, _ = indices(client, body)
        order = [joints[n] for n in model.joint_names(bullet)]
        for index, value in zip(order, target.ravel(), strict=True):
            p.resetJointState(body, index, float(value), physicsClientId=client)
            p.setJointMotorControl2(body, index, p.POSITION_CONTROL, targetPosition=float(value),
                                    force=bullet.servo.stall_torque, physicsClientId=client)
        for _ in range(240):
            p.stepSimulation(physicsClientId=client)
        reached = np.array([s[0] for s in p.getJointStates(body, order, physicsClientId=client)])
    assert np.all(np.isfinite(reached))
    assert np.allclose(reached, target.ravel(), atol=0.02)
