"""Terrain adaptation in physics, in both engines: IMU levelling on a ramp (OpenSHC), ATHENA posture control on a
ramp, admittance over a step, rough-terrain mode on blocks."""

from __future__ import annotations

import csv
import statistics
from pathlib import Path

import pytest

from shc_cli.domain.config import SimulationConfig
from shc_cli.domain.simulate import simulate

pytestmark = pytest.mark.slow  # long simulations on ramps, steps and blocks in both engines

# The Bullet tests were calibrated on OpenSHC's Bullet (arrangement B, its Gazebo position servos and parameters, e.g.
# the IMU PID gains): pinned to that robot, not the default `bullet` (the paper's robot, with the calibrated servos).
OPENSHC_BULLET = "bullet_openshc"

ENGINES = ["pybullet", "mujoco"]


def _log(path: Path) -> list[dict[str, str]]:
    with (path / "log.csv").open() as handle:
        return list(csv.DictReader(handle))


def _walk(tmp: Path, name: str, robot: str, seconds: float, switches: dict[str, object],
          engine: str = "pybullet") -> list[dict[str, str]]:
    path, summary = simulate(SimulationConfig.from_options(switches, robot=robot, duration=seconds, out=tmp / name,
                                                           plots=False, terrain="ramp:10", engine=engine)).pair
    assert summary.fell is False
    return _log(path)


@pytest.mark.parametrize("engine", ENGINES)
def test_imu_posing_levels_the_body_on_a_ramp(engine: str, tmp_path: Path) -> None:
    """Bullet up the 10° ramp: without IMU posing the body pitches with the slope (−0.175 rad); with OpenSHC's IMU
    PID (Bullet gains p 1.0, i 0.01, d −0.05) the steady error halves — a proportional gain of 1 takes half the
    tilt out, the small integral gain adds little within seconds (measured −0.176 vs −0.083 rad over 20 s)."""
    pitch = {}
    for name, on in (("off", False), ("imu", True)):
        rows = _walk(tmp_path, name, OPENSHC_BULLET, 8.0, {"imu_posing": on}, engine)
        on_slope = [float(r["pitch"]) for r in rows if float(r["x"]) > 1.05]  # all feet on the slope
        assert len(on_slope) > 100
        pitch[name] = statistics.median(on_slope)
    assert pitch["off"] == pytest.approx(-0.1745, abs=0.01)  # 10°, nose up is negative pitch
    assert abs(pitch["imu"]) < 0.6 * abs(pitch["off"])


@pytest.mark.parametrize("engine", ENGINES)
def test_athena_posture_control_steadies_the_height_on_the_ramp(engine: str, tmp_path: Path) -> None:
    """ATHENA up the 10° ramp, simple control (0, 0, 0) vs posture control (0.8, 0.6, 0): a smaller body-height
    IQR and a median nearer the standing height. (The paper's simple control sags to 65 % of the standing height,
    so there posture control also raises the median; our servos do not sag — docs/terrain-adaptation.md.)"""
    heights, reference = {}, {}
    for name, gains in (("simple", "kz=0,ka=0,kb=0"), ("posture", "kz=0.8,ka=0.6,kb=0")):
        rows = _walk(tmp_path, name, "athena", 30.0, {"posture": gains}, engine)
        running = [r for r in rows if r["robot_state"] == "RUNNING"]
        reference[name] = float(running[0]["height"])
        heights[name] = [float(r["height"]) for r in running if float(r["x"]) > 0.45]  # at and on the slope
        assert len(heights[name]) > 500
    assert reference["simple"] == pytest.approx(reference["posture"], abs=1e-9)

    def iqr(values: list[float]) -> float:
        q = statistics.quantiles(values, n=4)
        return q[2] - q[0]

    assert iqr(heights["posture"]) < 0.8 * iqr(heights["simple"])
    assert abs(statistics.median(heights["posture"]) - reference["posture"]) < abs(
        statistics.median(heights["simple"]) - reference["simple"])


ADMITTANCE_ROBOT = """
extends = "bullet_openshc"  # the geometry and servos the thresholds were measured on
name = "bullet_admittance"
[admittance]
use_joint_effort = false   # foot force sensors
# Bullet's OpenSHC values (k = 20 N/m, gain 0.5) would fold a leg carrying 22 N by 0.55 m (clamped at 0.2):
# a gain of 0.02 makes a leg yield 2 cm under its share of the weight.
force_gain = { default = 0.02 }
"""


@pytest.mark.parametrize("engine", ENGINES)
def test_admittance_keeps_more_feet_on_the_ground_over_a_step(engine: str, tmp_path: Path) -> None:
    """Bullet walks up a 6 cm step (stairs:0.06,1.0): with admittance on, the loaded legs yield and the others keep
    their feet down — fewer cycles with fewer than three feet in contact, more feet in contact on average."""
    robot = tmp_path / "bullet_admittance.toml"
    robot.write_text(ADMITTANCE_ROBOT, encoding="utf-8")
    legs = ["AR", "BR", "CR", "CL", "BL", "AL"]
    counts = {}
    for name, on in (("off", False), ("on", True)):
        path, summary = simulate(SimulationConfig(robot=str(robot), duration=8.0, out=tmp_path / name, plots=False,
                                                  terrain="stairs:0.06,1.0", admittance=on, engine=engine)).pair
        assert summary.fell is False
        rows = [r for r in _log(path) if r["robot_state"] == "RUNNING" and 0.2 < float(r["x"]) < 1.4]
        assert len(rows) > 300
        counts[name] = [sum(int(float(r[f"{leg}_contact"])) for leg in legs) for r in rows]
    few = {name: sum(1 for c in values if c < 3) / len(values) for name, values in counts.items()}
    assert few["on"] < few["off"]  # 0.124 against 0.135 (0.61 of it before MuJoCo's elliptic friction cone)
    assert statistics.mean(counts["on"]) > statistics.mean(counts["off"])


ROUGH_ROBOT = """
extends = "bullet_openshc"  # the geometry and servos the thresholds were measured on
name = "bullet_rough"
[walker]
rough_terrain_mode = true
step_depth = { default = 0.05, min = 0.0, max = 0.1, step = 0.01 }
"""


def test_rough_terrain_mode_on_flat_ground_walks_as_usual(tmp_path: Path) -> None:
    """Without sensing, rough-terrain mode only re-derives the default tips from where the feet land; on flat
    ground that is where they were, so the planned joints equal the normal mode's."""
    from shc_cli.control.controller import Command, Controller, RobotState
    from shc_cli.validation import load_checked

    robot_file = tmp_path / "bullet_rough.toml"
    robot_file.write_text(ROUGH_ROBOT, encoding="utf-8")
    outputs = {}
    for name in (OPENSHC_BULLET, str(robot_file)):  # the rough variant extends bullet_openshc
        robot, gait, _ = load_checked(name, "tripod")
        controller = Controller(robot, gait)
        joints = []
        for cycle in range(1200):
            out = controller.step(Command(velocity=(1.0, 0.0, 0.3) if cycle > 600 else (0.0, 0.0, 0.0),
                                          state_request=RobotState.RUNNING))
            joints.append(out.joints.copy())
        outputs[name] = joints
    import numpy as np

    np.testing.assert_allclose(outputs[OPENSHC_BULLET], outputs[str(robot_file)], atol=1e-9)


OPENSHC_IK = "[ik]\nlimit_avoidance_cap = 0.0\n"
"""OpenSHC's IK step (docs/deviations.md, issue 42): the rough-terrain comparison below was measured with it."""


@pytest.mark.parametrize("engine", ENGINES)
def test_rough_terrain_mode_keeps_more_feet_down_on_blocks(engine: str, tmp_path: Path) -> None:
    """Bullet over 1–5 cm blocks: with rough-terrain mode (step depth 5 cm, touchdown from the foot forces) the
    feet land where the ground is and the default footholds follow, so fewer cycles have fewer than three feet
    down (8 s, seed 0, OpenSHC's IK step: MuJoCo 5.1 % vs 13.4 %, PyBullet 22.5 % vs 32.7 %). With shc's default
    ``ik.limit_avoidance_cap`` the margin shrinks below this test's 10 % (MuJoCo 10.0 vs 11.0 %, PyBullet 29.4 vs
    31.4 %). Both vary in sign with the blocks' seed: MuJoCo, seeds 0–3, mean 7.5 vs 8.6 % with OpenSHC's step
    (seed 1: 9.4 vs 4.0 %), 10.2 vs 10.6 % with the cap (seed 2: 15.6 vs 8.0 %) — open (issue 42)."""
    robot = tmp_path / "bullet_rough.toml"
    robot.write_text(ROUGH_ROBOT + OPENSHC_IK, encoding="utf-8")
    normal = tmp_path / "bullet_normal.toml"
    normal.write_text(f'extends = "{OPENSHC_BULLET}"\nname = "bullet_normal"\n{OPENSHC_IK}', encoding="utf-8")
    legs = ["AR", "BR", "CR", "CL", "BL", "AL"]
    few = {}
    for name, robot_name in (("normal", str(normal)), ("rough", str(robot))):
        path, summary = simulate(SimulationConfig(robot=robot_name, gait="tripod", duration=8.0, out=tmp_path / name,
                                                  plots=False, terrain="blocks:0.01,0.05", engine=engine)).pair
        assert summary.fell is False
        rows = [r for r in _log(path) if r["robot_state"] == "RUNNING" and float(r["x"]) > 0.8]
        assert len(rows) > 150
        counts = [sum(int(float(r[f"{leg}_contact"])) for leg in legs) for r in rows]
        few[name] = sum(1 for c in counts if c < 3) / len(counts)
    assert few["rough"] < 0.9 * few["normal"]
