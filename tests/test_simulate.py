"""``shc simulate`` end to end: PyBullet and MuJoCo physics with the one controller (short runs)."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

import pytest

from shc_cli.backends.engine_registry import EngineName

from .test_cli import run

TIMING = {"wall_time_s", "physics_time_s", "running_wall_time_s", "running_physics_time_s"}
REQUIRED = {"sim_time_s", "wall_time_s", "physics_time_s", "distance_m", "mean_speed_mps", "mean_power_w", "cot",
            "fell", "seed", "terrain", "engine", "engine_version"}
ENGINES: list[EngineName] = ["pybullet", "mujoco"]


def _simulate(tmp_path: Path, name: str, args: list[str], capsys, monkeypatch) -> tuple[int, str, Path]:  # type: ignore[no-untyped-def]
    out = tmp_path / name
    code, stdout, err = run(["simulate", *args, "--out", str(out)], capsys, monkeypatch)
    assert err == "" or code != 0, err
    return code, stdout, out


@pytest.mark.parametrize("engine", ENGINES)
def test_bullet_walks_forward_on_flat_ground(engine: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, stdout, out = _simulate(tmp_path, "walk", ["--duration", "4", "--engine", engine], capsys, monkeypatch)
    assert code == 0 and "bullet / tripod / WG on flat" in stdout
    summary = json.loads((out / "summary.json").read_text())
    assert set(summary) >= REQUIRED
    assert summary["engine"] == engine and summary["versions"][engine] == summary["engine_version"]
    assert summary["fell"] is False and summary["terrain"] == "flat"  # shc view and render rebuild it from this
    assert summary["distance_m"] > 0.2  # accelerating towards bullet's 0.2 m/s for 4 s
    assert summary["forward_distance_m"] > 0.95 * summary["distance_m"]
    assert summary["mean_power_w"] > 30 * 0.9  # at least every servo's idle power
    assert summary["cot"] > 0.0
    with (out / "log.csv").open() as handle:
        header = next(csv.reader(handle))
    for column in ("cycle", "t", "AR_coxa_cmd", "AR_coxa", "AR_coxa_torque", "AR_coxa_power", "AR_force",
                   "AR_contact", "x", "roll", "vx", "wz", "imu_qw", "gyro_x", "acc_z", "height", "power_w"):
        assert column in header
    assert {p.name for p in out.glob("*.png")} == {"trajectory.png", "power.png", "contacts.png"}


@pytest.mark.parametrize("engine", ENGINES)
def test_same_seed_gives_the_same_summary(engine: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Determinism per engine: the same options give byte-identical logs."""
    args = ["--duration", "1", "--terrain", "blocks", "--seed", "7", "--imu-noise", "0.01", "--no-plots",
            "--engine", engine]
    summaries = []
    for name in ("a", "b"):
        code, _, out = _simulate(tmp_path, name, args, capsys, monkeypatch)
        assert code == 0
        summary = json.loads((out / "summary.json").read_text())
        summaries.append({k: v for k, v in summary.items() if k not in TIMING})
    assert summaries[0] == summaries[1]
    assert (tmp_path / "a" / "log.csv").read_bytes() == (tmp_path / "b" / "log.csv").read_bytes()


@pytest.mark.parametrize("engine", ENGINES)
def test_stance_in_the_air_holds_the_body_still(engine: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, out = _simulate(tmp_path, "sa", ["--scenario", "SA", "--duration", "1", "--no-plots", "--engine", engine],
                             capsys, monkeypatch)
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["distance_m"] < 1e-6 and summary["cot"] is None and summary["fell"] is False


@pytest.mark.parametrize(("args", "message"), [
    (["--terrain", "ramps:10"], "--terrain: unknown terrain 'ramps'"),
    (["--physics-rate", "333"], "--physics-rate: 333 Hz is not a whole multiple of the control rate 100 Hz"),
    (["--scenario", "XX"], "--scenario: 'XX' is not a scenario"),
    (["--engine", "ode"], "--engine: 'ode' is not a physics engine"),
    (["--velocity", "2,0,0"], "--velocity: VX 2 is outside the throttle range −1…1"),
    (["--velocity", "0,0,-1.5"], "--velocity: WZ -1.5 is outside the throttle range −1…1"),
])
def test_bad_options_are_one_line(tmp_path: Path, args: list[str], message: str, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err = run(["simulate", *args, "--out", str(tmp_path / "x")], capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1 and message in err


def test_export_urdf_writes_the_generated_model(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import xml.etree.ElementTree as ET

    target = tmp_path / "bullet.urdf"
    code, out, _ = run(["export", "urdf", "bullet", "--out", str(target)], capsys, monkeypatch)
    assert code == 0 and str(target) in out
    root = ET.fromstring(target.read_text())
    joints = [j.get("name") for j in root.iter("joint") if j.get("type") == "revolute"]
    assert len(joints) == 30 and joints[0] == "AR_coxa_joint"
    assert sum(1 for link in root.iter("link") if link.get("name", "").endswith("_foot")) == 6


@pytest.mark.parametrize("engine", [pytest.param("pybullet", marks=pytest.mark.slow), "mujoco"])  # PyBullet: 3.7 s
def test_mammalian_starts_on_the_stand_and_walks_its_bipod(engine: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """bullet_mammalian.toml sets ``start_up.simulation = "stand"``: no flag needed."""
    code, _, out = _simulate(tmp_path, "mammal", ["bullet_mammalian", "--duration", "3", "--no-plots", "--engine",
                                                  engine], capsys, monkeypatch)
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["gait"] == "bipod" and summary["fell"] is False
    assert summary["distance_m"] > 0.3


@pytest.mark.parametrize("engine", ENGINES)
def test_mammalian_cannot_lift_itself_off_the_ground(engine: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Why the mammalian starts on a stand: from the ground its front femurs saturate at the MX-106 stall torque
    and it pitches onto its nose during the direct start-up, in both engines since MuJoCo's friction is Bullet's
    elliptic cone (docs/physics-model.md, engines; it pitched 0.03–0.3 rad in MuJoCo with the pyramidal cone)."""
    code, _, out = _simulate(tmp_path, "ground", ["bullet_mammalian", "--ground", "--duration", "1", "--no-plots",
                                                  "--engine", engine], capsys, monkeypatch)
    assert code == 0
    with (out / "log.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    stall = 8.4
    assert max(abs(float(row["AR_femur_torque"])) for row in rows[:150]) > 0.99 * stall
    pitch = max(float(row["pitch"]) for row in rows if row["robot_state"] != "RUNNING")
    assert pitch > 0.3  # nose down [rad]


@pytest.mark.parametrize("substeps", [8, 9])
def test_readings_are_those_after_the_last_physics_step(substeps: int) -> None:
    """The world keeps the joint states of the control period's last physics step for the next reading instead of
    asking PyBullet again: they must equal a fresh read."""
    import numpy as np

    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.pybullet_.world import World
    from shc_cli.backends.simulated import open_world
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.control.controller import Command, Controller, RobotState
    from shc_cli.validation import load_checked

    robot, gait, _ = load_checked("bullet_openshc", "tripod")
    world = open_world(robot, EngineOptions(parse_terrain("flat"), substeps, engine="pybullet"))
    assert isinstance(world, World)
    controller = Controller(robot, gait, joints=world.read().joints)
    try:
        for _ in range(5):
            world.command(controller.step(Command(state_request=RobotState.RUNNING)).joints)
            world.step()
        fresh = world.p.getJointStates(world.body, world.flat_joints, physicsClientId=world.client)
        reading = world.read()
        measured = [reading.joints[leg, k] for leg, k in world.slots]
        assert np.array_equal(measured, [state[0] for state in fresh])
    finally:
        world.close()


def test_mean_joint_speed_from_the_displacement_equals_the_mean_of_every_physics_step() -> None:
    """The power model takes the period's mean joint speed as displacement / period instead of sampling the speed
    after every physics step; that is exact only because Bullet integrates q += v·h with the new v. Record the
    speeds PyBullet reports after each sub-step and compare."""
    import numpy as np

    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.power import servo_power
    from shc_cli.backends.pybullet_.world import World
    from shc_cli.backends.simulated import open_world
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.control.controller import Command, Controller, RobotState
    from shc_cli.validation import load_checked

    robot, gait, _ = load_checked("bullet_openshc", "tripod")  # the position motor's power model
    world = open_world(robot, EngineOptions(parse_terrain("flat"), 4, engine="pybullet"))
    assert isinstance(world, World)
    controller = Controller(robot, gait, joints=world.read().joints)
    recorded: list[list[tuple[float, float]]] = []

    class Recorder:
        """PyBullet, with every getJointStates answer kept (speed, torque)."""

        def __getattr__(self, name: str) -> object:
            return getattr(pybullet, name)

        def getJointStates(self, *args: object, **kwargs: object) -> object:
            states = pybullet.getJointStates(*args, **kwargs)
            recorded.append([(state[1], state[3]) for state in states])
            return states

    pybullet = world.p
    world.p = Recorder()
    try:
        largest = 0.0
        for _ in range(300):  # start-up: the legs move fast
            recorded.clear()
            world.command(controller.step(Command(state_request=RobotState.RUNNING)).joints)
            world.step()
            samples = np.array(recorded)  # (sub-steps, servos, [speed, torque])
            assert samples.shape[0] == 4
            speed, torque = samples[:, :, 0].mean(axis=0), samples[:, :, 1].mean(axis=0)
            power = world.read().servo_power[world.slot_rows, world.slot_cols]
            np.testing.assert_allclose(power, servo_power(robot.servo, torque, speed), rtol=1e-9, atol=1e-9)
            largest = max(largest, float(np.abs(speed).max()))
        assert largest > 0.5  # the joints really moved [rad/s]
    finally:
        world.p = pybullet
        world.close()


@pytest.mark.parametrize("engine", ENGINES)
def test_a_compliant_servo_sags_in_inverse_proportion_to_its_stiffness(engine: EngineName, tmp_path: Path) -> None:
    """``[servo] control = "pd"``: ATHENA standing on flat ground settles (no oscillation) lower than with the stiff
    position motor, and its femurs' steady errors halve when the stiffness doubles (a proportional servo)."""
    import numpy as np

    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.engine_registry import open_engine
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.control.startup import plan_direct_startup
    from shc_cli.model.chains import Chains
    from shc_cli.spec.loading import load_robot

    names = ["athena"]
    for stiffness in (5.0, 10.0):
        path = tmp_path / f"soft{stiffness:g}.toml"
        path.write_text(f'extends = "athena"\nname = "athena_soft"\n[servo]\ncontrol = "pd"\n'
                        f"stiffness = {stiffness}\ndamping = 0.05\n")
        names.append(str(path))
    heights, errors = [], []
    for name in names:
        robot = load_robot(name).robot
        chains = Chains.from_robot(robot)
        stance = plan_direct_startup(robot, chains, chains.default_joints())
        world = open_engine(robot, EngineOptions(parse_terrain("flat"), 4, engine=engine), stance)
        try:
            for _ in range(300):  # 3 s: settled
                world.command(stance)
                world.step()
            reading = world.read()
        finally:
            world.close()
        assert np.abs(reading.joint_velocities).max() < 0.01  # [rad/s]: standing still
        heights.append(reading.position[2])
        errors.append(np.abs(reading.joints - stance)[:, 1])  # femurs
    assert heights[1] < heights[2] < heights[0] - 0.002  # [m]: softer sits lower
    np.testing.assert_allclose(errors[1] / errors[2], 2.0, rtol=0.25)


def simulate_variant(tmp_path: Path, robot_text: str, args: list[str], out: str, capsys,  # type: ignore[no-untyped-def]
                     monkeypatch) -> tuple[int, str, dict[str, Any]]:
    """``shc simulate`` a robot file written from ``robot_text`` (into ``tmp_path``) for 1 s without plots, with
    ``args`` besides; the exit code, stderr and the run's summary (run directory ``tmp_path / out``)."""
    robot = tmp_path / "variant.toml"
    robot.write_text(robot_text)
    code, _, err = run(["simulate", str(robot), "--duration", "1", "--no-plots", *args, "--out", str(tmp_path / out)],
                       capsys, monkeypatch)
    return code, err, json.loads((tmp_path / out / "summary.json").read_text())


def test_a_robot_that_falls_in_its_first_running_cycle_has_no_speed_and_no_cot(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """ATHENA with an MX-106-like explicit servo law and no rotor inertia is thrown off the floor during start-up
    (tests/test_servo.py) and the fall check, which watches the start-up too, ends the run before it walks: no
    walking speed (a run that ended in its first RUNNING cycle once gave 7 m/s and a CoT of 0.07, which a sweep's CoT
    plot would take for the best run)."""
    code, _, summary = simulate_variant(
        tmp_path, 'extends = "athena"\nname = "athena_dxl"\n[servo]\ncontrol = "dynamixel"\nstall_torque = 1.5\n',
        ["--engine", "pybullet"],
        "run", capsys, monkeypatch)
    assert code == 0 and summary["fell"]
    assert summary["analysed_time_s"] <= 0.01
    assert summary["displacement_speed_mps"] == 0.0 and summary["path_speed_mps"] == 0.0
    assert summary["cot"] is None
