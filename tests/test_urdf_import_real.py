"""``shc import urdf`` on third-party descriptions (tests/data/robots, see its README) and on the classes of
description they stand for: each imports with no options, has the URDF's forward kinematics (yourdfpy's, the
reference), validates and plans."""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest

from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot

from .test_cli import run
from .urdf_robots import Element, LegSpec, insect_leg, robot_urdf

pytest.importorskip("yourdfpy", reason="shc import urdf needs the 'urdf' extra")

DATA = Path(__file__).parent / "data" / "robots"
DESCRIPTIONS = {
    "phantomx": (DATA / "phantomx_description" / "urdf" / "phantomx.urdf", 6),
    "pxmark4": (DATA / "pxmark4_interbotix.urdf", 6),
    "hexapod_olli_io": (DATA / "hexapod_olli_io.urdf", 6),
    "anymal_b": (DATA / "anymal_b_anybotics.urdf", 4),
    "octapod": (DATA / "octapod_spider_sai_raghava.urdf", 8),
    "solo12": (DATA / "solo12_odri.urdf", 4),
    "spot_micro": (DATA / "spot_micro_mike4192.urdf", 4),
    "hexaross": (DATA / "hexaross_description" / "urdf" / "hexapod.urdf", 6),
}
FALLS: set[str] = set()
"""Descriptions that fall in 10 s of simulation, and why: tests/data/robots/README.md (Spot Micro fell until the
import gave quad_wave quadrupeds a body sway, poses/quad_wave.toml)."""


def _import(path: Path, out: Path, capsys, monkeypatch, *options: str) -> tuple[int, str, str, Path | None]:  # type: ignore[no-untyped-def]
    code, stdout, err = run(["import", "urdf", str(path), "--out", str(out), *options], capsys, monkeypatch)
    written = next(iter((out / "robots").glob("*.toml")), None) if code == 0 else None
    return code, stdout, err, written


def _fk_worst(urdf_text: str, path: Path, robot_file: Path, yaw: float = 0.0, samples: int = 50,
              legs_text: str | None = None) -> float:
    """Largest tip distance between the robot file's chains and yourdfpy's FK of ``urdf_text`` at random angles,
    the URDF joints found through [hardware.servos]'s ``joint`` names [m]; the tip links and points are those the
    import chose (from ``legs_text``, default ``urdf_text``)."""
    from shc_cli.interop.urdf_import import import_tree
    from shc_cli.interop.urdf_import_source import parse_urdf

    model = parse_urdf(path, urdf_text)
    legs = import_tree(parse_urdf(path, legs_text or urdf_text), path, "x", forward=yaw).legs
    robot = load_robot(robot_file).robot
    servos = robot.hardware.servos
    chains = Chains.from_robot(robot)
    turn = np.array([[math.cos(yaw), math.sin(yaw), 0.0], [-math.sin(yaw), math.cos(yaw), 0.0], [0.0, 0.0, 1.0]])
    base = "base_link" if "base_link" in model.link_map else model.base_link
    rng = np.random.default_rng(3)
    worst = 0.0
    ends = {leg.joints[0].name: (leg.end, leg.tip_local) for leg in legs}
    for _ in range(samples):
        q = rng.uniform(chains.lower, chains.upper)
        cfg = {name: 0.0 for name in model.actuated_joint_names}
        for i, (leg_id, spec) in enumerate(robot.legs.items()):
            for k, joint in enumerate(spec.joints):
                cfg[servos[f"{leg_id}_{joint}"].joint] = float(q[i, k])
        model.update_cfg(cfg)
        ours = chains.tips(q)
        for i, (leg_id, spec) in enumerate(robot.legs.items()):
            end, point = ends[servos[f"{leg_id}_{next(iter(spec.joints))}"].joint]
            transform = np.asarray(model.get_transform(frame_to=end, frame_from=base), dtype=float)
            theirs = turn @ (transform @ np.append(point, 1.0))[:3]
            worst = max(worst, float(np.linalg.norm(ours[i] - theirs)))
    return worst


@pytest.mark.parametrize("name", list(DESCRIPTIONS))
def test_third_party_descriptions_import_without_options_with_their_kinematics(
        name: str, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    from shc_cli.interop.urdf_import_source import read_source

    path, legs = DESCRIPTIONS[name]
    code, out, err, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    data = tomllib.loads(robot_file.read_text())
    assert len(data["legs"]) == legs
    servos = data["hardware"]["servos"]
    assert len(servos) == sum(len(data["templates"][leg.get("template", "leg")]["joints"]) for leg in
                              data["legs"].values())
    snapped = read_source(path, {}, 0.001 if "snapped" in out else 0.0).snapped_text
    turned = re.search(r"turned (\S+) deg about z", robot_file.read_text())  # the header: the octapod's 22.5
    yaw = math.radians(float(turned.group(1))) if turned else 0.0
    assert _fk_worst(snapped, path, robot_file, yaw=yaw) < 1e-6
    if "snapped" in out:  # PhantomX: base z and coxa axes 8.9e-5 rad apart; the snap moves tips < 0.4 mrad × 0.3 m
        assert _fk_worst(path.read_text(), path, robot_file, legs_text=snapped, yaw=yaw) < 1.2e-4


@pytest.mark.slow
@pytest.mark.parametrize("name", list(DESCRIPTIONS))
def test_third_party_descriptions_validate_and_plan(name: str, tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err, robot_file = _import(DESCRIPTIONS[name][0], tmp_path, capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run(["validate", str(robot_file)], capsys, monkeypatch)
    assert code == 0, err
    code, out, err = run(["plan", str(robot_file), "--duration", "2", "--no-plots", "--out", str(tmp_path / "run")],
                         capsys, monkeypatch)
    assert code == 0, err
    speed = float(out.split("displacement speed ")[1].split()[0])
    assert speed > 0.01, out


@pytest.mark.slow
@pytest.mark.parametrize("name", [name for name in DESCRIPTIONS if name not in FALLS])
def test_third_party_descriptions_walk_10_s_in_simulation(name: str, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                          monkeypatch) -> None:
    """Each imported robot walks 10 s in MuJoCo at full throttle without falling, at least half as far as asked
    straight ahead and 0.6 of the distance asked along its path (tests/data/robots/README.md: what each walks with
    its stated efforts)."""
    import json

    code, _, err, robot_file = _import(DESCRIPTIONS[name][0], tmp_path, capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run(["simulate", str(robot_file), "--duration", "10", "--no-plots", "--out",
                        str(tmp_path / "sim")], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((tmp_path / "sim" / "summary.json").read_text())
    assert not summary["fell"] and summary["complete"], summary
    assert summary["forward_distance_m"] > 0.5 * summary["commanded_distance_m"] > 0.0, summary
    assert summary["walked_share"] >= 0.6, summary  # issue 37: an imported robot walks 0.6 of the distance asked


def test_an_octopod_with_legs_all_round_pointing_up_stands_and_pairs_its_legs(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                              monkeypatch) -> None:
    """The octapod's legs are every 45° (one straight ahead, one behind, one each side: no quarter turn pairs them)
    and point straight up at the zero pose (the hip yaw axis through the tip, the femur and tibia axes all along
    the URDF's y): forward turns 22.5°, the legs are AR…DR, DL…AL, and the stance is found from the seeds."""
    path = DESCRIPTIONS["octapod"][0]
    code, out, err, robot_file = _import(path, tmp_path, capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    assert "shc's forward is 22.5 deg from base_link's +x towards +y, halfway between two legs" in out
    data = tomllib.loads(robot_file.read_text())
    assert list(data["legs"]) == ["AR", "BR", "CR", "DR", "DL", "CL", "BL", "AL"]
    assert data["walker"]["gait"] == "octo_alternating"
    servos = data["hardware"]["servos"]
    assert servos["AR_joint1"]["joint"] == "joint_7_1" and servos["AL_joint1"]["joint"] == "joint_8_1"
    # every stance foot is outside its hip (the legs spread), below the body
    for leg in data["legs"].values():
        assert math.hypot(leg["stance"]["x"], leg["stance"]["y"]) > 0.5
    assert data["walker"]["body_clearance"] > 0.0
    assert _fk_worst(path.read_text(), path, robot_file, yaw=math.radians(22.5)) < 1e-6


def test_placeholder_efforts_and_unlimited_speeds_are_named_and_replaced(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                         monkeypatch) -> None:
    """Solo-12 gives every joint 1000 N·m and 1000 rad/s (its real actuators: ≈2.7 N·m): named, with the weight
    of its 2.5 kg on a third of its legs half a 0.35 m leg out (3.21 N·m) and 5 rad/s used instead."""
    code, out, err, robot_file = _import(DESCRIPTIONS["solo12"][0], tmp_path, capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    assert "every joint's effort limit is 1000 N·m, which looks like a placeholder" in out
    assert "every joint's velocity limit is 1000 rad/s, which looks like a placeholder" in out
    data = tomllib.loads(robot_file.read_text())
    mass = data["body"]["mass"] + sum(j["mass"] for leg in data["legs"].values() for j in
                                      data["templates"][leg.get("template", "leg")]["joints"].values())
    assert mass == pytest.approx(2.505, abs=0.01)
    # the leg through its joint origins to the foot (leg.xacro): HAA→HFE (19.5, 14) mm, HFE→KFE (37.45, 160) mm,
    # KFE→FOOT (9, 160) mm
    leg = math.hypot(0.0195, 0.014) + math.hypot(0.03745, 0.16) + math.hypot(0.009, 0.16)
    assert data["servo"]["stall_torque"] == pytest.approx(1.5 * mass * 9.81 * leg / 4, abs=0.01)
    assert data["servo"]["no_load_speed"] == 5.0


def test_placeholder_inertias_slow_speeds_and_huge_efforts_together(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                    monkeypatch) -> None:
    """Spot Micro: 100–1000 kg·m² on every link, 0.5 and 0.7 rad/s (not one value), 1000 N·m: all three named;
    the effort is judged against the masses used instead (0.07 kg per joint and as much again for the body)."""
    code, out, err, robot_file = _import(DESCRIPTIONS["spot_micro"][0], tmp_path, capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    assert "the URDF's inertial data look like placeholders (20 of 20 links" in out
    assert "every joint's velocity limit is 0.5–0.7 rad/s, which looks like a placeholder" in out
    assert "every joint's effort limit is 1000 N·m, which looks like a placeholder (the robot's 1.68 kg" in out
    servo = tomllib.loads(robot_file.read_text())["servo"]
    # its legs: shoulder → leg (0, 55, 0) mm, leg → foot (0, 0, 107.5) mm, foot → toe (0, 0, 130) mm and the toe
    # sphere's centre 20 mm back up
    leg = 0.055 + 0.1075 + 0.13 - 0.02
    assert servo["stall_torque"] == pytest.approx(1.5 * 2 * 0.07 * 12 * 9.81 * leg / 4, abs=0.01)
    assert servo["no_load_speed"] == 5.0


# -- the classes of description, made up -------------------------------------------------------------------------


def _hexapod(**leg_options: object) -> list[LegSpec]:
    return [insect_leg(f"leg{i}", x, y, standing=True)
            for i, (x, y) in enumerate([(0.12, -0.08), (0.0, -0.1), (-0.12, -0.08),
                                        (-0.12, 0.08), (0.0, 0.1), (0.12, 0.08)])]


def test_stubs_dummy_foot_joints_and_a_pan_tilt_head_are_not_leg_joints(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                        monkeypatch) -> None:
    """Each leg ends in two zero-length revolute joints at the foot and a force sensor modelled as a prismatic
    joint of ±0.1 mm; a camera pan/tilt chain hangs off the body: 6 legs of 3 joints, FK the URDF's."""
    legs = []
    for leg in _hexapod():
        extra = [Element("revolute", (0.12, 0.0, 0.0), axis=(0.0, 1.0, 0.0)), Element("revolute", axis=(1.0, 0.0, 0.0)),
                 Element("prismatic", axis=(1.0, 0.0, 0.0), lower=-0.0001, upper=0.0001)]
        legs.append(LegSpec(leg.name, [*leg.elements, *extra], sphere=(0.0, 0.0, 0.0)))
    legs.append(LegSpec("head", [Element("revolute", (0.15, 0.0, 0.05)),
                                 Element("revolute", (0.02, 0.0, 0.0), axis=(0.0, 1.0, 0.0)),
                                 Element("fixed", (0.03, 0.0, 0.0))]))
    path = tmp_path / "hex.urdf"
    path.write_text(robot_urdf(legs, name="hex"))
    code, out, err, robot_file = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    data = tomllib.loads(robot_file.read_text())
    assert len(data["legs"]) == 6 and list(data["templates"]["leg"]["joints"]) == ["joint0", "joint1", "joint2"]
    assert "leg0_joint6 is taken as fixed: prismatic with 0.2 mm of travel" in out
    assert "leg0_joint4, leg0_joint5 at the foot of the leg to leg0_link6 pass through the tip" in out
    assert "chains left out as not legs (their links count as body): head_link2 (2 joints)" in out
    assert _fk_worst(path.read_text(), path, robot_file) < 1e-6


def test_a_leg_straight_ahead_turns_forward_a_quarter(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Six legs every 60° from +x (legs straight ahead and behind): forward becomes base_link's +y, the legs pair
    up left and right; --forward +x keeps the URDF's."""
    legs = [LegSpec(f"leg{i}", [Element("revolute", (0.12 * math.cos(a), 0.12 * math.sin(a), 0.0), (0.0, 0.0, a),
                                        lower=-0.8, upper=0.8),
                                Element("revolute", (0.04, 0.0, 0.0), (math.pi / 2, 0.0, 0.0)),
                                Element("revolute", (0.08, 0.0, 0.0), lower=-2.4, upper=2.4),
                                Element("fixed", (0.0, 0.0, 0.0), (0.0, 0.0, -math.pi / 2))], sphere=(0.12, 0.0, 0.0))
            for i, a in enumerate(np.arange(6) * math.pi / 3)]
    path = tmp_path / "round.urdf"
    path.write_text(robot_urdf(legs, name="round"))
    code, out, err, robot_file = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    assert "shc's forward is base_link's +y" in out
    data = tomllib.loads(robot_file.read_text())
    assert list(data["legs"]) == ["AR", "BR", "CR", "CL", "BL", "AL"]
    assert _fk_worst(path.read_text(), path, robot_file, yaw=math.pi / 2) < 1e-6
    code, out, err, robot_file = _import(path, tmp_path / "kept", capsys, monkeypatch, "--forward", "+x",
                                         "--clearance", "0.1", "--reach", "0.5")
    assert code == 0, err
    assert robot_file is not None
    assert "shc's forward is" not in out and "turned" not in robot_file.read_text()


def test_placeholder_inertials_and_speeds_are_named_and_replaced(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Total mass 1e-4 kg with 1 kg·m² links and 0.52 rad/s on every joint: named, with plausible values used."""
    text = robot_urdf([LegSpec(leg.name, leg.elements, leg.sphere, masses=[1e-5] * 4) for leg in _hexapod()],
                      name="light", body_mass=1e-5)
    text = text.replace('ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"',
                        'ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"').replace('velocity="4.0"', 'velocity="0.52"')
    path = tmp_path / "light.urdf"
    path.write_text(text)
    code, out, err, robot_file = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    assert "inertial data look like placeholders (total mass 0.00025 kg)" in out
    assert "velocity limit is 0.52 rad/s, which looks like a placeholder" in out
    data = tomllib.loads(robot_file.read_text())
    joint = data["templates"]["leg"]["joints"]["joint1"]
    assert joint["max_vel"] == 5.0 and joint["mass"] == 0.07 and data["body"]["mass"] == pytest.approx(18 * 0.07)
    assert data["servo"]["no_load_speed"] == 5.0


def test_a_tip_on_the_knee_axis_is_refused_with_the_tip_that_fixes_it(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                     monkeypatch) -> None:
    """The tibia link's frame is on the knee axis and nothing follows it: refused, naming a --tip pattern and a
    point (twice the tibia's centre of mass, 0.01 m out, with nothing else to go by); that --tip imports."""
    legs = [LegSpec(leg.name, leg.elements[:3]) for leg in _hexapod()]
    path = tmp_path / "knee.urdf"
    path.write_text(robot_urdf(legs, name="knee"))
    code, _, err, _ = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 2 and err.count("\n") == 1
    assert "lies on the axis of leg" in err and "--tip '*_link2@0.02,0,0'" in err, err
    code, _, err, _ = _import(path, tmp_path / "out", capsys, monkeypatch, "--tip", "*_link2@0.12,0,0")
    assert code == 0, err


def test_a_stance_the_limits_forbid_names_the_leg_the_limit_and_what_works(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                          monkeypatch) -> None:
    path = tmp_path / "hex.urdf"
    path.write_text(robot_urdf(_hexapod(), name="hex"))
    code, _, err, _ = _import(path, tmp_path / "out", capsys, monkeypatch, "--clearance", "0.4")
    assert code == 2 and err.count("\n") == 1, err
    assert "cannot stand with clearance 0.4 m" in err and "limit" in err and "--clearance" in err, err
    assert not (tmp_path / "out").exists()


def test_a_knee_limit_that_keeps_the_leg_nearly_straight_stands_far_out(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                        monkeypatch) -> None:
    """A flat hexapod whose knees bend at most ±0.9 rad: no stance 0.2–0.7 of the leg's length out is reachable
    with its swing apex (femur to foot is 0.181–0.2 m); the search goes on to 0.75–0.9 and the robot plans."""
    legs = []
    for leg in _hexapod():
        flat = insect_leg(leg.name, leg.elements[0].xyz[0], leg.elements[0].xyz[1], standing=False)
        elements = list(flat.elements)
        elements[2] = Element("revolute", (0.08, 0.0, 0.0), lower=-0.9, upper=0.9)
        legs.append(LegSpec(leg.name, elements, flat.sphere, masses=flat.masses))
    path = tmp_path / "knee.urdf"
    path.write_text(robot_urdf(legs, name="knee"))
    code, out, err, robot_file = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 0, err
    assert "feet 0.85 of the leg's length out from the hips" in out
    code, out, err = run(["plan", str(robot_file), "--duration", "2", "--no-plots", "--out", str(tmp_path / "run")],
                         capsys, monkeypatch)
    assert code == 0, err


@pytest.mark.slow
@pytest.mark.serial  # a real-time loop on an emulated bus: beside another worker the emulator starved ("no reply")
def test_run_hw_reads_the_imported_servo_map(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The PhantomX's [hardware.servos] as imported (ids 11…63, the model guessed from its 2.8 N·m joints) drive a
    dry run on the emulated bus: every servo is found by the id the map gives."""
    import subprocess
    import sys

    from shc_cli.hardware.emulator_process import EmulatorProcess, promptly

    code, _, err, robot_file = _import(DESCRIPTIONS["phantomx"][0], tmp_path, capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    hardware = load_robot(robot_file).robot.hardware
    assert sorted(s.id for s in hardware.servos.values()) == [10 * leg + joint for leg in range(1, 7)
                                                             for joint in range(1, 4)]
    for skip in (None, 42):  # all there; then BL's femur (leg 4, joint 2) missing: refused, naming it
        # served by a process of its own, run-hw ahead of other work: on a loaded machine either starved said "no reply"
        servos = {s.id: hardware.model for s in hardware.servos.values() if s.id != skip}
        with promptly(), EmulatorProcess(servos) as bus:
            result = subprocess.run([sys.executable, "-m", "shc_cli.cli", "run-hw", str(robot_file), "--port",
                                     bus.port, "--out", str(tmp_path / f"dry{skip}"), "--dry-run", "--duration", "0.5",
                                     "--stop-state", "ready"], capture_output=True, text=True, timeout=120)
        if skip is None:
            assert result.returncode == 0, result.stderr
        else:
            assert result.returncode != 0 and "42" in result.stderr, result.stderr


def _odd_leg(name: str, x: float, y: float) -> LegSpec:
    """A hobby hexapod's leg as issue 27 met it: coxa ±0.46 rad, rear coxa frames turned by π (axis down), femur
    and tibia servos mounted at 45° (frames rolled π/4, axes given in them), the tip in a fixed ``endcap`` link."""
    side = -1.0 if y < 0 else 1.0
    rear = x < 0
    yaw = side * math.pi / 2 + (0.5 if x > 0 else -0.5 if x < 0 else 0.0) * side + (math.pi if rear else 0.0)
    out = -1.0 if rear else 1.0
    return LegSpec(name, [
        Element("revolute", (x, y, 0.0), (0.0, 0.0, yaw), (0.0, 0.0, -1.0 if rear else 1.0), -0.46, 0.46),
        Element("revolute", (out * 0.05, 0.0, 0.0), (math.pi / 4, 0.0, 0.0), (0.0, 1.0, -1.0), -1.6, 1.6),
        Element("revolute", (out * 0.07, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 1.0, -1.0), -2.2, 2.2),
        Element("fixed", (out * 0.08, 0.0, 0.0))], masses=[0.06, 0.08, 0.05, 0.005])


def test_odd_mounts_flipped_rear_frames_tight_coxas_and_an_endcap_tip(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                      monkeypatch) -> None:
    legs = [_odd_leg(f"leg{i}", x, y) for i, (x, y) in
            enumerate([(0.1, -0.06), (0.0, -0.08), (-0.1, -0.06), (-0.1, 0.06), (0.0, 0.08), (0.1, 0.06)])]
    path = tmp_path / "odd.urdf"
    path.write_text(robot_urdf(legs, name="odd").replace('_link3"', '_endcap"'))
    code, _, err, robot_file = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    assert "# Tip of every leg: the origin of its leg's last link." in robot_file.read_text()
    assert _fk_worst(path.read_text(), path, robot_file) < 1e-6
    code, _, err = run(["plan", str(robot_file), "--duration", "2", "--no-plots", "--out", str(tmp_path / "run")],
                         capsys, monkeypatch)
    assert code == 0, err


def test_legs_straight_up_at_the_zero_pose_stand_from_the_seeds(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """Every leg points straight up at the zero pose, its femur joint 0.08 m above the hip yaw on the yaw axis and
    every pitch axis along base_link's y (the octapod's build, on a hexapod): from all joints at 0 the IK cannot
    reach any stance (the yaw does not move a tip on its axis); from the seeds it stands, and plans."""
    legs = [LegSpec(f"leg{i}", [Element("revolute", (x, y, 0.0), lower=-3.1, upper=3.1),
                                Element("revolute", (0.0, 0.0, 0.08), axis=(0.0, 1.0, 0.0), lower=-3.1, upper=3.1),
                                Element("revolute", (0.0, 0.0, 0.08), axis=(0.0, 1.0, 0.0), lower=-3.1, upper=3.1),
                                Element("fixed", (0.0, 0.0, 0.08))], sphere=(0.0, 0.0, 0.0))
            for i, (x, y) in enumerate([(0.12, -0.08), (0.0, -0.1), (-0.12, -0.08),
                                        (-0.12, 0.08), (0.0, 0.1), (0.12, 0.08)])]
    path = tmp_path / "up.urdf"
    path.write_text(robot_urdf(legs, name="up"))
    code, _, err, robot_file = _import(path, tmp_path / "out", capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    data = tomllib.loads(robot_file.read_text())
    for leg in data["legs"].values():  # the feet stand out from the hips, below them
        assert leg["stance"]["x"] ** 2 + leg["stance"]["y"] ** 2 > 0.1 ** 2
    assert _fk_worst(path.read_text(), path, robot_file) < 1e-6
    code, _, err = run(["plan", str(robot_file), "--duration", "2", "--no-plots", "--out", str(tmp_path / "run")],
                       capsys, monkeypatch)
    assert code == 0, err
    import shc_cli.interop.urdf_import_stance as urdf_import

    monkeypatch.setattr(urdf_import, "_seeds", lambda chains: None)  # OpenSHC's initial pose alone: no stance
    code, _, err, _ = _import(path, tmp_path / "unseeded", capsys, monkeypatch)
    assert code == 2 and "no standing pose found" in err


@pytest.mark.parametrize(("angles", "expected"), [
    ([0, 60, 120, 180, 240, 300], 90.0),  # legs ahead and behind, none beside: a quarter turn
    ([30, 90, 150, 210, 270, 330], 0.0),  # none ahead or behind: as it is
    ([0, 90, 180, 270], 45.0),  # a "+" quadruped: halfway between two legs
    ([0, 45, 90, 135, 180, 225, 270, 315], 22.5),  # the octapod
    ([10, 55, 100, 145, 190, 235, 280, 325], 0.0),  # none within a twentieth of the x axis
])
def test_forward_turns_the_least_that_pairs_the_legs_left_and_right(angles: list[float], expected: float) -> None:
    from shc_cli.interop.urdf_import_clean import forward_turn

    hips = [np.array([0.2 * math.cos(math.radians(a)), 0.2 * math.sin(math.radians(a)), 0.0]) for a in angles]
    assert math.degrees(forward_turn(hips)) == pytest.approx(expected)


@pytest.mark.slow
def test_the_octapod_walks_with_the_eight_legged_wave_gait_too(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """gaits/octo_wave.toml (one leg at a time, duty 0.875) on the imported octapod: 10 s in MuJoCo, upright, as far
    as asked within a fifth."""
    import json

    code, _, err, robot_file = _import(DESCRIPTIONS["octapod"][0], tmp_path, capsys, monkeypatch)
    assert code == 0, err
    code, _, err = run(["simulate", str(robot_file), "--gait", "octo_wave", "--duration", "10", "--no-plots", "--out",
                        str(tmp_path / "sim")], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((tmp_path / "sim" / "summary.json").read_text())
    assert not summary["fell"] and summary["gait"] == "octo_wave", summary
    assert summary["forward_distance_m"] == pytest.approx(summary["commanded_distance_m"], rel=0.2), summary


def test_an_imported_quad_wave_quadruped_gets_a_sway_sized_for_its_stance(tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                                                         monkeypatch) -> None:
    """Spot Micro (quad_wave): the import turns auto posing on with a set of its own, written next to the robot,
    whose sideways sway is a third of the feet's lateral half-spread (the standing triangle's centroid); a
    hexapod gets none."""
    out = tmp_path / "spot"
    code, stdout, err, robot_file = _import(DESCRIPTIONS["spot_micro"][0], out, capsys, monkeypatch)
    assert code == 0, err
    assert robot_file is not None
    data = tomllib.loads(robot_file.read_text())
    assert data["walker"]["gait"] == "quad_wave"
    pose_file = out / "poses" / f"{data['name']}_quad_wave.toml"
    assert data["pose"] == {"auto": True, "auto_pose_type": f"../poses/{pose_file.name}"}
    assert f"wrote {pose_file}" in stdout
    half_spread = sum(abs(leg["stance"]["y"]) for leg in data["legs"].values()) / 4
    posers = tomllib.loads(pose_file.read_text())["poser"]
    assert [p["y"] for p in posers] == [pytest.approx(half_spread / 3, abs=5e-4),
                                        pytest.approx(-half_spread / 3, abs=5e-4)]
    code, _, err = run(["plan", str(robot_file), "--duration", "2", "--no-plots", "--out",
                        str(tmp_path / "run")], capsys, monkeypatch)
    assert code == 0, err
    # another gait has no set sized for it: one line that says how to go on
    code, _, err = run(["plan", str(robot_file), "--gait", "trot", "--duration", "2", "--no-plots", "--out",
                        str(tmp_path / "trot")], capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert f"{pose_file.name}:" in err and "gait 'trot'" in err and "pose.auto = false" in err
    code, _, err, hexapod = _import(DESCRIPTIONS["hexapod_olli_io"][0], tmp_path / "hex", capsys, monkeypatch)
    assert code == 0 and hexapod is not None, err
    assert "pose" not in tomllib.loads(hexapod.read_text()) and not (tmp_path / "hex" / "poses").exists()
