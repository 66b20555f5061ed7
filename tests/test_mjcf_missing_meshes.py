"""``shc import mjcf`` of a file whose mesh files are not there (issue 37, point 11: a Menagerie robot copied
without its assets, or a repository whose large meshes did not come with it): the import reads no mesh, so it goes
on without them and says so in a note; the robot file is the one the complete file gives."""

from __future__ import annotations

from pathlib import Path

import pytest

from .conftest import ROOT
from .test_cli import run

QUADRUPED = ROOT / "tests" / "data" / "classes" / "mjcf_quadruped.xml"


def _legs_and_body(text: str) -> str:
    """The robot file without its header comments and notes (which name the source file)."""
    return "\n".join(line for line in text.splitlines() if not line.startswith("#"))


def test_a_missing_mesh_file_is_left_out_with_a_note(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("mujoco")
    text = QUADRUPED.read_text()
    meshed = text.replace('<compiler angle="radian"/>', '<compiler angle="radian" meshdir="assets"/>\n'
                          '  <asset><mesh name="trunk_mesh" file="trunk.stl"/><texture type="2d" name="skin" '
                          'file="skin.png"/><material name="skin" texture="skin"/></asset>', 1).replace(
        '<geom type="box" size="0.19 0.05 0.055"/>',
        '<geom type="box" size="0.19 0.05 0.055" material="skin"/>\n      <geom class="visual" type="mesh" '
        'mesh="trunk_mesh"/>', 1)
    assert meshed.count("trunk_mesh") == 2
    source = tmp_path / "mjcf_quadruped.xml"
    source.write_text(meshed)
    code, out, err = run(["import", "mjcf", str(source), "--out", str(tmp_path / "meshed")], capsys, monkeypatch)
    assert code == 0, err
    assert "note: a file it names is missing (assets/trunk.stl): loaded without its mesh geoms, meshes and textures" \
        in out, out
    assert "largest tip difference to MuJoCo's (mj_kinematics)" in out
    code, _, err = run(["import", "mjcf", str(QUADRUPED), "--out", str(tmp_path / "plain")], capsys, monkeypatch)
    assert code == 0, err
    ours = (tmp_path / "meshed" / "robots" / "mjcf_quadruped.toml").read_text()
    theirs = (tmp_path / "plain" / "robots" / "mjcf_quadruped.toml").read_text()
    assert _legs_and_body(ours) == _legs_and_body(theirs)


def test_a_file_mujoco_refuses_for_another_reason_is_still_one_line(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    pytest.importorskip("mujoco")
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><asset><mesh name='m' file='gone.stl'/></asset><worldbody><body>"
                      "<joint type='hinge' axis='0 0 0'/><geom type='mesh' mesh='m'/></body></worldbody></mujoco>")
    code, _, err = run(["import", "mjcf", str(broken), "--out", str(tmp_path / "b")], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "MuJoCo cannot load it" in err and "Traceback" not in err, err
    assert "gone.stl" not in err  # the reason it still fails without its meshes (the zero axis), not the mesh
