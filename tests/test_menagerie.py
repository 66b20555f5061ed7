"""MuJoCo Menagerie's legged robots through ``shc import mjcf`` (issue 37, point 11): each imports with no option,
its tips match MuJoCo's own kinematics, and it walks 10 s on flat ground (MuJoCo) at least 0.6 of the distance asked
without falling. The models are Menagerie's own files kept in ``tests/data/robots/menagerie`` (their meshes left
out: the import reads no visuals and leaves missing meshes out with a note; licences and sources in
``tests/data/robots/README.md``), so the test needs neither the ``mujoco-menagerie`` package nor its download."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .conftest import ROOT
from .test_cli import run

MENAGERIE = ROOT / "tests" / "data" / "robots" / "menagerie"
MODELS = sorted(MENAGERIE.glob("*/*.xml"))
"""Menagerie's legged models kept here (the registry's quadrupeds; it has no hexapod)."""


def test_the_kept_menagerie_models_are_there() -> None:
    assert {path.name for path in MODELS} == {"go1.xml", "anymal_c.xml"}


@pytest.mark.slow  # an import and 10 s of MuJoCo per robot
@pytest.mark.parametrize("xml", MODELS, ids=[path.stem for path in MODELS])
def test_a_menagerie_quadruped_imports_and_walks(xml: Path, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, err = run(["import", "mjcf", str(xml), "--out", str(tmp_path / "robot")], capsys, monkeypatch)
    assert code == 0, err
    error = float(out.split("largest tip difference to MuJoCo's (mj_kinematics) ")[1].split()[0])
    assert error < 1e-9, out
    [robot_file] = (tmp_path / "robot" / "robots").glob("*.toml")
    code, out, err = run(["simulate", str(robot_file), "--duration", "10", "--no-plots", "--out",
                          str(tmp_path / "sim")], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((tmp_path / "sim" / "summary.json").read_text())
    assert not summary["fell"] and summary["complete"], summary
    assert summary["walked_share"] >= 0.6, out
