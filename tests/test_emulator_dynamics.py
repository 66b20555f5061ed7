"""The servo emulators' dynamics model (``dynamics=`` a ``[servo]`` table): a load-free joint whose readings follow
the motor and gearbox laws. Expected values are worked out here from the datasheet figures (XM430-W350: 4.1 N·m
and 2.3 A at stall, 46 rpm no-load, 12 V; MX-64(1.0): 6.0 N·m, 4.1 A, 63 rpm; STS3215: 1.91 N·m, 2.7 A, 52 rpm at
7.4 V) and the e-Manual's gain and unit conversions, not taken from the code under test. Each servo runs on an
injected clock, so nothing waits."""

from __future__ import annotations

import math

import pytest

from shc_cli.hardware.emulator import EmulatedServo
from shc_cli.hardware.emulator_protocol1 import EMULATED_MODELS
from shc_cli.hardware.emulator_protocol1 import EmulatedServo as Protocol1Servo
from shc_cli.hardware.models import MODELS
from shc_cli.spec.robot import Servo

RPM = 2.0 * math.pi / 60.0
"""rad/s per rpm."""


def _xm430(**fields: float) -> tuple[EmulatedServo, list[float]]:
    now = [100.0]
    servo = EmulatedServo(1, MODELS["XM430-W350"], clock=lambda: now[0],
                          dynamics=Servo(model="XM430-W350", **fields))  # type: ignore[arg-type]
    servo.write(servo.model.torque_enable, bytes([1]))
    return servo, now


def _goal(servo: EmulatedServo, ticks: int) -> None:
    servo.write(servo.model.goal_position, ticks.to_bytes(4, "little", signed=True))


def _state(servo: EmulatedServo) -> tuple[int, int, int]:
    """Present Current [2.69 mA], Present Velocity [0.229 rpm], Present Position [ticks] (one read of 126–135)."""
    data = servo.read(126, 10)
    return tuple(int.from_bytes(data[a:b], "little", signed=True) for a, b in ((0, 2), (2, 6), (6, 10)))  # type: ignore[return-value]


def _motor(stall_torque: float, stall_current: float, no_load_rpm: float, volts: float) -> tuple[float, float, float]:
    """Torque constant [N·m/A], winding resistance [Ω], back-EMF constant [V·s/rad] from datasheet figures."""
    return stall_torque / stall_current, volts / stall_current, volts / (no_load_rpm * RPM)


def test_a_saturated_step_cruises_where_motor_torque_meets_friction() -> None:
    """Far from the goal the PWM is at 100 %: the joint cruises at the speed where the motor's torque–speed line
    meets viscous plus Coulomb friction, drawing the current that friction needs."""
    coulomb, viscous = 0.1, 0.05
    servo, now = _xm430(coulomb_friction=coulomb, viscous_friction=viscous, armature=0.005)
    _goal(servo, 2048 + 3000)  # 4.6 rad: saturated for the whole half second
    now[0] += 0.5
    current, velocity, position = _state(servo)
    kt, resistance, ke = _motor(4.1, 2.3, 46.0, 12.0)
    speed = (kt * 12.0 / resistance - coulomb) / (kt * ke / resistance + viscous)  # [rad/s]
    amps = (12.0 - ke * speed) / resistance
    assert velocity == pytest.approx(speed / RPM / 0.229, abs=1)
    assert current == pytest.approx(amps * 1000.0 / 2.69, abs=1)
    assert position > 2048 + 0.9 * speed * 0.5 * 4096 / (2 * math.pi)  # it got there at about that speed


def test_the_rotor_inertia_sets_the_mechanical_time_constant() -> None:
    """Without friction the speed after a saturated step rises as ``1 − e^(−t/τ)`` to the no-load speed, with the
    mechanical time constant ``τ = J·R/(k_t·k_e)``."""
    inertia = 0.05
    servo, now = _xm430(armature=inertia)
    _goal(servo, 2048 + 700)  # 1.07 rad: the PWM stays saturated (full voltage above 0.2 rad of error)
    kt, resistance, ke = _motor(4.1, 2.3, 46.0, 12.0)
    tau = inertia * resistance / (kt * ke)
    now[0] += tau
    _, velocity, _ = _state(servo)
    assert velocity * 0.229 == pytest.approx(46.0 * (1.0 - math.exp(-1.0)), rel=0.02)


def test_coulomb_friction_leaves_the_position_error_a_p_controller_cannot_overcome() -> None:
    """A P-controlled joint stops where the motor's torque at standstill, ``k_t·V/R`` with ``V = K·e``, no longer
    exceeds the Coulomb friction: a steady error within ``friction·R/(k_t·K)``, holding the current ``K·e/R``."""
    coulomb = 0.3
    servo, now = _xm430(coulomb_friction=coulomb, armature=0.01)
    _goal(servo, 2048 + 500)
    now[0] += 2.0
    current, velocity, position = _state(servo)
    kt, resistance, _ = _motor(4.1, 2.3, 46.0, 12.0)
    per_tick = 12.0 / 885.0 * 800.0 / 128.0  # e-Manual: K_P = P/128 PWM units per tick, 885 = 12 V [V/tick]
    error = 2048 + 500 - position
    assert velocity == 0 and 0 < error <= coulomb * resistance / (kt * per_tick) + 1
    units_per_tick = per_tick / resistance * 1000.0 / 2.69  # [2.69 mA]: the position reads in whole ticks
    assert current == pytest.approx(units_per_tick * error, abs=units_per_tick / 2 + 1)
    now[0] += 1.0
    assert _state(servo) == (current, 0, position)  # static friction holds it


def test_without_friction_it_reaches_the_goal_and_with_the_torque_off_it_does_not_move() -> None:
    servo, now = _xm430(armature=0.01)
    _goal(servo, 2048 - 400)
    now[0] += 1.0
    assert _state(servo) == (0, 0, 2048 - 400)
    servo.write(servo.model.torque_enable, bytes([0]))
    _goal(servo, 2048 + 400)
    now[0] += 1.0
    assert _state(servo) == (0, 0, 2048 - 400)


@pytest.mark.parametrize(("name", "sheet", "speed_rpm_per_unit"), [
    ("MX-64(1.0)", (6.0, 4.1, 63.0, 12.0), 0.114), ("STS3215", (1.91, 2.7, 52.0, 7.4), None)])
def test_protocol1_and_feetech_servos_report_the_same_law_in_their_units(
        name: str, sheet: tuple[float, float, float, float], speed_rpm_per_unit: float | None) -> None:
    """Present Speed in the model's unit (MX(1.0) 0.114 rpm; Feetech steps/s) and Present Load as the current's
    share of the stall current in 0.1 % (sign-magnitude, bit 10), as the hosts read them."""
    now = [5.0]
    coulomb, viscous = 0.05, 0.02
    servo = Protocol1Servo(1, EMULATED_MODELS[name], lambda: now[0], 0.03, None,
                           Servo(model=name, coulomb_friction=coulomb, viscous_friction=viscous, armature=0.003))
    servo.write(servo.addr["torque"], bytes([1]))
    servo.write(servo.addr["goal"], (2048 + 1500).to_bytes(2, "little"))  # 2.3 rad: 1 rad still to go at 0.2 s
    now[0] += 0.2
    _, data = servo.read(servo.addr["position"], 6)
    speed_word, load_word = int.from_bytes(data[2:4], "little"), int.from_bytes(data[4:6], "little")
    kt, resistance, ke = _motor(*sheet)
    volts = sheet[3]
    speed = (kt * volts / resistance - coulomb) / (kt * ke / resistance + viscous)
    amps = (volts - ke * speed) / resistance
    if speed_rpm_per_unit is None:  # Feetech: steps/s, bit 15 the sign
        assert speed_word == pytest.approx(speed * 4096 / (2 * math.pi), abs=1)
    else:  # Dynamixel 1.0: bit 10 set = clockwise (negative); this one turns counter-clockwise
        assert speed_word == pytest.approx(speed / RPM / speed_rpm_per_unit, abs=1)
    assert load_word == pytest.approx(amps / sheet[1] * 1000.0, abs=1)


def test_shc_hw_emulate_dynamics_gives_every_bus_the_robot_files_servo_model(tmp_path: object) -> None:
    """``shc hw emulate ROBOT --dynamics``: every emulated servo moves as the robot's ``[servo]`` table (a Protocol
    2.0 bus here); without it, the first-order lag."""
    from pathlib import Path

    from shc_cli.hardware.emulator import BusEmulator
    from shc_cli.hardware.emulator_process import robot_emulators
    from shc_cli.spec.loading import load_robot

    path = Path(str(tmp_path)) / "xm.toml"
    path.write_text('extends = "openshc_default"\nname = "xm"\n[servo]\nmodel = "XM430-W350"\ncoulomb_friction = 0.2\n'
                    '[hardware]\nmodel = "XM430-W350"\n[hardware.servos]\n'
                    + "".join(f"{leg}_{joint} = {{ id = {10 * k + j + 1} }}\n" for k, leg in
                              enumerate(("AR", "BR", "CR", "CL", "BL", "AL"))
                              for j, joint in enumerate(("coxa", "femur", "tibia"))))
    robot = load_robot(path).robot
    [bus] = robot_emulators(robot, dynamics=True)
    assert isinstance(bus, BusEmulator) and len(bus.servos) == 18
    assert all(servo.dynamics == robot.servo for servo in bus.servos.values())
    assert robot.servo.coulomb_friction == 0.2
    [plain] = robot_emulators(robot)
    assert isinstance(plain, BusEmulator) and all(s.dynamics is None for s in plain.servos.values())
    for emulator in (bus, plain):  # (closes their pseudo-terminals)
        with emulator:
            pass
