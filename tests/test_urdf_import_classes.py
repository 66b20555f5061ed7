"""``shc import urdf`` on the classes of description of issue 37 (tests/data/classes, one property each, made by
``make_classes.py`` there): each imports with no options, and its tips follow the source's own kinematics
(yourdfpy's forward kinematics of the file, the reference) at random joint vectors."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot

from .test_cli import run

pytest.importorskip("yourdfpy", reason="shc import urdf needs the 'urdf' extra")

CLASSES = Path(__file__).parent / "data" / "classes"
LEGS = ["fr", "mr", "rr", "rl", "ml", "fl"]


def _import(path: Path, out: Path, capsys, monkeypatch, *options: str) -> tuple[str, str, Path]:  # type: ignore[no-untyped-def]
    code, stdout, err = run(["import", "urdf", str(path), "--out", str(out), *options], capsys, monkeypatch)
    assert code == 0, err
    return stdout, err, next(iter((out / "robots").glob("*.toml")))


def _fk_worst(source: Path, robot_file: Path, tips: dict[str, tuple[str, tuple[float, float, float]]],
              base: str = "base_link", samples: int = 40, text: str | None = None) -> float:
    """Largest distance between the robot file's tips and yourdfpy's FK of ``source`` (or its ``text``) at random
    joint vectors inside the file's limits [m]; ``tips`` maps each leg's first URDF joint to its tip link and the
    tip point in that link (what the description means by the foot, written by the test)."""
    from shc_cli.interop.urdf_import_source import parse_urdf

    model = parse_urdf(source, text or source.read_text())
    robot = load_robot(robot_file).robot
    servos = robot.hardware.servos
    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(samples):
        q = rng.uniform(chains.lower, chains.upper)
        cfg = {name: 0.0 for name in model.actuated_joint_names}
        for i, (leg_id, spec) in enumerate(robot.legs.items()):
            for k, joint in enumerate(spec.joints):
                cfg[servos[f"{leg_id}_{joint}"].joint] = float(q[i, k])
        model.update_cfg(cfg)
        ours = chains.tips(q)
        for i, (leg_id, spec) in enumerate(robot.legs.items()):
            end, point = tips[str(servos[f"{leg_id}_{next(iter(spec.joints))}"].joint)]
            transform = np.asarray(model.get_transform(frame_to=end, frame_from=base), dtype=float)
            worst = max(worst, float(np.linalg.norm(ours[i] - (transform @ np.append(point, 1.0))[:3])))
    return worst


FEET = {f"{leg}_coxa_joint": (f"{leg}_foot", (0.0, 0.0, 0.0)) for leg in LEGS}
"""The made-up hexapods' feet: the centre of each foot link's sphere."""


def test_continuous_joints_are_revolute_with_a_whole_turn(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    path = CLASSES / "continuous_hexapod.urdf"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "18 leg joints are continuous in the URDF" in out and "-3.142 … 3.142 rad" in out
    data = tomllib.loads(robot_file.read_text())
    joints = data["templates"]["leg"]["joints"]
    # a whole turn, as far as the servo map's servo reaches with the zero in the middle of its ticks
    from shc_cli.interop.servo_map import servo_angle_range

    low, high = servo_angle_range(data["hardware"]["model"])
    assert all((j["min"], j["max"]) == (low, high) for j in joints.values())
    assert -math.pi <= low < -2.5 and 2.5 < high <= math.pi  # an AX-12A here: 300° about its middle
    assert _fk_worst(path, robot_file, FEET) < 1e-9


def test_rounded_rpy_values_are_snapped_and_the_tip_move_reported(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """1.57 for pi/2 and 3.14 for pi put the knee axis 0.0016 rad off the femur's: snapped without being asked;
    the tips follow the snapped file exactly and the written one within 0.0016 × 0.12 m (the tibia) + 0.0008 ×
    0.24 m (the leg)."""
    from shc_cli.interop.urdf_import_source import read_source

    path = CLASSES / "rounded_rpy_hexapod.urdf"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "0.0016 rad from parallel" in out and "snapped" in out and "m at most (accepted up to" in out, out
    tips = {f"{leg}_coxa_joint": (f"{leg}_foot", (0.0, 0.0, 0.0)) for leg in LEGS}
    assert _fk_worst(path, robot_file, tips, text=read_source(path, {}, 0.002).snapped_text) < 1e-9
    assert _fk_worst(path, robot_file, tips) < 0.0016 * 0.12 + 0.0008 * 0.24


def test_a_tip_on_the_knee_axis_is_the_far_end_of_the_tibias_geometry(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """No foot link and the tibia frame on the knee axis: the tip is the far end of the tibia's collision
    cylinder (0.12 m long, centred 0.06 m out along the tibia's x): (0.12, 0, 0) in the tibia's frame."""
    path = CLASSES / "rod_tibia_hexapod.urdf"
    _, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "collision or visual geometry farthest from its joint's axis" in robot_file.read_text()
    tips = {f"{leg}_coxa_joint": (f"{leg}_tibia", (0.12, 0.0, 0.0)) for leg in LEGS}
    assert _fk_worst(path, robot_file, tips) < 1e-9


def test_a_massless_spawn_root_far_from_the_body_is_not_the_base(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The root ``spawn`` has no mass and holds the body ``torso`` 1.2 m away: base_link is torso, where the legs
    meet; a ``--base`` link not in the body is one line (test_refusals_name_the_leg_and_the_limits: ``--base
    spawn``)."""
    path = CLASSES / "spawn_root_hexapod.urdf"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "base_link is torso, where the legs meet" in out and "URDF link 'torso'" in robot_file.read_text()
    data = tomllib.loads(robot_file.read_text())
    assert data["body"]["mass"] == 1.5 and data["body"]["size"] == [0.3, 0.2, 0.05]
    assert _fk_worst(path, robot_file, FEET, base="torso") < 1e-9
    code, _, err = run(["import", "urdf", str(path), "--out", str(tmp_path / "x"), "--base", "fr_tibia"], capsys,
                       monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "'fr_tibia' is not a link of the body" in err, err


def test_a_missing_package_in_a_ros2_control_parameter_is_a_note(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """``$(find my_hexapod_control)`` in a ros2_control and a Gazebo parameter, that package absent: the import
    goes on and says where it was left; an include from an absent package is still one line."""
    path = CLASSES / "ros2_control_hexapod.urdf.xacro"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "$(find my_hexapod_control): no folder 'my_hexapod_control'" in out
    assert "left as package://my_hexapod_control, in <param>, <parameters>" in out, out
    assert _fk_worst(path, robot_file, FEET, text=_expanded(path)) < 1e-9
    including = tmp_path / "including.urdf.xacro"
    including.write_text('<robot name="x" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                         '<xacro:include filename="$(find absent_description)/urdf/leg.xacro"/></robot>')
    code, _, err = run(["import", "urdf", str(including), "--out", str(tmp_path / "x")], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "$(find absent_description): no folder" in err, err


def _expanded(path: Path) -> str:
    """The xacro file expanded by xacro itself, ``$(find)`` of an absent package given as a plain string."""
    import xacro
    import xacro.substitution_args as substitution

    original = substitution._eval_find
    substitution._eval_find = lambda package: f"/absent/{package}"
    try:
        return str(xacro.process_file(str(path)).toprettyxml(indent="  "))
    finally:
        substitution._eval_find = original


def test_feet_hanging_off_the_root_by_floating_joints_are_the_tips(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A CAD export: the body and the six feet are children of the root by floating joints, each foot placed at
    its tibia's end (0.12 m along the tibia of a flat leg): the feet are the tips, (0.12, 0, 0) in each tibia's
    frame, the body starts at the chassis; a seventh floating link that ends no leg is one line naming it."""
    path = CLASSES / "detached_feet_hexapod.urdf"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "fixed, where they sit, to the leg ends nearest them (fr_foot → fr_tibia" in out, out
    tips = {f"{leg}_coxa_joint": (f"{leg}_tibia", (0.12, 0.0, 0.0)) for leg in LEGS}
    assert _fk_worst(path, robot_file, tips, base="chassis") < 1e-9
    data = tomllib.loads(robot_file.read_text())
    assert data["templates"]["leg"]["joints"]["tibia"]["mass"] == pytest.approx(0.07)  # the foot's 0.01 kg with it
    extra = tmp_path / "camera.urdf"
    extra.write_text(path.read_text().replace("</robot>", '<link name="camera"/><joint name="cam" type="floating">'
                                              '<parent link="root"/><child link="camera"/></joint></robot>'))
    code, _, err = run(["import", "urdf", str(extra), "--out", str(tmp_path / "cam")], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "link camera hangs off the root by floating joints" in err, err


def test_narrow_joint_limits_stand_where_the_joints_centres_put_the_feet(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                        monkeypatch) -> None:
    """Femur 0.2–0.9 rad down and knee 0.8–1.5 rad bent: no stance of the reach and height search stands, the
    feet where every joint is at the centre of its range do, with the swing height the limits allow."""
    path = CLASSES / "narrow_limits_hexapod.urdf"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "the feet where every joint is at the centre of its limits" in out, out
    assert "as high as every leg's joint limits lift the foot" in out, out
    assert _fk_worst(path, robot_file, FEET) < 1e-9
    data = tomllib.loads(robot_file.read_text())
    unpacked = [j["unpacked"] for j in data["templates"]["leg"]["joints"].values()]
    assert unpacked == pytest.approx([0.0, 0.55, 1.15], abs=2e-3)  # the centres of the ranges


@pytest.mark.parametrize(("name", "torque"), [("mjcf_hexapod", 1.5), ("mjcf_quadruped", 23.7)])
def test_mjcf_imports_with_mujocos_kinematics(name: str, torque: float, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                              monkeypatch) -> None:
    """``shc import mjcf``: two hinges in one body, euler and axis-angle frames and a knee ``ref`` (the hexapod);
    default classes, a childclass, straight legs at qpos0 and position actuators (the quadruped). Every foot
    sphere (MuJoCo's geom_xpos, in the trunk's frame) is where the robot file's chains put it at random joint
    vectors (angles from MuJoCo's qpos0); the effort is the motor's ctrlrange × gear (1 × 1.5), or the
    position actuators' forcerange (the most common, 23.7); a file MuJoCo refuses is one line."""
    mujoco = pytest.importorskip("mujoco")
    path = CLASSES / f"{name}.xml"
    code, out, err = run(["import", "mjcf", str(path), "--out", str(tmp_path)], capsys, monkeypatch)
    assert code == 0, err
    assert "largest tip difference to MuJoCo's (mj_kinematics)" in out
    robot_file = tmp_path / "robots" / f"{name}.toml"
    assert robot_file.read_text().startswith(f"# Imported by `shc import mjcf` from {name}.xml")
    robot = load_robot(robot_file).robot
    chains = Chains.from_robot(robot)
    data = tomllib.loads(robot_file.read_text())
    assert data["servo"]["stall_torque"] == torque
    model = mujoco.MjModel.from_xml_path(str(path))
    state = mujoco.MjData(model)
    rng = np.random.default_rng(5)
    trunk = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "trunk")
    worst = 0.0
    for _ in range(40):
        q = rng.uniform(chains.lower, chains.upper)
        state.qpos[:] = model.qpos0
        feet = []
        for i, (leg_id, spec) in enumerate(robot.legs.items()):
            for k, joint in enumerate(spec.joints):
                index = model.joint(str(robot.hardware.servos[f"{leg_id}_{joint}"].joint)).qposadr[0]
                state.qpos[index] = model.qpos0[index] + q[i, k]
            feet.append(str(robot.hardware.servos[f"{leg_id}_{next(iter(spec.joints))}"].joint).split("_")[0])
        mujoco.mj_kinematics(model, state)
        rotation, origin = state.xmat[trunk].reshape(3, 3), state.xpos[trunk]
        theirs = [rotation.T @ (state.geom(f"{leg}_foot").xpos - origin) for leg in feet]
        worst = max(worst, float(np.abs(chains.tips(q) - np.array(theirs)).max()))
    assert worst < 1e-9
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body><joint type='hinge' axis='0 0 0'/></body></worldbody></mujoco>")
    code, _, err = run(["import", "mjcf", str(broken), "--out", str(tmp_path / "b")], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "MuJoCo cannot load it" in err, err


def test_a_stance_with_knees_below_the_feet_is_not_chosen(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The zero pose stands with every knee 45 mm below its foot (femur 1.2 rad down, tibia 0.6 rad up): the
    zero-pose candidates put the knees in the ground, so the stance comes from the search, every joint above the
    feet (the robot file's own chains at its unpacked pose)."""
    path = CLASSES / "low_knees_hexapod.urdf"
    out, _, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert "zero pose" not in out.splitlines()[0], out
    robot = load_robot(robot_file).robot
    chains = Chains.from_robot(robot)
    unpacked = np.array([[joint.unpacked for joint in leg.joints.values()] for leg in robot.legs.values()])
    frames = chains.frames_in_base(unpacked[None])[0]
    assert np.allclose(frames[:, -1, 2, 3], -robot.walker.body_clearance, atol=1e-4)
    assert (frames[:, 1:-1, 2, 3] >= -robot.walker.body_clearance - 1e-4).all()
    assert _fk_worst(path, robot_file, FEET) < 1e-9


def test_import_urdf_given_an_mjcf_file_imports_it_as_mjcf(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The file says what it is: a ``<mujoco>`` file given to ``shc import urdf`` goes through the MJCF import."""
    pytest.importorskip("mujoco")
    code, out, err = run(["import", "urdf", str(CLASSES / "mjcf_quadruped.xml"), "--out", str(tmp_path)], capsys,
                         monkeypatch)
    assert code == 0, err
    assert "is MJCF (a <mujoco> file)" in out and "largest tip difference to MuJoCo's" in out, out
    text = (tmp_path / "robots" / "mjcf_quadruped.toml").read_text()
    assert text.startswith("# Imported by `shc import mjcf` from mjcf_quadruped.xml")


@pytest.mark.slow  # each searches every stance before refusing
def test_refusals_name_the_leg_and_the_limits(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Limits narrower still (femur 0.45–0.65, knee 1.1–1.3: no foot lifts 1 cm) and the spawn frame kept as the
    base (``--base spawn``: the hips 0.4 m above it) find no stance: one line naming the leg and the limits."""
    path = CLASSES / "narrow_limits_hexapod.urdf"
    narrower = tmp_path / "narrower.urdf"
    narrower.write_text(path.read_text().replace('lower="0.2" upper="0.9"', 'lower="0.45" upper="0.65"')
                        .replace('lower="0.8" upper="1.5"', 'lower="1.1" upper="1.3"'))
    code, _, err = run(["import", "urdf", str(narrower), "--out", str(tmp_path / "n")], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "nor where poses across the joint ranges put them" in err, err
    assert "femur at its lower limit 0.45 rad, tibia at its upper limit 1.3 rad" in err, err
    code, _, err = run(["import", "urdf", str(CLASSES / "spawn_root_hexapod.urdf"), "--out", str(tmp_path / "s"),
                        "--base", "spawn"], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "no standing pose found" in err and "limit" in err, err


@pytest.mark.slow  # imports and walks 10 s in MuJoCo
@pytest.mark.parametrize(("name", "share"), [("continuous_hexapod", 0.6), ("rounded_rpy_hexapod", 0.6),
                                           ("rod_tibia_hexapod", 0.6), ("spawn_root_hexapod", 0.6),
                                           ("detached_feet_hexapod", 0.6), ("ros2_control_hexapod.urdf", 0.6),
                                           ("narrow_limits_hexapod", 0.6), ("mjcf_hexapod", 0.6),
                                           ("low_knees_hexapod", 0.6), ("mjcf_quadruped", 0.6)])
def test_each_class_walks_10_s(name: str, share: float, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    if name.startswith("mjcf"):
        code, _, err = run(["import", "mjcf", str(CLASSES / f"{name}.xml"), "--out", str(tmp_path)], capsys,
                           monkeypatch)
        assert code == 0, err
        robot_file = tmp_path / "robots" / f"{name}.toml"
    else:
        suffix = ".xacro" if name.endswith(".urdf") else ".urdf"
        _, _, robot_file = _import(CLASSES / f"{name}{suffix}", tmp_path, capsys, monkeypatch)
    code, _, err = run(["simulate", str(robot_file), "--duration", "10", "--no-plots", "--out",
                        str(tmp_path / "sim")], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((tmp_path / "sim" / "summary.json").read_text())
    assert not summary["fell"] and summary["complete"], summary
    assert summary["walked_share"] >= share and summary["max_tilt_rad"] < 0.2, summary
