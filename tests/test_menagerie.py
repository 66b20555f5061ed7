"""MuJoCo Menagerie's legged robots through ``shc import mjcf`` (issue 37, point 11), from the ``mujoco-menagerie``
package: each imports with no option, its tips match MuJoCo's own kinematics, and it walks 10 s on flat ground
(MuJoCo) at least 0.6 of the distance asked without falling.

The package fetches a model's files from the network the first time it is asked for them; this test never does:
it takes a robot from a local Menagerie checkout (``MENAGERIE_ROOT``) or the package's cache, and skips the robots
it finds in neither (the import needs only the XML: missing meshes are left out with a note)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from .test_cli import run

LEGGED = ("anybotics_anymal_b", "anybotics_anymal_c", "boston_dynamics_spot", "google_barkour_v0",
          "google_barkour_vb", "unitree_a1", "unitree_go1", "unitree_go2")
"""The registry's quadrupeds (category ``quadruped``; it has no hexapod)."""


def _local_xml(name: str) -> Path:
    """The robot's default model XML from a local checkout or the cache, else skip (no download)."""
    menagerie = pytest.importorskip("mujoco_menagerie")
    robot = menagerie.get(name)
    cache = menagerie.Cache()
    if cache.root is not None:
        folder = cache.root / name
    elif cache.is_cached(robot):
        folder = cache.model_path(robot)
    else:
        pytest.skip(f"{name} is neither under MENAGERIE_ROOT nor in the package's cache (it would be downloaded)")
    xml = Path(folder) / str(robot.entry(robot.default_model).file)
    if not xml.is_file():
        pytest.skip(f"{xml} is not there")
    return xml


def test_the_registry_lists_the_legged_robots_this_test_tries() -> None:
    menagerie = pytest.importorskip("mujoco_menagerie")
    assert {robot.name for robot in menagerie.robots("quadruped")} == set(LEGGED)


@pytest.mark.slow  # an import and 10 s of MuJoCo per robot
@pytest.mark.parametrize("name", LEGGED)
def test_a_menagerie_quadruped_imports_and_walks(name: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    xml = _local_xml(name)
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
