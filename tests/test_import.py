"""``shc import openshc``: OpenSHC's own YAML files become robots that compute exactly what ours do."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from shc_cli.spec.autopose import load_pose_set
from shc_cli.spec.loading import load_gait, load_robot

from .conftest import GOLDEN
from .test_cli import run

PAIRS = [("bullet_openshc", "bullet_insectoid"), ("bullet_mammalian", "bullet_mammalian"),
         ("openshc_default", "openshc_default")]


@pytest.mark.parametrize(("ours", "yaml_name"), PAIRS)
def test_imported_robots_have_our_workspaces(ours: str, yaml_name: str, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                             monkeypatch) -> None:
    """`workspace --json` of the imported robot equals that of the hand-written TOML (the robot's name aside)."""
    code, stdout, err = run(["import", "openshc", str(GOLDEN / "openshc" / f"{yaml_name}.yaml"),
                             str(GOLDEN / "openshc" / "gait.yaml"), "--out", str(tmp_path)], capsys, monkeypatch)
    assert code == 0, err
    imported = tmp_path / "robots" / f"{yaml_name}.toml"
    assert f"wrote {imported}" in stdout
    outputs = []
    for robot in (ours, str(imported)):
        code, stdout, err = run(["workspace", robot, "--json"], capsys, monkeypatch)
        assert code == 0, err
        data = json.loads(stdout)
        data.pop("robot")
        outputs.append(data)
    assert outputs[0] == outputs[1]


def test_legs_share_a_template_and_list_only_their_differences(tmp_path: Path) -> None:
    from shc_cli.interop.openshc import import_openshc

    robot_file = import_openshc(GOLDEN / "openshc" / "bullet_insectoid.yaml", None, None, tmp_path)[0]
    text = robot_file.read_text()
    assert "[templates.leg]" in text and "individual_control_interface" in text.splitlines()[1]
    import tomllib

    data = tomllib.loads(text)
    assert data["legs"]["BR"] == {"template": "leg", "base": {"r": 0.0}, "stance": {"x": -0.02, "y": -0.35}}
    assert data["legs"]["AR"]["joints"] == {"coxa": {"min": -1.571, "max": 1.571}}  # OpenSHC's AR coxa limits
    assert "base" not in data["legs"]["AR"]
    loaded = load_robot(robot_file).robot
    ours = load_robot("bullet_openshc").robot
    for leg_id, leg in ours.legs.items():  # every kinematic value as in our file
        mine = loaded.legs[leg_id]
        assert (mine.base, mine.stance) == (leg.base, leg.stance)
        for name, joint in leg.joints.items():
            assert mine.joints[name].model_dump(exclude={"mass"}) == joint.model_dump(exclude={"mass"})


def test_the_servo_map_is_numbered_like_bullets_and_marked_to_check(tmp_path: Path) -> None:
    """OpenSHC keeps its servo ids elsewhere: the import numbers them as robots/bullet.toml does (10 × leg +
    joint) and says they are to check."""
    from shc_cli.interop.openshc import import_openshc

    robot_file = import_openshc(GOLDEN / "openshc" / "bullet_insectoid.yaml", None, None, tmp_path)[0]
    assert "[hardware.servos] below is TO CHECK" in robot_file.read_text()
    ids = {key: servo.id for key, servo in load_robot(robot_file).robot.hardware.servos.items()}
    assert ids == {key: servo.id for key, servo in load_robot("bullet").robot.hardware.servos.items()}


def test_gaits_and_auto_pose_sets_equal_the_shipped_ones(tmp_path: Path) -> None:
    from shc_cli.interop.openshc import import_openshc

    files = import_openshc(GOLDEN / "openshc" / "bullet_insectoid.yaml", GOLDEN / "openshc" / "gait.yaml",
                           GOLDEN / "openshc" / "bullet_auto_pose.yaml", tmp_path)
    gaits = [f for f in files if f.parent.name == "gaits"]
    poses = [f for f in files if f.parent.name == "poses"]
    assert {f.stem for f in gaits} == {"wave", "tripod", "ripple", "amble", "bipod"}
    for path in gaits:
        mine, ours = load_gait(path).gait, load_gait(path.stem).gait
        assert mine is not None and ours is not None
        assert mine.model_dump(exclude={"description"}) == ours.model_dump(exclude={"description"})
    assert {f.stem for f in poses} >= {"wave", "tripod", "ripple", "amble", "bipod", "quad_wave"}
    for path in poses:
        shipped = "bullet_quad_wave" if path.stem == "quad_wave" else path.stem  # shc's own quad_wave is the sway
        mine_set, ours_set = load_pose_set(path).pose_set, load_pose_set(shipped).pose_set
        assert mine_set is not None and ours_set is not None
        assert mine_set.model_dump(exclude={"description", "name"}) == ours_set.model_dump(exclude={"description",
                                                                                               "name"})


@pytest.mark.parametrize(("text", "message"), [
    ("syropod:\n  parameters: [1, 2\n", "YAML syntax error"),
    ("other: 1\n", "no syropod.parameters"),
    ("syropod:\n  parameters:\n    time_delta: 0.01\n", "missing or malformed OpenSHC parameter"),
])
def test_bad_yaml_is_one_line(text: str, message: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    path = tmp_path / "robot.yaml"
    path.write_text(text)
    code, _, err = run(["import", "openshc", str(path), "--out", str(tmp_path / "out")], capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1 and message in err, err


def test_without_a_urdf_the_placeholder_masses_are_warned(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """OpenSHC's parameters carry no masses: the robot weighs shc's 1 kg placeholder, which the import says."""
    import logging

    from shc_cli.interop.openshc import import_openshc

    with caplog.at_level(logging.WARNING):
        robot_file = import_openshc(GOLDEN / "openshc" / "bullet_insectoid.yaml", None, None, tmp_path)[0]
    (warning,) = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert warning.startswith(f"warning: {robot_file}: OpenSHC's parameters carry no masses, so the robot weighs "
                              "shc's placeholder 1.00 kg") and "--urdf FILE" in warning
    assert load_robot(robot_file).robot.total_mass() == 1.0


def test_masses_come_from_the_xacro_beside_the_parameters(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """--urdf bullet.xacro: the masses of robots/bullet_openshc.toml, which were copied from it by hand (body 6 kg +
    6 base motors of 0.2 kg; coxa 0.2, coxat 0.2, femur 0.4, tibia 0.152, tarsus 0.076035 kg); no warning."""
    import sys

    from shc_cli.cli import main

    monkeypatch.setattr(sys, "argv", ["shc", "import", "openshc", str(GOLDEN / "openshc" / "bullet_insectoid.yaml"),
                                      "--urdf", str(GOLDEN / "bullet_syropod" / "robot" / "bullet.xacro"),
                                      "--out", str(tmp_path)])
    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 0, err
    assert "warning" not in err
    robot = load_robot(tmp_path / "robots" / "bullet_insectoid.toml").robot
    ours = load_robot("bullet_openshc").robot
    assert robot.body.mass == pytest.approx(7.2) == ours.body.mass
    for leg_id, leg in ours.legs.items():
        assert {name: j.mass for name, j in robot.legs[leg_id].joints.items()} == {
            name: j.mass for name, j in leg.joints.items()}
    assert robot.total_mass() == pytest.approx(ours.total_mass())


def test_a_urdf_of_another_robot_is_one_line(tmp_path: Path) -> None:
    from shc_cli.errors import SpecError
    from shc_cli.interop.openshc import import_openshc

    other = Path(__file__).parent / "data" / "robots" / "solo12_odri.urdf"
    with pytest.raises(SpecError) as raised:
        import_openshc(GOLDEN / "openshc" / "bullet_insectoid.yaml", None, None, tmp_path, urdf=other)
    assert str(raised.value) == (f"{other}: no joint AR_coxa_joint (or AR_coxa) for OpenSHC's AR coxa (give the URDF "
                                 "or xacro of the same robot)")
    assert not (tmp_path / "robots").exists()


def test_an_import_over_existing_files_needs_overwrite(tmp_path: Path) -> None:
    """The one output rule: a second import into the same folder is refused before anything is written (it replaced
    the robot file silently), and replaces it with --overwrite."""
    from shc_cli.errors import OutputError
    from shc_cli.interop.openshc import import_openshc

    source = GOLDEN / "openshc" / "bullet_insectoid.yaml", GOLDEN / "openshc" / "gait.yaml", None
    robot_file = import_openshc(*source, tmp_path)[0]
    robot_file.write_text(robot_file.read_text() + "# edited\n")
    with pytest.raises(OutputError) as raised:
        import_openshc(*source, tmp_path)
    assert str(raised.value) == (f"{robot_file}: already exists (add --overwrite to replace it and 5 more of the "
                                 "outputs, or choose another --out)")
    assert robot_file.read_text().endswith("# edited\n")
    assert import_openshc(*source, tmp_path, overwrite=True)[0] == robot_file
    assert not robot_file.read_text().endswith("# edited\n")
