"""``shc import urdf``: URDF and xacro legs become DH chains with the URDF's forward kinematics.

The reference for every tip position is yourdfpy's own forward kinematics of the URDF (its scene graph), or
for the Bullet xacro, our hand-written ``robots/bullet_openshc.toml`` (from CSIRO's OpenSHC configuration).
"""

from __future__ import annotations

import json
import math
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot
from shc_cli.spec.robot import Robot

from .conftest import GOLDEN
from .test_cli import run
from .urdf_robots import Element, LegSpec, dog_leg, insect_leg, robot_urdf

pytest.importorskip("yourdfpy", reason="shc import urdf needs the 'urdf' extra")
pytest.importorskip("xacro", reason="shc import urdf needs the 'urdf' extra")

BULLET_XACRO = GOLDEN / "bullet_syropod" / "robot" / "bullet.xacro"
BULLET_TIP = "*_tarsus_link@0.173,0,0"
"""OpenSHC's tarsus length (bullet_insectoid.yaml): the URDF's tarsus mesh has no tip frame of its own."""


def _yourdfpy_tips(model, base: str, ends: list[str], points: list[np.ndarray],  # type: ignore[no-untyped-def]
                   cfg: dict[str, float]) -> np.ndarray:
    model.update_cfg({name: cfg.get(name, 0.0) for name in model.actuated_joint_names})
    out = []
    for end, point in zip(ends, points, strict=True):
        transform = np.asarray(model.get_transform(frame_to=end, frame_from=base))
        out.append((transform @ np.append(point, 1.0))[:3])
    return np.array(out)


def _chains(tree: dict) -> Chains:  # type: ignore[type-arg]
    legs = {leg_id: {**spec, "stance": {"x": 0.0, "y": 0.0}} for leg_id, spec in tree["legs"].items()}
    return Chains.from_robot(Robot.model_validate({**tree, "legs": legs}))


def _import_text(text: str, tmp_path: Path, **options):  # type: ignore[no-untyped-def]
    from shc_cli.interop.urdf_import import import_tree
    from shc_cli.interop.urdf_import_source import parse_urdf
    from shc_cli.interop.urdf_import_tree import TipSpec

    path = tmp_path / "robot.urdf"
    path.write_text(text)
    model = parse_urdf(path, text)
    tips = [TipSpec.parse(t) for t in options.pop("tips", [])]
    return model, import_tree(model, path, "made_up", tips=tips, **options)


def _fk_difference(model, imported, rng: np.random.Generator, samples: int = 5) -> float:  # type: ignore[no-untyped-def]
    chains = _chains(imported.tree)
    worst = 0.0
    for _ in range(samples):
        q = rng.uniform(chains.lower, chains.upper)
        cfg = {joint.name: float(q[i, k]) for i, leg in enumerate(imported.legs)
               for k, joint in enumerate(leg.joints)}
        theirs = _yourdfpy_tips(model, imported.base_frame, [leg.end for leg in imported.legs],
                                [leg.tip_local for leg in imported.legs], cfg)
        worst = max(worst, float(np.abs(chains.tips(q) - theirs).max()))
    return worst


# -- property test: random chains ------------------------------------------------------------------------------

NICE = [0.0, math.pi / 2, -math.pi / 2, math.pi]
angles = st.one_of(st.sampled_from(NICE), st.floats(-3.1, 3.1).filter(
    lambda a: abs(a - round(a / (math.pi / 2)) * (math.pi / 2)) > 0.05))
lengths = st.one_of(st.just(0.0), st.floats(-0.15, 0.15))
unit_axes = st.one_of(
    st.sampled_from([(1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0), (0.0, 0.0, -1.0), (-1.0, 0.0, 0.0)]),
    st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: math.hypot(*v) > 0.3))


@st.composite
def chains(draw: st.DrawFn, name: str) -> LegSpec:
    """A leg of 1–6 revolute joints with any origins and axes, 0–2 fixed joints before each."""
    elements = []
    for _ in range(draw(st.integers(1, 6))):
        for _ in range(draw(st.integers(0, 2))):
            elements.append(Element("fixed", draw(st.tuples(lengths, lengths, lengths)),
                                    draw(st.tuples(angles, angles, angles))))
        low, high = draw(st.floats(-2.5, -0.1)), draw(st.floats(0.1, 2.5))
        elements.append(Element("revolute", draw(st.tuples(lengths, lengths, lengths)),
                                draw(st.tuples(angles, angles, angles)), draw(unit_axes), low, high))
    if draw(st.booleans()):
        elements.append(Element("fixed", draw(st.tuples(lengths, lengths, lengths)),
                                draw(st.tuples(angles, angles, angles))))
    sphere = draw(st.one_of(st.none(), st.tuples(lengths, lengths, lengths)))
    return LegSpec(name, elements, sphere=sphere)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(legs=st.lists(st.sampled_from(["p", "q", "r"]), min_size=1, max_size=3, unique=True).flatmap(
    lambda names: st.tuples(*[chains(name) for name in names])), seed=st.integers(0, 2**31))
@pytest.mark.slow  # FK of many random URDF chains (property test)
def test_random_chains_have_the_urdfs_forward_kinematics(legs: tuple[LegSpec, ...], seed: int,
                                                         tmp_path: Path) -> None:
    """Non-DH axes, rpy offsets, fixed joints between: every tip within 1e-6 m of yourdfpy's, inside the limits.
    Random axes sometimes come out nearly parallel (CI drew two 0.0083 rad apart): the import then refuses with the
    --snap that fixes it, which is right for such a chain (its DH table would need offsets of metres), not a
    failure; the refusal must name a small angle."""
    from hypothesis import reject

    from shc_cli.interop.urdf_import import NeedsSnap

    try:
        model, imported = _import_text(robot_urdf(list(legs)), tmp_path)
    except NeedsSnap as refusal:
        assert 0.0 < refusal.snap <= 0.1 and "from parallel" in refusal.problem, refusal.problem
        reject()
    assert len(imported.legs) == len(legs)
    assert _fk_difference(model, imported, np.random.default_rng(seed)) < 1e-6


@settings(max_examples=15, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture,
                                                                  HealthCheck.too_slow])
@given(leg=chains("p"), seed=st.integers(0, 2**31))
def test_random_chains_have_pybullets_forward_kinematics(leg: LegSpec, seed: int, tmp_path: Path) -> None:
    """The same, against PyBullet's forward kinematics of the URDF (link frames relative to base_link); a nearly
    parallel pair of random axes is refused with its --snap, as above."""
    import pybullet
    from hypothesis import reject

    from shc_cli.interop.urdf_import import NeedsSnap

    text = robot_urdf([leg])
    try:
        _, imported = _import_text(text, tmp_path)
    except NeedsSnap as refusal:
        assert 0.0 < refusal.snap <= 0.1 and "from parallel" in refusal.problem, refusal.problem
        reject()
    (tmp_path / "robot.urdf").write_text(text)
    client = pybullet.connect(pybullet.DIRECT)
    try:
        body = pybullet.loadURDF(str(tmp_path / "robot.urdf"), useFixedBase=True, physicsClientId=client)
        index = {pybullet.getJointInfo(body, i, physicsClientId=client)[12].decode(): i
                 for i in range(pybullet.getNumJoints(body, physicsClientId=client))}
        joint_index = {pybullet.getJointInfo(body, i, physicsClientId=client)[1].decode(): i for i in index.values()}
        chains_ = _chains(imported.tree)
        rng = np.random.default_rng(seed)
        chain = imported.legs[0]
        for _ in range(5):
            q = rng.uniform(chains_.lower, chains_.upper)
            for k, joint in enumerate(chain.joints):
                pybullet.resetJointState(body, joint_index[joint.name], float(q[0, k]), physicsClientId=client)

            def frame(link: str) -> np.ndarray:
                state = pybullet.getLinkState(body, index[link], computeForwardKinematics=True,
                                              physicsClientId=client)
                out = np.eye(4)
                out[:3, :3] = np.reshape(pybullet.getMatrixFromQuaternion(state[5]), (3, 3))
                out[:3, 3] = state[4]
                return out

            tip = np.linalg.inv(frame("base_link")) @ frame(chain.end) @ np.append(chain.tip_local, 1.0)
            assert np.abs(chains_.tips(q)[0] - tip[:3]).max() < 1e-6
    finally:
        pybullet.disconnect(client)


def test_tip_is_the_leaf_sphere_centre_else_its_origin(tmp_path: Path) -> None:
    with_sphere = LegSpec("p", [Element("revolute", (0.1, -0.1, 0.0))], sphere=(0.2, 0.0, -0.05), radius=0.02)
    without = LegSpec("q", [Element("revolute", (0.1, 0.1, 0.0)), Element("fixed", (0.3, 0.0, 0.0))])
    _, imported = _import_text(robot_urdf([with_sphere, without]), tmp_path)
    tips = {leg.end: leg.tip for leg in imported.legs}
    assert np.allclose(tips["p_link0"], [0.3, -0.1, -0.05]) and np.allclose(tips["q_link1"], [0.4, 0.1, 0.0])
    radii = {leg.end: leg.sphere for leg in imported.legs}
    assert radii == {"p_link0": 0.02, "q_link1": 0.0}


# -- leg ids, names, masses -------------------------------------------------------------------------------------


@pytest.mark.parametrize(("count", "expected"), [
    (4, ["AR", "BR", "BL", "AL"]),
    (6, ["AR", "BR", "CR", "CL", "BL", "AL"]),
    (8, ["AR", "BR", "CR", "DR", "DL", "CL", "BL", "AL"]),
])
def test_leg_ids_by_position_clockwise_from_front_right(count: int, expected: list[str], tmp_path: Path) -> None:
    half = count // 2
    xs = np.linspace(0.15, -0.15, half)
    # URDF order scrambled: left legs first, rear to front; each leg named after its true place
    specs = [insect_leg(f"{'LR'[side]}{i}", float(x), 0.1 if side == 0 else -0.1, standing=True)
             for side in (0, 1) for i, x in reversed(list(enumerate(xs)))]
    _, imported = _import_text(robot_urdf(specs), tmp_path)
    assert [leg.leg_id for leg in imported.legs] == expected
    places = [f"{'L' if leg.end.startswith('L') else 'R'}{leg.end[1]}" for leg in imported.legs]
    right = [f"R{i}" for i in range(half)]
    assert places == right + [f"L{i}" for i in reversed(range(half))]
    assert list(imported.tree["legs"]) == expected


def test_joint_names_drop_what_a_legs_joints_share() -> None:
    from shc_cli.interop.urdf_import_tree import joint_names

    assert joint_names([["AR_coxa_joint", "AR_femur_joint"], ["AL_coxa_joint", "AL_femur_joint"]]) == \
        [["coxa", "femur"], ["coxa", "femur"]]
    assert joint_names([["FR_hip", "FR_thigh", "FR_calf"]]) == [["hip", "thigh", "calf"]]
    assert joint_names([["leg_1_j_1", "leg_1_j_2"]]) == [["joint1", "joint2"]]


def test_masses_go_to_the_joint_that_moves_them_and_fixed_links_to_the_body(tmp_path: Path) -> None:
    leg = insect_leg("R0", 0.1, -0.1, standing=True)
    _, imported = _import_text(robot_urdf([leg], body_mass=2.5), tmp_path)
    joints = imported.tree["legs"][imported.legs[0].leg_id]["joints"]
    # the foot link (fixed to the tibia) adds its 0.01 kg to the tibia's 0.06 kg
    assert [j["mass"] for j in joints.values()] == pytest.approx([0.05, 0.08, 0.07])
    assert imported.tree["body"]["mass"] == 2.5 and imported.tree["body"]["size"] == [0.3, 0.2, 0.05]
    assert imported.tree["servo"]["stall_torque"] == 5.0 and joints["joint2"]["max_vel"] == 4.0


# -- whole robots through the command -----------------------------------------------------------------------------


def test_quadruped_standing_at_its_zero_pose_imports_validates_and_plans(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                         monkeypatch) -> None:
    specs = [insect_leg(f"leg{i}", x, y, standing=True)
             for i, (x, y) in enumerate([(0.12, -0.08), (-0.12, -0.08), (-0.12, 0.08), (0.12, 0.08)])]
    urdf = tmp_path / "quad.urdf"
    urdf.write_text(robot_urdf(specs, name="quad"))
    code, out, err = run(["import", "urdf", str(urdf), "--out", str(tmp_path / "out")], capsys, monkeypatch)
    assert code == 0, err
    robot_file = tmp_path / "out" / "robots" / "quad.toml"
    assert f"wrote {robot_file}" in out and "the URDF's zero pose" in out
    data = tomllib.loads(robot_file.read_text())
    assert data["walker"]["body_clearance"] == pytest.approx(0.12)  # the feet 0.12 m below the hips at q = 0
    assert data["legs"]["AR"]["stance"]["y"] < 0 and data["legs"]["AL"]["stance"]["y"] > 0
    assert "joint1" in data["templates"]["leg"]["joints"]
    code, _, err = run(["validate", str(robot_file)], capsys, monkeypatch)
    assert code == 0, err
    code, out, err = run(["plan", str(robot_file), "--duration", "3", "--no-plots", "--out",
                          str(tmp_path / "run")], capsys, monkeypatch)
    assert code == 0, err
    assert "IK deviations 0" in out


def test_dog_with_straight_legs_and_a_free_root_stands_lower_and_plans(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                     monkeypatch) -> None:
    """Legs straight down at the zero pose (a singular pose, and outside the knee limits): the body is lowered to
    the largest walkspace; a 'world' root holding the robot by a floating joint is skipped."""
    specs = [dog_leg(f"{name}", x, y) for name, x, y in
             [("FR", 0.19, -0.05), ("RR", -0.19, -0.05), ("RL", -0.19, 0.05), ("FL", 0.19, 0.05)]]
    text = robot_urdf(specs, name="dog").replace(
        '<link name="root_link"/>', '<link name="world"/><joint name="free" type="floating"><parent link="world"/>'
        '<child link="root_link"/></joint><link name="root_link"/>')
    urdf = tmp_path / "dog.urdf"
    urdf.write_text(text)
    code, out, err = run(["import", "urdf", str(urdf), "--out", str(tmp_path)], capsys, monkeypatch)
    assert code == 0, err
    assert "the body lowered to 0.7 of their depth" in out and "holds the robot by a free joint" in out
    data = tomllib.loads((tmp_path / "robots" / "dog.toml").read_text())
    assert data["walker"]["body_clearance"] == pytest.approx(0.28)  # 0.9 and 0.8 of 0.4 m: smaller walkspaces
    assert data["walker"]["gait"] == "quad_wave"
    assert list(data["legs"]) == ["AR", "BR", "BL", "AL"]
    assert list(data["templates"]["leg"]["joints"]) == ["joint0", "joint1", "joint2"]
    assert _servo_rows(tmp_path / "robots" / "dog.toml")[:4] == \
        [("FR_joint0", "AR", "joint0", 11), ("FR_joint1", "AR", "joint1", 12), ("FR_joint2", "AR", "joint2", 13),
         ("RR_joint0", "BR", "joint0", 21)]
    assert "[hardware.servos] below is TO CHECK" in (tmp_path / "robots" / "dog.toml").read_text()
    code, out, err = run(["plan", str(tmp_path / "robots" / "dog.toml"), "--duration", "3", "--no-plots", "--out",
                          str(tmp_path / "run")], capsys, monkeypatch)
    assert code == 0, err
    assert "IK deviations 0" in out


def test_legs_named_and_ordered_by_hand_and_xacro_arguments(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """`--legs ID=LINK,…` gives ids and order; `--arg NAME=VALUE` reaches the xacro; xacro errors are one line."""
    specs = [insect_leg(f"leg{i}", x, y, standing=True)
             for i, (x, y) in enumerate([(0.12, -0.08), (-0.12, -0.08), (-0.12, 0.08), (0.12, 0.08)])]
    body = robot_urdf(specs, name="quad").split("\n", 2)[2].replace("</robot>", "")
    xacro_file = tmp_path / "quad.xacro"
    xacro_file.write_text('<?xml version="1.0"?>\n<robot name="$(arg name)" xmlns:xacro="http://www.ros.org/wiki/xacro">'
                          '<xacro:arg name="name" default="quad"/>\n' + body + "</robot>\n")
    legs = "FL=leg3_link3,FR=leg0_link3,RR=leg1_link3,RL=leg2_link3"  # not the automatic ids, nor their order
    code, out, err = run(["import", "urdf", str(xacro_file), "--out", str(tmp_path), "--arg", "name=fido",
                          "--legs", legs], capsys, monkeypatch)
    assert code == 0, err
    assert "walker.gait 'quad_wave' names legs AR, BR, BL, AL, not these" in out
    rows = _servo_rows(tmp_path / "robots" / "fido.toml")
    assert [row[1] for row in rows[::3]] == ["FL", "FR", "RR", "RL"]
    assert [row[0] for row in rows[::3]] == ["leg3_joint0", "leg0_joint0", "leg1_joint0", "leg2_joint0"]
    assert list(tomllib.loads((tmp_path / "robots" / "fido.toml").read_text())["legs"]) == ["FL", "FR", "RR", "RL"]
    xacro_file.write_text(xacro_file.read_text().replace("$(arg name)", "${undefined_thing}"))
    code, _, err = run(["import", "urdf", str(xacro_file), "--out", str(tmp_path / "bad")], capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1 and "xacro:" in err and "undefined_thing" in err, err


def test_flat_hexapod_gets_a_standing_pose_it_reaches(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    specs = [insect_leg(f"leg{i}", x, y, standing=False)
             for i, (x, y) in enumerate([(0.12, -0.08), (0.0, -0.1), (-0.12, -0.08),
                                         (-0.12, 0.08), (0.0, 0.1), (0.12, 0.08)])]
    urdf = tmp_path / "hex.urdf"
    urdf.write_text(robot_urdf(specs, name="hex"))
    code, out, err = run(["import", "urdf", str(urdf), "--out", str(tmp_path)], capsys, monkeypatch)
    assert code == 0, err
    assert "out from the hips" in out
    code, out, err = run(["import", "urdf", str(urdf), "--out", str(tmp_path), "--name", "hex2",
                          "--clearance", "0.1", "--reach", "0.6"], capsys, monkeypatch)
    assert code == 0, err
    data = tomllib.loads((tmp_path / "robots" / "hex2.toml").read_text())
    assert data["walker"]["body_clearance"] == 0.1
    assert math.hypot(data["legs"]["BR"]["stance"]["x"], data["legs"]["BR"]["stance"]["y"] + 0.1) == \
        pytest.approx(0.6 * 0.24, abs=1e-4)


# -- the Bullet xacro ---------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def bullet_import(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, object]:
    from shc_cli.interop.urdf_import import import_urdf

    out = tmp_path_factory.mktemp("bullet")
    return out, import_urdf(BULLET_XACRO, out, tips=[BULLET_TIP])


def _servo_rows(robot_file: Path) -> list[tuple[str, str, str, int]]:
    """``(urdf_joint, leg, joint, id)`` of each [hardware.servos] entry an import wrote, in file order."""
    servos = tomllib.loads(robot_file.read_text())["hardware"]["servos"]
    return [(entry["joint"], *key.split("_", 1), entry["id"]) for key, entry in servos.items()]


def _through_servo_map(robot_file: Path, ours: Robot, imported: Robot, q: np.ndarray) -> np.ndarray:
    """Joint angles of robots/bullet_openshc.toml → the imported robot's, through [hardware.servos]'s URDF joint names
    (OpenSHC drives the URDF joints ``LEG_JOINT_joint`` with its own angles; a URDF angle is the shc angle)."""
    rows = _servo_rows(robot_file)
    assert len(rows) == 30
    mapped = np.zeros_like(q)
    for urdf_joint, leg_id, joint, _ in rows:
        leg, name = urdf_joint.removesuffix("_joint").split("_")
        mapped[..., list(imported.legs).index(leg_id), list(imported.legs[leg_id].joints).index(joint)] = \
            q[..., list(ours.legs).index(leg), list(ours.legs[leg].joints).index(name)]
    return mapped


def test_bullet_xacro_matches_the_urdf_exactly(bullet_import) -> None:  # type: ignore[no-untyped-def]
    _, result = bullet_import
    assert result.fk_error < 1e-9 and result.snap == 0.0  # to the URDF as written (1.5708, not pi/2)


def test_bullet_xacro_gives_bullet_toml_tips(bullet_import) -> None:  # type: ignore[no-untyped-def]
    """Same joint angles, same tips: within 10.5 mm, the differences of CSIRO's OpenSHC parameters from its URDF;
    with those values replaced by the URDF's, within 1e-5 m."""
    _, result = bullet_import
    ours, imported = load_robot("bullet_openshc").robot, load_robot(result.robot_path).robot
    assert ours is not None and imported is not None
    assert list(imported.legs) == list(ours.legs)
    rng = np.random.default_rng(7)
    mine = Chains.from_robot(ours)
    q = rng.uniform(np.maximum(mine.lower, -2.4), np.minimum(mine.upper, 2.4), size=(200, *mine.lower.shape))
    theirs = Chains.from_robot(imported)
    mapped = _through_servo_map(result.robot_path, ours, imported, q)
    worst = max(float(np.linalg.norm(mine.tips(a) - theirs.tips(b), axis=1).max())
                for a, b in zip(q, mapped, strict=True))
    assert 0.009 < worst < 0.0105
    # bullet_insectoid.yaml rounds the URDF: base d 0.051 (URDF 0.0505), coxa d 0.195 (0.0457 + 0.145), coxa r
    # -0.047 (-0.04678), coxat d -0.060 (-0.06024), coxat r 0.035 (0.02898), and pi/2 as 1.571. What remains is
    # the URDF's own 1.5708 for pi/2 in several rpy values (3.7e-6 rad each, over 0.6 m of leg): 4.2e-6 m.
    legs = {}
    for leg_id, leg in ours.legs.items():
        side = 1.0 if leg_id.endswith("R") else -1.0
        joints = dict(leg.joints)
        joints["coxa"] = joints["coxa"].model_copy(update={"d": 0.1907, "r": -0.04678, "alpha": -side * math.pi / 2})
        joints["coxat"] = joints["coxat"].model_copy(update={"d": -0.06024, "r": 0.02898, "alpha": math.pi / 2,
                                                             "theta": -side * math.pi / 2})
        legs[leg_id] = leg.model_copy(update={"joints": joints, "base": leg.base.model_copy(
            update={"d": 0.0505, "alpha": side * math.pi / 2})})
    corrected = Chains.from_robot(ours.model_copy(update={"legs": legs}))
    worst = max(float(np.abs(corrected.tips(a) - theirs.tips(b)).max()) for a, b in zip(q, mapped, strict=True))
    assert worst < 1e-5


def test_our_own_exported_urdf_comes_back_as_the_robot(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """`shc export urdf bullet` imported: the same legs, joint names, tips (to 1e-9 m), masses and limits."""
    urdf = tmp_path / "bullet.urdf"
    code, _, err = run(["export", "urdf", "bullet_openshc", "--out", str(urdf)], capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run(["import", "urdf", str(urdf), "--out", str(tmp_path)], capsys, monkeypatch)
    assert code == 0, err
    written = (tmp_path / "robots" / "bullet_openshc.toml").read_text()
    assert "the centre of its leg's last link's collision sphere" in written
    ours, back = load_robot("bullet_openshc").robot, load_robot(tmp_path / "robots" / "bullet_openshc.toml").robot
    assert ours is not None and back is not None
    assert list(back.legs) == list(ours.legs)
    assert [list(leg.joints) for leg in back.legs.values()] == [list(leg.joints) for leg in ours.legs.values()]
    mine, theirs = Chains.from_robot(ours), Chains.from_robot(back)
    assert np.array_equal(mine.lower, theirs.lower) and np.array_equal(mine.upper, theirs.upper)
    q = np.random.default_rng(3).uniform(mine.lower, mine.upper, size=(100, *mine.lower.shape))
    assert max(float(np.abs(mine.tips(x) - theirs.tips(x)).max()) for x in q) < 1e-9
    assert back.body.mass == ours.body.mass and back.legs["AR"].foot_radius == ours.legs["AR"].foot_radius
    # every link's mass comes back; the foot sphere's 1 g (FOOT_MASS) rides on the last joint
    assert [j.mass for j in back.legs["CL"].joints.values()] == \
        pytest.approx([0.2, 0.2, 0.4, 0.152, 0.076035 + 0.001])
    assert back.servo.stall_torque == ours.servo.stall_torque


def test_bullet_import_masses_and_limits(bullet_import) -> None:  # type: ignore[no-untyped-def]
    _, result = bullet_import
    imported, ours = load_robot(result.robot_path).robot, load_robot("bullet_openshc").robot
    assert imported is not None and ours is not None
    assert imported.body.mass == pytest.approx(ours.body.mass)  # 6.0 kg box + 6 x 0.2 kg base motors
    assert imported.total_mass() == pytest.approx(ours.total_mass())
    assert imported.servo.stall_torque == 8.4
    joint = imported.legs["AR"].joints["femur"]
    assert (joint.min, joint.max, joint.max_vel) == (-2.4, 2.4, 2.35619449)


@pytest.mark.slow  # imports, searches workspaces and walks
def test_bullet_import_validates_has_a_workspace_and_walks(bullet_import, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                  monkeypatch) -> None:
    _, result = bullet_import
    code, out, err = run(["validate", str(result.robot_path)], capsys, monkeypatch)
    assert code == 0, err
    assert "6 legs, 5 DOF per leg" in out
    code, out, err = run(["workspace", str(result.robot_path), "--json"], capsys, monkeypatch)
    assert code == 0, err
    walkspace = json.loads(out)["walkspace"]
    assert min(walkspace.values()) > 0.1  # m, every bearing
    code, out, err = run(["plan", str(result.robot_path), "--duration", "3", "--no-plots", "--out",
                          str(tmp_path / "plan")], capsys, monkeypatch)
    assert code == 0, err
    assert "IK deviations 0" in out
    code, out, err = run(["simulate", str(result.robot_path), "--duration", "3", "--no-plots", "--out",
                          str(tmp_path / "sim")], capsys, monkeypatch)
    assert code == 0, err
    distance = float(out.split("distance ")[1].split(" m")[0])
    assert distance > 0.2  # the controller asks for 0.167 m/s


def test_flat_copy_of_a_package_resolves_includes_beside_the_file(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                  monkeypatch) -> None:
    """A copy of the package's files in one folder: robot/macros.xacro is found beside bullet.xacro; $(find
    bullet_syropod) is the folder named so above the file. Renamed, the package is found nowhere: the include is
    still found beside the file, and the meshes left as package://bullet_syropod are named in a note."""
    flat = tmp_path / "bullet_syropod"
    flat.mkdir()
    for name in ("bullet.xacro", "macros.xacro"):
        shutil.copy(BULLET_XACRO.parent / name, flat / name)
    code, _, err = run(["import", "urdf", str(flat / "bullet.xacro"), "--out", str(tmp_path / "out"), "--tip",
                        BULLET_TIP, "--name", "bullet_flat"], capsys, monkeypatch)
    assert code == 0, err
    assert (tmp_path / "out" / "robots" / "bullet_flat.toml").is_file()
    renamed = tmp_path / "elsewhere"
    flat.rename(renamed)
    code, out, err = run(["import", "urdf", str(renamed / "bullet.xacro"), "--out", str(tmp_path / "out2"),
                          "--tip", BULLET_TIP], capsys, monkeypatch)
    assert code == 0, err
    assert "$(find bullet_syropod): no folder 'bullet_syropod'" in out and "in <mesh>" in out, out


# -- bad input: one line, exit 2, nothing written ------------------------------------------------------------------


def _prismatic() -> str:
    leg = LegSpec("p", [Element("revolute", (0.1, -0.1, 0.0)), Element("prismatic", (0.1, 0.0, 0.0))],
                  sphere=(0.0, 0.0, 0.0))
    return robot_urdf([leg])


@pytest.mark.parametrize(("content", "message"), [
    (None, "file not found"),
    ("<robot name='x'><link name='a'>", "malformed XML"),
    (robot_urdf([LegSpec("p", [Element("fixed", (0.1, 0.0, 0.0))])]), "no legs found"),
    (_prismatic(), "is prismatic (it slides)"),
    (robot_urdf([LegSpec("p", [Element("revolute", (0.1, -0.1, 0.0), lower=0.5, upper=0.5)])]),
     "has lower 0.5 >= upper 0.5"),
])
def test_bad_urdfs_are_one_line_and_exit_2(content: str | None, message: str, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                           monkeypatch) -> None:
    path = tmp_path / "robot.urdf"
    if content is not None:
        path.write_text(content)
    code, _, err = run(["import", "urdf", str(path), "--out", str(tmp_path / "out")], capsys, monkeypatch)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith(f"error: {path}") and message in err, err
    assert not (tmp_path / "out").exists()


def _tilted_leg(tilt: float, femur: float = 0.08, tibia: float = 0.1) -> LegSpec:
    """Femur and tibia axes ``tilt`` rad apart in their common plane (a pitch of the knee frame)."""
    return LegSpec("p", [Element("revolute", (0.1, -0.1, 0.0), (0.0, 0.0, -math.pi / 2)),
                         Element("revolute", (0.04, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
                         Element("revolute", (femur, 0.0, 0.0), (0.0, tilt, 0.0))], sphere=(tibia, 0.0, 0.0))


def test_nearly_parallel_axes_are_snapped_when_the_tips_hardly_move(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                     monkeypatch) -> None:
    """Femur and tibia axes 2e-5 rad apart meet 4 km away: the import snaps without being asked and says so; 0.003
    rad apart (3.14 for pi is 0.0016) is snapped too (the tip moves tilt × tibia = 0.3 mm, under 0.5 % of the
    0.22 m leg); 0.015 rad on 0.2 m links moves it 3 mm, more than 0.5 % of 0.44 m: one line naming the --snap
    that accepts it, which then imports."""
    from shc_cli.interop.urdf_import import import_urdf

    path = tmp_path / "robot.urdf"
    path.write_text(robot_urdf([_tilted_leg(2e-5)]))
    result = import_urdf(path, tmp_path / "out", legs="p_link2", clearance=0.05, reach=0.9)
    assert result.fk_error < 1e-9 and result.snap == pytest.approx(2e-5, rel=0.01)
    assert 1e-7 < result.fk_error_unsnapped < 2e-5 * 0.2
    assert any("2e-05 rad from parallel" in note and "snapped" in note for note in result.notes)
    path.write_text(robot_urdf([_tilted_leg(0.003)]))
    result = import_urdf(path, tmp_path / "out1", legs="p_link2", clearance=0.05, reach=0.9)
    assert result.fk_error < 1e-9 and result.fk_error_unsnapped == pytest.approx(0.003 * 0.1, rel=0.02)
    assert any("0.003 rad from parallel" in note and "within 0.005 rad" in note and "0.0003 m at most" in note
               for note in result.notes), result.notes
    path.write_text(robot_urdf([_tilted_leg(0.015, femur=0.2, tibia=0.2)]))
    code, _, err = run(["import", "urdf", str(path), "--out", str(tmp_path / "out2"), "--legs", "p_link2"],
                       capsys, monkeypatch)
    assert code == 2
    assert err.count("\n") == 1 and "0.015 rad from parallel" in err and "--snap 0.02" in err, err
    assert not (tmp_path / "out2").exists()
    code, _, err = run(["import", "urdf", str(path), "--out", str(tmp_path / "out2"), "--legs", "p_link2",
                          "--snap", "0.02", "--clearance", "0.1", "--reach", "0.8"], capsys, monkeypatch)
    assert code == 0, err


@given(mass=st.floats(0.011, 50.0), size=st.floats(1e-4, 2.0), legs=st.integers(1, 8))
def test_a_placeholder_effort_becomes_a_positive_stall_torque_for_any_robot(mass: float, size: float,
                                                                            legs: int) -> None:
    """One effort limit far above what the robot's weight needs is a placeholder; the torque put in its place is the
    weight on a third of the legs (module docstring of urdf_import_clean) and a valid servo.stall_torque (> 0) for a
    robot however small — a fuzzed chain of 1e-4 m legs once rounded it to 0.00 N·m, which the robot file refuses.
    (Masses above the 0.01 kg below which they are placeholders themselves.)"""
    from shc_cli.interop.urdf_import_clean import placeholders

    weight = mass * 9.81 * size
    found = placeholders([mass / 3] * 3, [0.0] * 3, [size] * legs, [], [1e9] * 3)
    assert found.torque is not None and found.torque > 0.0
    assert found.torque == pytest.approx(1.5 * weight / legs, rel=5e-3)
