"""``--admittance`` on the default robot walks (issue 42, point 4), and a run that makes no progress has no cost of
transport in its summary line, its ``summary.json`` and ``shc analyze`` alike.

The cause: shc's tip forces are newtons, and Bullet's OpenSHC values (``force_gain`` 0.5, ``virtual_stiffness``
20 N/m; never used by OpenSHC, whose Bullet files keep admittance off) make a leg carrying its share of the weight,
10.07 kg·9.81 / 6 = 16.5 N, yield gain·F/k = 0.41 m — clamped at 0.2 m, the whole body clearance: the body sits on
its servos. The bundled ``force_gain`` is 0.01 (8 mm standing).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from shc_cli import api
from shc_cli.control.admittance import MAX_DELTA, AdmittanceController
from shc_cli.spec.loading import load_robot

from .test_cli import run

WEIGHT_SHARE = 10.07 * 9.81 / 6
"""Bullet's weight on each of six feet [N] (Table I's mass)."""
OPENSHC_GAIN = """
extends = "bullet"
name = "bullet_openshc_gain"
[admittance]
force_gain = { default = 0.5 }   # OpenSHC's Bullet value
"""


def _standing_offset(name: str, force: float) -> float:
    """The admittance offset [m] of a leg holding ``force`` [N] at rest, with robot ``name``'s parameters."""
    spec = load_robot(name).robot.admittance
    controller = AdmittanceController(6, spec.virtual_mass.default, spec.virtual_stiffness.default,
                                      spec.virtual_damping_ratio.default, spec.force_gain.default,
                                      spec.integrator_step_time, spec.swing_stiffness_scaler,
                                      spec.load_stiffness_scaler, spec.dynamic_stiffness)
    for _ in range(3000):
        delta = controller.update(np.full(6, force), np.full(6, -1.0), walking=False)
    return float(delta[0])


@pytest.mark.parametrize("name", ["bullet", "bullet_openshc", "bullet_mammalian"])
def test_bullets_admittance_yields_millimetres_under_the_weight(name: str) -> None:
    """gain·F/k with the bundled values: 0.01 · 16.5 N / 20 N/m = 8.2 mm (OpenSHC's 0.5 would be 0.41 m)."""
    assert _standing_offset(name, WEIGHT_SHARE) == pytest.approx(0.01 * WEIGHT_SHARE / 20.0, rel=1e-3)
    assert 0.5 * WEIGHT_SHARE / 20.0 > MAX_DELTA == 0.2


def _walked(tmp_path: Path, name: str, admittance: bool, **options: object) -> tuple[float, api.Run]:
    """(distance [m], the run) of the default robot simulated for 5 s."""
    done = api.simulate("bullet", duration=5.0, admittance=admittance, plots=False, out=tmp_path / name,
                        **options)  # type: ignore[arg-type]
    assert done.summary.distance_m is not None
    return done.summary.distance_m, done


def test_admittance_walks_on_flat_ground_as_far_as_without(tmp_path: Path) -> None:
    """The default robot, 5 s at full throttle on flat ground: with admittance it walks ≥ 90 % of the distance it
    walks without (measured: 97 % over 10 s) and has no NO PROGRESS flag. (Without: 0.32 m, at the verified 0.094
    m/s of its speed limits after the start-up.)"""
    off, _ = _walked(tmp_path, "off", False)
    on, run_on = _walked(tmp_path, "on", True)
    assert off > 0.25
    assert on >= 0.9 * off
    assert not run_on.summary.no_progress and run_on.summary.cot is not None


@pytest.mark.slow  # four simulations on blocks
def test_admittance_walks_on_blocks(tmp_path: Path) -> None:
    """``--terrain blocks`` (seeds 0, 1): with admittance the default robot walks ≥ 50 % of the distance it walks
    without, summed (measured over 10 s: 73 % over seeds 0–2)."""
    off = on = 0.0
    for seed in (0, 1):
        off += _walked(tmp_path, f"off{seed}", False, terrain="blocks", seed=seed)[0]
        on += _walked(tmp_path, f"on{seed}", True, terrain="blocks", seed=seed)[0]
    assert on >= 0.5 * off


def test_a_run_without_progress_has_no_cot_anywhere(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """OpenSHC's gain (0.5) folds the legs: NO PROGRESS. The line said "CoT: not enough walking" while ``shc analyze``
    printed a CoT of 302; now the summary's ``cot`` and analyze's are None too, with the same window's rule."""
    robot = tmp_path / "gain.toml"
    robot.write_text(OPENSHC_GAIN, encoding="utf-8")
    out = tmp_path / "stuck"
    code, stdout, err = run(["simulate", str(robot), "--admittance", "--duration", "5", "--no-plots", "--out",
                             str(out)], capsys, monkeypatch)
    assert code == 0, err
    assert "NO PROGRESS" in stdout and "CoT: not enough walking to measure" in stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["no_progress"] and summary["mean_power_w"] > 0.0
    assert summary["cot"] is None
    assert api.analyze(out)["cot"] is None
    code, stdout, err = run(["analyze", str(out)], capsys, monkeypatch)
    assert code == 0, err
    assert stdout.splitlines()[-1].split()[8] == "–"  # the CoT column
