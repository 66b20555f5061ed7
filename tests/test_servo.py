"""The servo and gearbox model (shc_cli/backends/servo.py) against datasheet arithmetic, and its PyBullet wiring."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from shc_cli.backends.engine_registry import EngineName
from shc_cli.backends.servo import ServoModel
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Servo

from .conftest import ROOT

MX106: dict[str, Any] = {"control": "dynamixel", "stall_torque": 8.4, "no_load_speed": 4.71, "torque_constant": 1.62,
         "winding_resistance": 2.31, "supply_voltage": 12.0, "position_p_gain": 850.0, "idle_power": 0.89}


def test_the_e_manual_gain_becomes_a_stiffness_and_the_motor_a_damping() -> None:
    """K_P = 850/128 PWM units per tick, 885 units = 12 V, 4096 ticks per turn; τ = k_t·(V − k_e·ω)/R."""
    gains = ServoModel(Servo(**MX106)).gains()
    volts_per_tick = 850 / 128 * 12.0 / 885
    assert gains.stiffness == pytest.approx(1.62 / 2.31 * volts_per_tick * 4096 / (2 * math.pi), rel=1e-12)
    assert gains.stiffness == pytest.approx(41.17, abs=0.01)
    assert gains.damping == pytest.approx(1.62 * (12.0 / 4.71) / 2.31, rel=1e-12)  # back-EMF, no viscous friction
    assert gains.torque_limit == pytest.approx(8.4)


def test_the_torque_follows_the_torque_speed_line_and_the_limits() -> None:
    model = ServoModel(Servo(**MX106))
    far = np.array([1.0])  # a position error that saturates the PWM
    assert model.torque(far, np.zeros(1), np.zeros(1))[0] == pytest.approx(1.62 * 12.0 / 2.31)  # stall: 8.42 N·m
    assert model.torque(far, np.zeros(1), np.array([4.71]))[0] == pytest.approx(0.0, abs=1e-9)  # no-load speed
    assert model.torque(far, np.zeros(1), np.array([2.355]))[0] == pytest.approx(1.62 * 6.0 / 2.31)  # half way
    limited = ServoModel(Servo(**MX106, current_limit=2.0))
    assert limited.torque(far, np.zeros(1), np.zeros(1))[0] == pytest.approx(2.0 * 1.62)
    assert limited.gains().torque_limit == pytest.approx(2.0 * 1.62)
    small = np.array([0.001])  # inside the linear range: stiffness × error
    assert model.torque(small, np.zeros(1), np.zeros(1))[0] == pytest.approx(model.gains().stiffness * 0.001)


def test_holding_needs_less_current_than_moving_and_negative_work_is_not_returned() -> None:
    servo = Servo(**MX106, coulomb_friction=0.7, holding_ratio=0.3, static_speed=0.1)
    model = ServoModel(servo)
    held = model.electrical(np.array([3.0]), np.array([0.0]))
    assert held.current[0] == pytest.approx(0.3 * 3.0 / 1.62)  # the gear train carries 70 % of a static load
    assert held.power[0] == pytest.approx(0.89 + (0.9 / 1.62) ** 2 * 2.31)
    lifting = model.electrical(np.array([3.0]), np.array([1.0]))  # motoring: load plus friction
    assert lifting.current[0] == pytest.approx(3.7 / 1.62)
    assert lifting.power[0] == pytest.approx(0.89 + (3.7 / 1.62) ** 2 * 2.31 + 3.7 * 1.0)
    lowering = model.electrical(np.array([3.0]), np.array([-1.0]))  # back-driven: friction helps, no regeneration
    assert lowering.current[0] == pytest.approx(2.3 / 1.62)
    assert lowering.power[0] == pytest.approx(0.89 + (2.3 / 1.62) ** 2 * 2.31)
    creeping = model.electrical(np.array([3.0]), np.array([0.05]))  # half-way to static_speed: the two blend
    assert creeping.motor_torque[0] == pytest.approx(0.5 * 0.9 + 0.5 * 3.7)


def test_the_default_servo_keeps_the_old_power_formula() -> None:
    """control = 'position' with no friction: P = idle + (τ/k_t)²R + max(τω, 0), as before the servo model."""
    servo = Servo()
    torque, speed = np.array([2.0, -1.0, 0.5]), np.array([1.0, 2.0, 0.0])
    old = servo.idle_power + (torque / servo.torque_constant) ** 2 * servo.winding_resistance + np.maximum(
        torque * speed, 0.0)
    assert np.allclose(ServoModel(servo).power(torque, speed), old, rtol=1e-12)


def test_pybullet_applies_the_model_torque_and_the_rotor_inertia() -> None:
    """A leg held in the air settles where the servo model's torque holds it: mean torque = stiffness × error − damping
    × speed at every joint (the engine's torque is the model's), and the rotor links carry the armature."""
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.pybullet_.world import World
    from shc_cli.backends.terrain import TerrainSpec
    from shc_cli.model.chains import Chains

    robot = load_robot(ROOT / "robots" / "bullet_insectoid_b.toml").robot
    joints = np.tile([0.0, 0.0, 1.088, -0.765, -1.212], (6, 1))
    world = World(robot, EngineOptions(TerrainSpec(kind="flat"), 4, True), joints)
    try:
        p = world.p
        inertias = [p.getDynamicsInfo(world.body, j, physicsClientId=world.client)[2]
                    for j in range(p.getNumJoints(world.body, physicsClientId=world.client))
                    if p.getJointInfo(world.body, j, physicsClientId=world.client)[12].decode().endswith("_rotor")]
        assert len(inertias) == 30
        assert inertias[0][2] == pytest.approx(robot.servo.armature)
        for _ in range(100):
            world.command(joints)
            world.step()
        reading = world.read()
        gains = world.gains
        error = joints - reading.joints
        expected = gains.stiffness * error - gains.damping * reading.joint_velocities
        assert np.allclose(reading.joint_efforts, expected, atol=0.02)
        assert np.abs(reading.joint_efforts).max() > 0.3  # gravity loads the joints: a real check, not zeros
        assert Chains.from_robot(robot).joints == 5
    finally:
        world.close()


def test_the_i_and_d_gains_convert_as_the_e_manual_says() -> None:
    """K_I = I/65536 PWM units per tick summed every firmware period, K_D = D/16 per tick of change per period:
    for a constant error e over t seconds the I term is I/65536 · e_ticks · t/T_fw PWM units; for a speed ω the D
    term is −D/16 · ω_ticks · T_fw."""
    ticks_per_rad = 4096 / (2 * math.pi)
    volts_per_pwm = 12.0 / 885
    model = ServoModel(Servo(**{**MX106, "position_p_gain": 0.0}, position_i_gain=100.0, firmware_period=0.002))
    error = np.array([0.001])  # small: nothing saturates
    for _ in range(50):  # 50 steps of 1 ms: 0.05 s = 25 firmware periods
        torque = model.torque(error, np.zeros(1), np.zeros(1), 0.001)
    volts = volts_per_pwm * 100 / 65536 * (0.001 * ticks_per_rad) * 25
    assert torque[0] == pytest.approx(1.62 / 2.31 * volts, rel=1e-9)
    d_only = ServoModel(Servo(**{**MX106, "position_p_gain": 0.0}, position_d_gain=160.0, firmware_period=0.001))
    volts = -volts_per_pwm * 160 / 16 * (0.5 * ticks_per_rad) * 0.001
    back_emf = -12.0 / 4.71 * 0.5
    assert d_only.torque(np.zeros(1), np.zeros(1), np.array([0.5]))[0] == pytest.approx(
        1.62 / 2.31 * (volts + back_emf), rel=1e-9)
    assert d_only.gains().damping == pytest.approx(1.62 / 2.31 * (12.0 / 4.71 + volts_per_pwm * 10 * ticks_per_rad
                                                                   * 0.001), rel=1e-9)
    factory = ServoModel(Servo(**MX106))  # I = D = 0 from the factory: the P servo, no state kept
    assert factory.torque(error, np.zeros(1), np.zeros(1), 0.001)[0] == pytest.approx(
        factory.gains().stiffness * 0.001)


def test_the_integral_stops_growing_at_the_pwm_limit() -> None:
    """Anti-windup: a long error saturates the I term at the PWM limit, and it unwinds as soon as the error turns."""
    model = ServoModel(Servo(**{**MX106, "position_p_gain": 0.0}, position_i_gain=1000.0))
    for _ in range(10_000):
        model.torque(np.array([0.5]), np.zeros(1), np.zeros(1), 0.01)
    stall = 1.62 * 12.0 / 2.31
    assert model.torque(np.array([0.5]), np.zeros(1), np.zeros(1), 0.01)[0] == pytest.approx(stall)
    for _ in range(20):  # a reversed error drives it down at once: no 100 s of stored windup to work off
        last = model.torque(np.array([-0.5]), np.zeros(1), np.zeros(1), 0.01)[0]
    assert last < stall * 0.9


@pytest.mark.parametrize("engine", ["pybullet", "mujoco"])
def test_integral_action_removes_the_sag_a_p_servo_leaves(engine: EngineName) -> None:
    """A leg held in the air under gravity: with P only the loaded joints sit a load/stiffness error off their goals;
    with an I gain the same servo settles on them (both engines run the same torque law)."""
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.engine_registry import open_engine
    from shc_cli.backends.terrain import TerrainSpec

    base = load_robot(ROOT / "robots" / "bullet_insectoid_b.toml").robot
    joints = np.tile([0.0, 0.0, 1.088, -0.765, -1.212], (6, 1))
    errors = {}
    for i_gain in (0.0, 2000.0):
        robot = base.model_copy(update={"servo": base.servo.model_copy(update={"position_i_gain": i_gain})})
        world = open_engine(robot, EngineOptions(TerrainSpec(kind="flat"), 4, True, engine=engine), joints)
        try:
            for _ in range(300):  # 3 s
                world.command(joints)
                world.step()
            errors[i_gain] = float(np.abs(joints - world.read().joints).max())
        finally:
            world.close()
    assert errors[0.0] > 0.005  # the P servo's sag: gravity torque / 41 N·m/rad
    assert errors[2000.0] < 0.2 * errors[0.0]


@pytest.mark.parametrize(("figure", "stable"), [(0.6, True), (0.95, True), (1.05, False), (1.5, False)])
def test_the_explicit_stability_figure_marks_where_bullets_integrator_diverges(figure: float, stable: bool) -> None:
    """A joint of inertia I under τ = −K·x − c·ẋ, integrated as Bullet does (velocity first, then position with the
    new velocity), for gains scaled to a given figure: below 1 the motion decays, above 1 it grows."""
    from shc_cli.backends.pybullet_.world import explicit_stability

    step, inertia = 0.0025, 2e-3
    base = explicit_stability(step, 41.0, 1.8, 1.0 / inertia)
    stiffness, damping = 41.0 * figure / base, 1.8 * figure / base
    assert explicit_stability(step, stiffness, damping, 1.0 / inertia) == pytest.approx(figure)
    x, v = 0.1, 0.0
    for _ in range(2000):
        v += step * (-stiffness * x - damping * v) / inertia
        x += step * v
    assert (abs(x) < 0.1) == stable


def test_the_suggested_rate_is_the_lowest_stable_multiple_of_the_control_rate() -> None:
    from shc_cli.backends.pybullet_.world import EXPLICIT_STABILITY_LIMIT, explicit_stability, stable_rate

    period, stiffness, damping, inverse = 0.01, 41.2, 1.79, 1.0 / 0.0015
    rate = stable_rate(period, stiffness, damping, inverse)
    assert rate * period == pytest.approx(round(rate * period))
    assert explicit_stability(1.0 / rate, stiffness, damping, inverse) <= EXPLICIT_STABILITY_LIMIT
    assert explicit_stability(1.0 / (rate - 1.0 / period), stiffness, damping, inverse) > EXPLICIT_STABILITY_LIMIT


def test_a_light_robot_with_a_stiff_servo_law_is_warned_and_the_suggested_rate_walks(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """The quadruped (links of 30–90 g) with the MX-106 firmware law and no rotor inertia: PyBullet's explicit
    servo torque diverges at 400 Hz (the robot is thrown off the floor). The run says so before the user wonders
    why, in the summary and on the terminal, with the rate that fixes it; at that rate it walks, with no note."""
    from .test_simulate import simulate_variant

    text = 'extends = "quadruped"\nname = "quad_dxl"\n[servo]\ncontrol = "dynamixel"\n'
    code, err, summary = simulate_variant(tmp_path, text, ["--engine", "pybullet"], "a", capsys, monkeypatch)
    assert code == 0 and summary["fell"]
    [warning] = summary["engine_warnings"]
    assert "too stiff for 400 Hz physics" in warning
    [note] = [line for line in err.splitlines() if line.startswith("note: pybullet: ")]
    rate = note.split("--physics-rate ")[1].split()[0]
    assert int(rate) > 400
    code, err, summary = simulate_variant(tmp_path, text, ["--engine", "pybullet", "--physics-rate", rate], "b",
                                          capsys, monkeypatch)
    assert code == 0 and not summary["fell"] and summary["engine_warnings"] == []
    assert "note: pybullet" not in err


@pytest.mark.parametrize("name", ["bullet_insectoid_a", "bullet_insectoid_b", "bullet_mammalian_a",
                                  "bullet_mammalian_b"])
def test_the_paper_robots_are_within_the_explicit_stability_limit(name: str) -> None:
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.pybullet_.world import World
    from shc_cli.backends.terrain import TerrainSpec

    robot = load_robot(name).robot
    joints = np.array([[joint.unpacked for joint in leg.joints.values()] for leg in robot.legs.values()])
    world = World(robot, EngineOptions(TerrainSpec(kind="flat"), 4), joints)
    try:
        assert world.warnings == []
    finally:
        world.close()
