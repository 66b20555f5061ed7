"""The ``quad_wave`` body sway (poses/quad_wave.toml, shc_cli/spec/sway.py): while a leg swings the body moves
towards the three standing feet, off the diagonal edge that the centre of mass sits on without it.

Expectations come from geometry and OpenSHC's poser curve, not from the code under test: mid-swing of AR is
phase 2 of the 8-unit cycle, where the +y poser (window 6–4, peak at 1) has fallen a third of its second half,
``A(1 − t)³(1 + 3t)`` at t = 1/3, and the −y poser (window 2–0) has only just started (0)."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from shc_cli.analysis.metrics import feet_and_com
from shc_cli.record.runread import read_run
from shc_cli.spec.loading import data_dir
from shc_cli.spec.sway import quad_wave_sway_toml, sway_amplitude

from .test_cli import run

OPPOSITE = {"AR": "BL", "BL": "AR", "BR": "AL", "AL": "BR"}
MID_SWING_SHARE = (1 - 1 / 3) ** 3 * (1 + 3 / 3)  # = 16/27: the +y poser at t = 1/3 of its falling half


def _plan(robot: Path, out: Path, capsys, monkeypatch) -> Path:  # type: ignore[no-untyped-def]
    code, _, err = run(["plan", str(robot), "--duration", "6", "--no-plots", "--out", str(out)], capsys, monkeypatch)
    assert code == 0, err
    return out


def _mid_swing_distances(path: Path) -> dict[str, list[tuple[float, float, float]]]:
    """Per swinging leg, at each mid-swing row: the signed distance [m] of the body origin and of the centre of
    mass from the standing diagonal (the two standing feet that are not the swinging leg's opposite), positive
    towards the third standing foot, and that normal's y component in the body frame."""
    log = read_run(path)
    assert log.progress is not None
    moving = np.flatnonzero(log.walk_state == "MOVING")
    cycle = round(4 / 2.5 / log.robot.time_delta)  # 8 units, 2 per swing of 1 / step_frequency (2.5 Hz) [iterations]
    rows = np.arange(moving[0] + cycle, moving[-1])  # posers wait for their start phase: skip the first cycle
    feet, com = feet_and_com(log, rows)
    legs = list(log.legs)
    found: dict[str, list[tuple[float, float, float]]] = {leg: [] for leg in legs}
    for i, leg in enumerate(legs):
        swing = log.progress[rows, i, 1]
        mids = np.flatnonzero((swing[:-1] < 0.5) & (swing[1:] >= 0.5) & (swing[:-1] >= 0.0)) + 1
        for m in mids:
            a, b = (feet[m, legs.index(other), :2] for other in legs if other not in (leg, OPPOSITE[leg]))
            third = feet[m, legs.index(OPPOSITE[leg]), :2]
            along = (b - a) / np.linalg.norm(b - a)
            normal = np.array([-along[1], along[0]])
            if np.dot(third - a, normal) < 0.0:
                normal = -normal
            yaw = float(log.rpy[rows[m], 2])
            body_y = np.array([-np.sin(yaw), np.cos(yaw)])
            found[leg].append((float(np.dot(log.position[rows[m], :2] - a, normal)),
                               float(np.dot(com[m, :2] - a, normal)), float(np.dot(normal, body_y))))
    return found


def test_the_quadruped_sways_towards_the_standing_feet_in_each_swing(  # type: ignore[no-untyped-def]
        tmp_path: Path, capsys, monkeypatch) -> None:
    """The bundled quadruped with ``[pose] auto = true`` (the bundled quad_wave set is sized for it) against the
    same robot without auto posing (its default)."""
    still = data_dir("robots") / "quadruped.toml"
    text = still.read_text()
    assert "\n[pose]" not in text
    swaying = tmp_path / "quadruped.toml"
    swaying.write_text(text.replace("\n[templates.leg]", "\n[pose]\nauto = true\n\n[templates.leg]", 1))
    sway = _mid_swing_distances(_plan(swaying, tmp_path / "sway", capsys, monkeypatch))
    plain = _mid_swing_distances(_plan(still, tmp_path / "plain", capsys, monkeypatch))
    robot = tomllib.loads(text)
    half_spread = abs(robot["legs"]["AR"]["stance"]["y"])
    amplitude = half_spread / 3  # the three standing feet's centroid lies a third of the half-spread to the side
    for leg in ("AR", "BR", "BL", "AL"):
        assert len(sway[leg]) >= 1 and len(sway[leg]) == len(plain[leg]), leg
        for (body, com, normal_y), (body_0, com_0, _) in zip(sway[leg], plain[leg], strict=True):
            # the body's y shift (+y for the right legs, -y for the left) seen across the diagonal; one control
            # iteration earlier or later moves it 0.03 of the amplitude (-12t(1-t)² per 60 iterations)
            expected = MID_SWING_SHARE * amplitude * abs(normal_y)
            assert expected > 0.01
            assert np.sign(normal_y) == (1 if leg.endswith("R") else -1), leg
            assert body - body_0 == pytest.approx(expected, rel=0.1), leg
            assert com - com_0 > 0.5 * expected  # the centre of mass moves into the support triangle
            assert com > 0.5 * expected


def test_an_imported_sway_set_scales_with_the_stance() -> None:
    assert sway_amplitude([0.094, -0.094, 0.093, -0.095]) == 0.031
    text = quad_wave_sway_toml("spot_quad_wave", 0.031, "spot")
    data = tomllib.loads(text)
    assert [(p["start"], p["end"], p["y"]) for p in data["poser"]] == [(6, 4, 0.031), (2, 0, -0.031)]
