"""The shipped TOML robots expand to exactly the parameters of OpenSHC's own YAML files."""

from __future__ import annotations

from pathlib import Path

import pytest
from ruamel.yaml import YAML

from shc_cli.spec.loading import bundled, load_gait, load_robot

from .conftest import GOLDEN, ROOT

PAIRS = [
    ("bullet_openshc", "bullet_insectoid.yaml"),
    ("bullet_mammalian", "bullet_mammalian.yaml"),
    ("openshc_default", "openshc_default.yaml"),
]


def _yaml(name: str) -> dict:  # type: ignore[type-arg]
    data = YAML(typ="safe").load((GOLDEN / "openshc" / name).read_text())
    return data["syropod"]["parameters"]  # type: ignore[no-any-return]


@pytest.mark.parametrize(("robot_name", "yaml_name"), PAIRS)
def test_every_leg_parameter_matches_openshc(robot_name: str, yaml_name: str) -> None:
    params = _yaml(yaml_name)
    robot = load_robot(robot_name).robot
    assert list(robot.legs) == params["leg_id"]
    assert robot.time_delta == params["time_delta"]
    assert robot.walker.body_clearance == params["body_clearance"]
    for leg_id, leg in robot.legs.items():
        assert len(leg.joints) == params["leg_DOF"][leg_id]
        assert list(leg.joints) == params["joint_id"][: len(leg.joints)]
        base = params[f"{leg_id}_base_link_parameters"]
        assert (leg.base.d, leg.base.theta, leg.base.r, leg.base.alpha) == (
            base["d"], base["theta"], base["r"], base["alpha"]), leg_id
        stance = params[f"{leg_id}_stance_position"]
        assert (leg.stance.x, leg.stance.y) == (stance["x"], stance["y"])
        for name, joint in leg.joints.items():
            link = params[f"{leg_id}_{name}_link_parameters"]
            assert (joint.d, joint.theta, joint.r, joint.alpha) == (
                link["d"], link["theta"], link["r"], link["alpha"]), f"{leg_id} {name}"
            spec = params[f"{leg_id}_{name}_joint_parameters"]
            assert (joint.min, joint.max, joint.unpacked, joint.max_vel, joint.offset) == (
                spec["min"], spec["max"], spec["unpacked"], spec["max_vel"], spec["offset"]), f"{leg_id} {name}"
            numbered = [spec[k] for k in sorted(spec) if k.startswith("packed_")]
            packed = [spec["packed"]] if "packed" in spec else numbered
            assert joint.packed == packed, f"{leg_id} {name}"


@pytest.mark.parametrize(("robot_name", "yaml_name"), PAIRS)
def test_walker_parameters_match_openshc(robot_name: str, yaml_name: str) -> None:
    params = _yaml(yaml_name)
    robot = load_robot(robot_name).robot
    walker = robot.walker
    for name in ("step_frequency", "swing_height", "swing_width", "step_depth", "stance_span_modifier"):
        expected = params[name]
        got = getattr(walker, name)
        assert (got.default, got.min, got.max, got.step) == (
            expected["default"], expected["min"], expected["max"], expected["step"]), name
    assert walker.gait == params["gait_type"].removesuffix("_gait")
    assert robot.ik.clamp_joint_velocities == params["clamp_joint_velocities"]
    assert robot.ik.ignore_warnings == params["ignore_IK_warnings"]
    assert robot.start_up.time_to_start == params["time_to_start"]


def test_gaits_match_openshc_gait_file() -> None:
    gaits = YAML(typ="safe").load((GOLDEN / "openshc" / "gait.yaml").read_text())["syropod"]["gait_parameters"]
    for key, expected in gaits.items():
        gait = load_gait(key.removesuffix("_gait")).gait
        assert (gait.stance_phase, gait.swing_phase, gait.phase_offset) == (
            expected["stance_phase"], expected["swing_phase"], expected["phase_offset"])
        assert gait.offset_multiplier == expected["offset_multiplier"]


def test_every_bundled_robot_and_gait_loads_from_any_directory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert {"bullet", "bullet_mammalian", "openshc_default", "athena", "quadruped", "octopod"} <= set(bundled("robots"))
    for name in bundled("robots"):
        assert load_robot(name).robot is not None
    for name in bundled("gaits"):
        assert load_gait(name).gait is not None
    assert (ROOT / "robots" / "bullet.toml").is_file()


def test_the_default_robot_is_the_papers_bullet_and_its_paper_name_is_the_same_robot() -> None:
    """``bullet`` is the robot the OpenSHC paper measured: Table I's 10.07 kg (arrangement A), Table III's heights, the
    calibrated servo model; ``bullet_insectoid_a`` is the same robot under the paper's name, and the paper's
    arrangement-B robots extend OpenSHC's own Bullet file (``bullet_openshc``), whose legs they keep."""
    bullet, paper = load_robot("bullet").robot, load_robot("bullet_insectoid_a").robot
    openshc, b = load_robot("bullet_openshc").robot, load_robot("bullet_insectoid_b").robot
    assert bullet is not None and paper is not None and openshc is not None and b is not None
    # the same robot; only the default robot walks its verified speed limits (the paper measured OpenSHC's limits)
    walker = paper.walker.model_copy(update={"verify_speed_limits": bullet.walker.verify_speed_limits})
    assert paper.model_copy(update={"name": bullet.name, "description": bullet.description, "walker": walker}) == bullet
    assert bullet.total_mass() == pytest.approx(10.07, abs=0.005)  # Table I, arrangement A
    assert (bullet.walker.body_clearance, bullet.walker.swing_height.default) == (0.20, 0.15)  # Table III
    assert bullet.servo.control == "dynamixel" and bullet.servo.coulomb_friction > 0.0  # fitted (the default is 0)
    assert b.legs["AR"].joints == openshc.legs["AR"].joints


def test_mammalian_extends_bullet_openshc_and_overrides_only_what_it_says() -> None:
    bullet = load_robot("bullet_openshc").robot
    mammal = load_robot("bullet_mammalian").robot
    assert mammal.walker.gait == "bipod" and bullet.walker.gait == "tripod"
    assert mammal.legs["CL"].joints["coxat"].min == 0.0 and mammal.legs["CL"].joints["coxat"].max == 3.142
    assert mammal.legs["AL"].joints["tarsus"].min == -3.142
    assert mammal.body == bullet.body
    assert mammal.admittance == bullet.admittance


@pytest.mark.parametrize("path", sorted((ROOT / "robots").glob("*.toml")), ids=lambda p: p.stem)
def test_no_robot_spawns_with_its_feet_in_the_floor(path: Path) -> None:
    """On the stand the body starts at its standing height with the legs at their ``unpacked`` angles: no foot centre
    may be more than 1 mm (contact slop) below the standing plane, else the engine pushes the feet out of the floor
    through the stand during start-up (bullet_insectoid_a did, 100 N per foot, after its roll axis moved down)."""
    from shc_cli.control.packing import joint_configurations
    from shc_cli.model.chains import Chains

    robot = load_robot(path).robot
    chains = Chains.from_robot(robot)
    _, unpacked = joint_configurations(robot, chains.joints)
    heights = robot.walker.body_clearance + chains.tips(unpacked)[:, 2]
    assert heights.min() >= -0.001, f"{path.stem}: a foot starts {-heights.min():.4f} m below the floor"
