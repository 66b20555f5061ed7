"""Restitution in MuJoCo (docs/physics-model.md): not mapped onto an under-damped contact spring, since PyBullet
applies no restitution below its 0.2 m/s threshold, where walking feet land — and with it ATHENA's ramp result
(Robotica 2023, the paper's set-up: friction 0.9, restitution 0.5) holds in the default engine too."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Literal

import pytest

from shc_cli import api
from shc_cli.backends.mujoco_.mjcf import Options, robot_mjcf
from shc_cli.backends.terrain import Terrain, parse_terrain
from shc_cli.spec.loading import load_robot


def test_restitution_leaves_the_mujoco_model_critically_damped() -> None:
    robot = load_robot("athena").robot
    terrain = Terrain(parse_terrain("ramp:10"), 0, diagonal="mujoco")
    bouncy = robot_mjcf(robot, terrain, Options(0.0025, 0.2, restitution=0.5))
    plain = robot_mjcf(robot, terrain, Options(0.0025, 0.2, restitution=0.0))
    assert bouncy == plain
    assert 'solref="0.005 1"' in plain


def test_a_mujoco_run_with_restitution_says_it_is_not_applied(tmp_path: Path,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.INFO, logger="shc_cli"):
        api.simulate("athena", duration=0.1, restitution=0.5, out=tmp_path / "run", plots=False)
    assert any("MuJoCo applies no restitution" in r.getMessage() for r in caplog.records)


def _posture_change(engine: Literal["mujoco", "pybullet"], tmp: Path, restitution: float = 0.5) -> dict[str, float]:
    """Relative change (posture control against simple control) of the torso height's IQR and the median roll and
    pitch rates on the 10° ramp, the paper's set-up."""
    figures = {}
    for name, gains in (("on", "kz=0.8,ka=0.6,kb=0"), ("off", "kz=0,ka=0,kb=0")):
        run = api.simulate("athena", engine=engine, terrain="ramp:10", posture=gains, friction=0.9,
                           restitution=restitution, seed=0, duration=30, out=tmp / f"{engine}-{name}", plots=False)
        figures[name] = api.analyze(run)
    return {key: figures["on"][key] / figures["off"][key] - 1.0
            for key in ("height_iqr_m", "roll_rate_median_rps", "pitch_rate_median_rps")}


Engine = Literal["mujoco", "pybullet"]


@pytest.mark.slow
@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_athena_posture_control_on_the_ramp_in_both_engines(engine: Engine, tmp_path: Path) -> None:
    """Issue 38's acceptance: height IQR ≤ −40 %, roll-rate median ≤ −20 %, pitch-rate median < 0 (the paper:
    −36 % roll, −11.9 % pitch). Measured: MuJoCo −54 %, −28 %, −9 %."""
    change = _posture_change(engine, tmp_path)
    assert change["height_iqr_m"] <= -0.40
    assert change["roll_rate_median_rps"] <= -0.20
    assert change["pitch_rate_median_rps"] < 0.0


@pytest.mark.slow
def test_pybullet_walks_the_ramp_alike_with_and_without_restitution(tmp_path: Path) -> None:
    """The reason for the mapping: in PyBullet restitution 0.5 and 0 walk ATHENA up the ramp within 1 %."""
    distances = []
    for e in (0.5, 0.0):
        run = api.simulate("athena", engine="pybullet", terrain="ramp:10", friction=0.9, restitution=e, seed=0,
                           duration=30, out=tmp_path / f"r{e}", plots=False)
        distances.append(run.summary.distance_m or 0.0)
    assert distances[0] == pytest.approx(distances[1], rel=0.01)
    assert distances[1] > 0.9
