"""The physics-engine interface: PyBullet and MuJoCo build the same robot on the same terrain.

Both engines' generated models are checked against the DH chains the controller uses (foot frames at random
joint angles), MuJoCo's terrain against the analytic ground height, the MJCF's masses against the URDF's, and
both engines against each other while standing.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shc_cli.backends.engine import EngineOptions, rpy_from_matrix
from shc_cli.backends.engine_registry import ENGINES, EngineName, open_engine
from shc_cli.backends.mujoco_.world import MujocoWorld
from shc_cli.backends.terrain import FEATURE_END_X, HALF_WIDTH, LANDING_END_X, Terrain, parse_terrain
from shc_cli.errors import BackendError
from shc_cli.model import body as model
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot, resolve

ROBOTS = ["bullet", "bullet_mammalian", "athena", "quadruped", "octopod", "openshc_default"]


def robot_named(name: str):  # type: ignore[no-untyped-def]
    return load_robot(resolve("robots", name)).robot


def random_joints(chains: Chains, rng: np.random.Generator) -> np.ndarray:
    q = rng.uniform(chains.lower, chains.upper)
    for leg, count in enumerate(chains.joint_count):
        q[leg, count:] = 0.0
    return np.asarray(q)


def foot_frames(world, robot) -> np.ndarray:  # type: ignore[no-untyped-def]
    """Each foot frame in the world ``(L, 4, 4)``, from the engine's own forward kinematics."""
    out = np.tile(np.eye(4), (len(robot.legs), 1, 1))
    if world.name == "pybullet":
        p = world.p
        for leg, link in enumerate(world.foot_links):
            state = p.getLinkState(world.body, link, computeForwardKinematics=True, physicsClientId=world.client)
            out[leg, :3, 3] = state[4]
            out[leg, :3, :3] = np.reshape(p.getMatrixFromQuaternion(state[5]), (3, 3))
    else:
        for leg, name in enumerate(model.foot_names(robot)):
            body = world.model.body(name).id
            out[leg, :3, 3] = world.data.xpos[body]
            out[leg, :3, :3] = world.data.xmat[body].reshape(3, 3)
    return out


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("name", ROBOTS)
def test_feet_follow_the_dh_chains_in_both_engines(engine: EngineName, name: str) -> None:
    """At random joint angles within the limits each engine's foot frame is the DH tip (1e-6 m, 1e-6 rad)."""
    robot = robot_named(name)
    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(11)
    for _ in range(5):
        q = random_joints(chains, rng)
        world = open_engine(robot, EngineOptions(parse_terrain("flat"), 4, True, engine=engine), q)
        try:
            base = world.read().position
            frames = foot_frames(world, robot)
        finally:
            world.close()
        tips = chains.tip_transforms(q)
        assert np.allclose(frames[:, :3, 3] - base, tips[:, :3, 3], rtol=0.0, atol=1e-6), (engine, name)
        assert np.allclose(frames[:, :3, :3], tips[:, :3, :3], rtol=0.0, atol=1e-6), (engine, name)


@pytest.mark.parametrize("name", ROBOTS)
def test_mjcf_masses_are_the_urdf_masses(name: str) -> None:
    robot = robot_named(name)
    chains = Chains.from_robot(robot)
    world = open_engine(robot, EngineOptions(parse_terrain("flat"), 4, engine="mujoco"), chains.default_joints())
    assert isinstance(world, MujocoWorld)
    assert float(world.model.body_mass.sum()) == pytest.approx(model.body_mass(robot), abs=1e-9)


def test_mjcf_is_deterministic() -> None:
    from shc_cli.backends.mujoco_.mjcf import Options, robot_mjcf

    robot = robot_named("bullet")
    terrain = Terrain(parse_terrain("blocks"), seed=3)
    options = Options(0.0025, 0.3)
    assert robot_mjcf(robot, terrain, options) == robot_mjcf(robot, Terrain(parse_terrain("blocks"), seed=3), options)


@pytest.mark.parametrize("text", ["flat", "ramp:10", "ramp:30", "blocks", "stairs:0.05,0.3", "heightfield",
                                  "stairs-down:0.15,0.3", "slope:0.5", "steps:1", "obstacles:1", "stones:1",
                                  "gaps:0.7"])
def test_mujoco_rays_hit_height_at(text: str, field_csv: Path) -> None:
    """MuJoCo's terrain geoms are where :meth:`Terrain.height_at` says (1 mm), away from vertical faces; its height
    field follows MuJoCo's triangulation (the other diagonal than PyBullet's)."""
    from shc_cli.backends.mujoco_.world import RAY_GROUPS, import_mujoco

    mujoco = import_mujoco()

    spec = parse_terrain(f"heightfield:{field_csv}" if text == "heightfield" else text)
    robot = robot_named("bullet")
    chains = Chains.from_robot(robot)
    world = open_engine(robot, EngineOptions(spec, 4, True, seed=5, engine="mujoco"), chains.default_joints())
    assert isinstance(world, MujocoWorld)
    terrain = world.terrain
    rng = np.random.default_rng(1)
    if spec.kind == "heightfield":
        assert terrain.field is not None
        nx, ny = terrain.field.shape
        xs = rng.uniform(0.5, 0.5 + (nx - 1) * spec.cell, 400)
        ys = rng.uniform(-(ny - 1) * spec.cell / 2.0, (ny - 1) * spec.cell / 2.0, 400)
        points = list(zip(xs, ys, strict=True))
    else:
        points = list(zip(rng.uniform(-2.5, LANDING_END_X + 1.0, 400), rng.uniform(-HALF_WIDTH - 0.5,
                                                                                      HALF_WIDTH + 0.5, 400),
                          strict=True))
    hit = np.zeros(1, dtype=np.int32)
    checked = 0
    for x, y in points:
        near_face = any(abs(terrain.height_at(x + dx, y + dy) - terrain.height_at(x, y)) > 0.0
                        for dx in (-0.002, 0.002) for dy in (-0.002, 0.002))
        boxed = terrain.spec.kind in ("blocks", "stairs", "stairs-down", "stones", "gaps")
        if boxed and near_face:  # stay 2 mm away from vertical faces
            continue
        distance = mujoco.mj_ray(world.model, world.data, np.array([x, y, 20.0]), np.array([0.0, 0.0, -1.0]),
                                 RAY_GROUPS, 1, -1, hit)
        assert distance > 0.0
        assert 20.0 - distance == pytest.approx(terrain.height_at(x, y), abs=1e-3), (text, x, y)
        checked += 1
    assert checked > 50
    assert FEATURE_END_X > 0


def test_unknown_engine_is_one_line() -> None:
    robot = robot_named("bullet")
    with pytest.raises(BackendError, match="unknown physics engine 'ode'"):
        open_engine(robot, EngineOptions(parse_terrain("flat"), 4, True, engine="ode"),  # type: ignore[arg-type]
                    Chains.from_robot(robot).default_joints())


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.slow  # long simulations
def test_standing_readings_agree_between_engines(engine: EngineName) -> None:
    """Standing still in the default stance: the feet carry the weight, the IMU reads +g up, the body is level at
    the standing height — the same in both engines (OpenSHC's Bullet: stiff position motors, no servo sag)."""
    from shc_cli.control.startup import plan_direct_startup

    robot = robot_named("bullet_openshc")
    chains = Chains.from_robot(robot)
    stance = plan_direct_startup(robot, chains, chains.default_joints())
    world = open_engine(robot, EngineOptions(parse_terrain("flat"), 4, engine=engine), stance)
    try:
        for _ in range(150):
            world.command(stance)
            world.step()
        reading = world.read()
    finally:
        world.close()
    weight = model.body_mass(robot) * 9.81
    assert float(reading.foot_forces.sum()) == pytest.approx(weight, rel=0.03)
    assert reading.foot_contact.all()
    assert reading.linear_acceleration == pytest.approx([0.0, 0.0, 9.81], abs=0.2)
    assert np.abs(reading.rpy[:2]).max() < 0.02
    height = -float(chains.tips(stance)[:, 2].mean()) + model.foot_radius(robot.legs["AR"])
    assert reading.body_height == pytest.approx(height, abs=0.006)
    assert reading.position[2] == pytest.approx(reading.body_height, abs=1e-9)


def test_rpy_from_matrix_is_pybullets_euler() -> None:
    import pybullet

    rng = np.random.default_rng(2)
    for _ in range(50):
        rpy = rng.uniform(-1.4, 1.4, 3)
        matrix = np.reshape(pybullet.getMatrixFromQuaternion(pybullet.getQuaternionFromEuler(rpy)), (3, 3))
        assert rpy_from_matrix(matrix) == pytest.approx(rpy, abs=1e-9)


def test_mujoco_dynamixel_servo_is_the_servo_models_torque() -> None:
    """MuJoCo drives a ``dynamixel`` servo with :meth:`ServoModel.torque` every physics step, as PyBullet does: a
    back-driven joint resists with more than the stall torque (up to the current limit), which a position actuator
    clipped at ± the stall torque could not (bullet_mammalian_b fell on ramp:10 in MuJoCo for that,
    docs/physics-model.md)."""
    from shc_cli.backends.servo import ServoModel

    robot = robot_named("bullet_mammalian_b")
    servo = robot.servo
    assert servo.control == "dynamixel"
    chains = Chains.from_robot(robot)
    joints = chains.default_joints()
    world = open_engine(robot, EngineOptions(parse_terrain("flat"), 1, True, engine="mujoco"), joints)
    assert isinstance(world, MujocoWorld)
    try:
        assert world.xml.count('<motor ') == len(world.qvel_index)
        goals = joints + 0.5  # every servo pushes towards +0.5 rad while the joints move the other way at 3 rad/s
        world.command(goals)
        world.data.qvel[world.qvel_index] = -3.0
        q = world.data.qpos[world.qpos_index].copy()
        v = world.data.qvel[world.qvel_index].copy()
        flat = goals[world.slot_rows, world.slot_cols]
        world.step()
        applied = world.data.actuator_force.copy()
    finally:
        world.close()
    expected = ServoModel(servo).torque(flat, q, v)
    assert applied == pytest.approx(expected, rel=1e-9, abs=1e-9)
    current_limited = servo.torque_constant * servo.current_limit
    assert applied.min() == pytest.approx(current_limited, rel=1e-6)  # back-driven: the current limit
    assert current_limited > 1.3 * servo.stall_torque


@pytest.mark.slow  # long simulations
def test_an_unstable_mujoco_run_reports_it_and_writes_no_log_file(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """ATHENA's explicit servo law at a 50 ms physics step blows up in MuJoCo: the run stops with the physics-diverged
    exit code 6, the summary and the terminal name it, and MuJoCo's own MUJOCO_LOG.TXT is not left in the working
    directory."""
    from .test_cli import run

    monkeypatch.chdir(tmp_path)
    code, _, err = run(["simulate", "athena_paper", "--engine", "mujoco", "--terrain", "ramp:10", "--duration", "3",
                          "--physics-rate", "20", "--no-plots", "--out", str(tmp_path / "run")], capsys, monkeypatch)
    assert code == 6, err
    import json

    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["stop_reason"] == "diverged"
    assert "the physics diverged at cycle" in err and "--physics-rate" in err
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
