"""OpenSHC parameter files (ROS YAML) → shc TOML robot, gait and auto-pose files.

The robot file: every parameter shc supports, under its shc name (docs/robot-files.md §7 lists the pairs). Legs
share one ``[templates.leg]`` holding each DH value, limit and packed pose that most legs have; a leg lists only
what differs from it (OpenSHC's insectoid Bullet: the front-right coxa limit and the left legs' mirrored signs).
Parameters shc has no use for (hardware interface switches, debug flags) are listed at the top of the file and
printed. Physics-only fields (masses, servo model) are absent in OpenSHC: the masses come from the robot's URDF or
xacro when one is given (:func:`masses_from_urdf`: the body is every link no joint moves, each joint moves its
child link and what is fixed to it); without one the import warns that the robot weighs shc's placeholder 1 kg.
"""

from __future__ import annotations

import logging
from collections import Counter
from pathlib import Path
from typing import Any

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.robot import ADJUSTABLE_ADMITTANCE, ADJUSTABLE_WALKER
from shc_cli.spec.toml_out import dump_toml

SIMPLE = {
    # OpenSHC name: (shc table, shc name)
    "body_clearance": ("walker", "body_clearance"),
    "velocity_input_mode": ("walker", "velocity_input_mode"),
    "body_velocity_scaler": ("walker", "body_velocity_scaler"),
    "overlapping_walkspaces": ("walker", "overlapping_walkspaces"),
    "force_normal_touchdown": ("walker", "force_normal_touchdown"),
    "gravity_aligned_tips": ("walker", "gravity_aligned_tips"),
    "rough_terrain_mode": ("walker", "rough_terrain_mode"),
    "force_cruise_velocity": ("cruise", "force_velocity"),
    "angular_cruise_velocity": ("cruise", "angular"),
    "cruise_control_time_limit": ("cruise", "time_limit"),
    "clamp_joint_positions": ("ik", "clamp_joint_positions"),
    "clamp_joint_velocities": ("ik", "clamp_joint_velocities"),
    "ignore_IK_warnings": ("ik", "ignore_warnings"),
    "manual_posing": ("pose", "manual"),
    "auto_posing": ("pose", "auto"),
    "auto_pose_type": ("pose", "auto_pose_type"),
    "inclination_posing": ("pose", "inclination"),
    "imu_posing": ("pose", "imu"),
    "max_translation_velocity": ("pose", "max_translation_velocity"),
    "max_rotation_velocity": ("pose", "max_rotation_velocity"),
    "start_up_sequence": ("start_up", "sequence"),
    "time_to_start": ("start_up", "time_to_start"),
    "leg_manipulation_mode": ("manipulation", "mode"),
    "admittance_control": ("admittance", "enabled"),
    "dynamic_stiffness": ("admittance", "dynamic_stiffness"),
    "use_joint_effort": ("admittance", "use_joint_effort"),
    "integrator_step_time": ("admittance", "integrator_step_time"),
    "load_stiffness_scaler": ("admittance", "load_stiffness_scaler"),
    "swing_stiffness_scaler": ("admittance", "swing_stiffness_scaler"),
    "touchdown_threshold": ("admittance", "touchdown_threshold"),
    "liftoff_threshold": ("admittance", "liftoff_threshold"),
}
"""One-to-one parameters."""
STRUCTURED = {"rotation_pid_gains", "max_translation", "max_rotation", "linear_cruise_velocity", "gait_type",
              "leg_id", "joint_id", "link_id", "leg_DOF", "time_delta", "syropod_type",
              *ADJUSTABLE_WALKER, *ADJUSTABLE_ADMITTANCE}
"""Parameters mapped with some reshaping (below)."""

log = logging.getLogger(__name__)

Masses = tuple[float, dict[str, dict[str, float]]]
"""The body's mass and each leg's joints' masses [kg] (:func:`masses_from_urdf`)."""


def _read_yaml(path: Path, section: str) -> dict[str, Any]:
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError

    try:
        data = YAML(typ="safe").load(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise SpecError([Issue(path, None, "", "file not found", "check the path")]) from None
    except YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        line = mark.line + 1 if mark is not None else None
        raise SpecError([Issue(path, line, "", f"YAML syntax error: {getattr(error, 'problem', error)}",
                               "fix the YAML")]) from None
    node = data.get("syropod", {}) if isinstance(data, dict) else {}
    if not isinstance(node, dict) or section not in node:
        raise SpecError([Issue(path, None, "", f"no syropod.{section} in this file",
                               f"give an OpenSHC {section.replace('_', ' ')} file")])
    result: dict[str, Any] = node[section]
    return result


def _number(value: Any) -> Any:
    """YAML integers where shc expects floats stay exact; keep ints for int fields by the caller."""
    return float(value) if isinstance(value, int) and not isinstance(value, bool) else value


def _dh(values: dict[str, Any]) -> dict[str, float]:
    return {key: float(values[key]) for key in ("d", "theta", "r", "alpha")}


def robot_from_openshc(params: dict[str, Any], name: str, masses: Masses | None = None
                       ) -> tuple[dict[str, Any], list[str]]:
    """The shc robot table tree of OpenSHC ``syropod.parameters`` (with ``masses`` when given), and the
    parameters shc does not use."""
    legs_out: dict[str, Any] = {}
    joint_ids = list(params["joint_id"])
    used = set(SIMPLE) | STRUCTURED
    for leg in params["leg_id"]:
        dof = int(params["leg_DOF"][leg])
        joints: dict[str, Any] = {}
        used.add(f"{leg}_base_link_parameters")
        used.add(f"{leg}_stance_position")
        for joint in joint_ids[:dof]:
            link_key, joint_key = f"{leg}_{joint}_link_parameters", f"{leg}_{joint}_joint_parameters"
            used |= {link_key, joint_key}
            spec = params[joint_key]
            numbered = [float(spec[k]) for k in sorted(spec) if k.startswith("packed_")]
            packed = [float(spec["packed"])] if "packed" in spec else numbered
            joints[joint] = {**_dh(params[link_key]), "min": float(spec["min"]), "max": float(spec["max"]),
                             "offset": float(spec.get("offset", 0.0)), "packed": packed,
                             "unpacked": float(spec.get("unpacked", 0.0)), "max_vel": float(spec["max_vel"])}
            if masses is not None:
                joints[joint]["mass"] = masses[1][leg][joint]
        stance = params[f"{leg}_stance_position"]
        legs_out[leg] = {"base": _dh(params[f"{leg}_base_link_parameters"]), "joints": joints,
                         "stance": {"x": float(stance["x"]), "y": float(stance["y"])}}
    tree: dict[str, Any] = {"name": name, "description": f"imported from OpenSHC parameters ({name})",
                            "time_delta": float(params["time_delta"])}
    if masses is not None:
        tree["body"] = {"mass": masses[0]}
    for key, (table, field) in SIMPLE.items():
        if key in params:
            tree.setdefault(table, {})[field] = _number(params[key])
    walker = tree.setdefault("walker", {})
    walker["gait"] = str(params.get("gait_type", "tripod_gait")).removesuffix("_gait")
    for key in ADJUSTABLE_WALKER:
        if key in params:
            walker[key] = {k: float(params[key][k]) for k in ("default", "min", "max", "step")}
    admittance = tree.setdefault("admittance", {})
    for key in ADJUSTABLE_ADMITTANCE:
        if key in params:
            admittance[key] = {k: float(params[key][k]) for k in ("default", "min", "max", "step")}
    if "linear_cruise_velocity" in params:
        tree.setdefault("cruise", {})["linear"] = [float(params["linear_cruise_velocity"]["x"]),
                                                   float(params["linear_cruise_velocity"]["y"])]
    pose = tree.setdefault("pose", {})
    for key in ("rotation_pid_gains", "max_translation", "max_rotation"):
        if key in params:
            pose[key] = {k: float(v) for k, v in params[key].items()}
    tree["templates"], tree["legs"] = _factor_legs(legs_out)
    unused = sorted(k for k in params if k not in used)
    return tree, unused


def _flatten(node: Any, prefix: tuple[str, ...] = ()) -> dict[tuple[str, ...], Any]:
    if isinstance(node, dict):
        out: dict[tuple[str, ...], Any] = {}
        for key, value in node.items():
            out.update(_flatten(value, (*prefix, key)))
        return out
    return {prefix: node}


def _nest(flat: dict[tuple[str, ...], Any]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for path, value in flat.items():
        node = out
        for key in path[:-1]:
            node = node.setdefault(key, {})
        node[path[-1]] = value
    return out


def _factor_legs(legs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """A ``leg`` template of the values most legs share; each leg keeps its stance and what differs."""
    flats = {leg: _flatten({k: v for k, v in spec.items() if k != "stance"}) for leg, spec in legs.items()}
    paths = [path for path in flats[next(iter(flats))] if all(path in f for f in flats.values())]
    template: dict[tuple[str, ...], Any] = {}
    for path in paths:
        counts = Counter(repr(f[path]) for f in flats.values())
        value, times = counts.most_common(1)[0]
        if times > 1:
            template[path] = next(f[path] for f in flats.values() if repr(f[path]) == value)
    out: dict[str, Any] = {}
    for leg, flat in flats.items():
        own = {path: value for path, value in flat.items() if path not in template or template[path] != value}
        out[leg] = {"template": "leg", **_nest(own), "stance": legs[leg]["stance"]}
    return {"leg": _nest(template)}, out


def gaits_from_openshc(params: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """OpenSHC ``syropod.gait_parameters`` → shc gait tables by name."""
    out = {}
    for key, gait in params.items():
        name = key.removesuffix("_gait")
        out[name] = {"name": name, "description": f"imported from OpenSHC gait parameters ({key})",
                     "stance_phase": int(gait["stance_phase"]), "swing_phase": int(gait["swing_phase"]),
                     "phase_offset": int(gait["phase_offset"]),
                     "offset_multiplier": {leg: int(v) for leg, v in gait["offset_multiplier"].items()}}
    return out


def poses_from_openshc(params: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """OpenSHC ``syropod.auto_pose_parameters`` → shc auto-pose set tables by name."""
    out = {}
    for key, spec in params.items():
        name = key.removesuffix("_pose").removesuffix("_gait")
        posers = []
        for i, (start, end) in enumerate(zip(spec["pose_phase_starts"], spec["pose_phase_ends"], strict=True)):
            poser: dict[str, Any] = {"start": int(start), "end": int(end)}
            for axis in ("x", "y", "z", "roll", "pitch", "yaw", "gravity"):
                value = float(spec.get(f"{axis}_amplitudes", [0.0] * (i + 1))[i])
                if value != 0.0:
                    poser[axis] = value
            posers.append(poser)
        ratios = spec.get("negation_transition_ratio", {})
        negation = {leg: {"start": int(start), "end": int(spec["pose_negation_phase_ends"][leg]),
                          "transition_ratio": float(ratios.get(leg, 0.0))}
                    for leg, start in spec["pose_negation_phase_starts"].items()}
        out[name] = {"name": name, "description": f"imported from OpenSHC auto-pose parameters ({key})",
                     "pose_frequency": float(spec["pose_frequency"]),
                     "pose_phase_length": int(spec["pose_phase_length"]), "poser": posers, "negation": negation}
    return out


def masses_from_urdf(path: Path, params: dict[str, Any]) -> Masses:
    """The masses of the robot OpenSHC's ``params`` describe, from its URDF or xacro at ``path``: the body is every
    link no movable joint moves (the base link and what is fixed to it: Bullet's base motors), each joint of
    ``params`` (URDF joint ``<LEG>_<joint>_joint`` or ``<LEG>_<joint>``) moves its child link and the links fixed
    below it. One-line SpecError for a joint the URDF does not have."""
    import xml.etree.ElementTree as ET

    from shc_cli.interop.urdf_import_source import read_source

    root = ET.fromstring(read_source(path, {}, 0.0).text)
    mass = {link.get("name", ""): float(m.get("value", 0.0)) if (m := link.find("inertial/mass")) is not None
            else 0.0 for link in root.findall("link")}
    children: dict[str, list[tuple[str, bool]]] = {}
    joints: dict[str, str] = {}
    moved: set[str] = set()
    for joint in root.findall("joint"):
        parent, child = joint.find("parent"), joint.find("child")
        if parent is None or child is None:
            continue
        fixed = joint.get("type") == "fixed"
        children.setdefault(parent.get("link", ""), []).append((child.get("link", ""), fixed))
        joints[joint.get("name", "")] = child.get("link", "")
        if not fixed:
            moved.add(child.get("link", ""))

    def rigid(link: str) -> float:  # the link and the links fixed to it, down to the next movable joint
        return mass.get(link, 0.0) + sum(rigid(child) for child, fixed in children.get(link, []) if fixed)

    below = {link for top in moved for link in _subtree(top, children)}
    body = sum(value for link, value in mass.items() if link not in below)
    legs: dict[str, dict[str, float]] = {}
    for leg in params["leg_id"]:
        legs[leg] = {}
        for joint in list(params["joint_id"])[:int(params["leg_DOF"][leg])]:
            link = joints.get(f"{leg}_{joint}_joint", joints.get(f"{leg}_{joint}"))
            if link is None:
                raise SpecError([Issue(path, None, "", f"no joint {leg}_{joint}_joint (or {leg}_{joint}) for "
                                       f"OpenSHC's {leg} {joint}", "give the URDF or xacro of the same robot")])
            legs[leg][joint] = round(rigid(link), 6)
    if body <= 0.0:
        raise SpecError([Issue(path, None, "", "no mass on the links no joint moves (the body)",
                               "give a URDF whose base link has an <inertial><mass>")])
    return round(body, 6), legs


def _subtree(top: str, children: dict[str, list[tuple[str, bool]]]) -> list[str]:
    out, todo = [], [top]
    while todo:
        link = todo.pop()
        out.append(link)
        todo += [child for child, _ in children.get(link, [])]
    return out


def import_openshc(robot_yaml: Path, gait_yaml: Path | None, pose_yaml: Path | None, out: Path,
                   urdf: Path | None = None, overwrite: bool = False) -> list[Path]:
    """Write ``out/robots/NAME.toml`` (+ ``out/gaits/*.toml``, ``out/poses/*.toml``); returns the files, each
    checked by loading it back. The robot is named after the YAML file; its ``[hardware.servos]`` is the servo map
    of :mod:`shc_cli.interop.servo_map` (ids numbered, to check). Its masses come from ``urdf`` (the robot's URDF
    or xacro, :func:`masses_from_urdf`); without it a warning says the robot has shc's placeholder masses. Files
    that exist are refused before anything is written, unless ``overwrite`` (the one output rule)."""
    from shc_cli.interop.servo_map import servo_table, with_check_note
    from shc_cli.outputs import refuse_existing, write_text
    from shc_cli.spec.loading import load_robot
    from shc_cli.validation import check_robot

    params = _read_yaml(robot_yaml, "parameters")
    name = robot_yaml.stem
    try:
        masses = masses_from_urdf(urdf, params) if urdf is not None else None
        tree, unused = robot_from_openshc(params, name, masses)
    except (KeyError, TypeError, ValueError) as error:
        raise SpecError([Issue(robot_yaml, None, "", f"missing or malformed OpenSHC parameter: {error}",
                               "compare with bullet_syropod/config/bullet_insectoid.yaml")]) from None
    written = []
    header = [f"# Imported by `shc import openshc` from {robot_yaml.name}"
              + (f", masses from {urdf.name}." if urdf is not None else ".")]
    if unused:
        header.append(f"# OpenSHC parameters shc does not use: {', '.join(unused)}.")
    if masses is None:
        header.append("# OpenSHC's parameters carry no masses: body.mass is shc's placeholder 1 kg and the links have "
                      "none (import again with --urdf FILE, or set them).")
    gaits = gaits_from_openshc(_read_yaml(gait_yaml, "gait_parameters")) if gait_yaml is not None else {}
    poses = poses_from_openshc(_read_yaml(pose_yaml, "auto_pose_parameters")) if pose_yaml is not None else {}
    robot_path = out / "robots" / f"{name}.toml"
    refuse_existing([robot_path, *(out / "gaits" / f"{g}.toml" for g in gaits),
                     *(out / "poses" / f"{p}.toml" for p in poses)], overwrite)
    if gait_yaml is not None:
        for gait_name, gait in gaits.items():
            path = out / "gaits" / f"{gait_name}.toml"
            write_text(path, f"# Imported by `shc import openshc` from {gait_yaml.name}.\n{dump_toml(gait)}")
            written.append(path)
        if tree["walker"]["gait"] in gaits:  # the imported gait file, next to the robot's folder
            tree["walker"]["gait"] = f"../gaits/{tree['walker']['gait']}.toml"
    write_text(robot_path, "\n".join(header) + "\n" + dump_toml(tree))
    legs = {leg: list(spec.joints) for leg, spec in load_robot(robot_path).robot.legs.items()}
    tree["hardware"] = servo_table(legs)  # the servo map (OpenSHC keeps it elsewhere): numbered, to check
    write_text(robot_path, "\n".join(header) + "\n" + with_check_note(dump_toml(tree)))
    loaded = load_robot(robot_path)
    problems = check_robot(loaded)
    if problems:
        raise SpecError(problems)
    written.insert(0, robot_path)
    if masses is None:
        log.warning("warning: %s: OpenSHC's parameters carry no masses, so the robot weighs shc's placeholder %.2f kg "
                    "(a 1 kg body, massless links): simulated power and cost of transport are not the robot's; give "
                    "its URDF or xacro with --urdf FILE, or set body.mass and each joint's mass", robot_path,
                    loaded.robot.total_mass())
    if pose_yaml is not None:
        for set_name, pose_set in poses.items():
            path = out / "poses" / f"{set_name}.toml"
            write_text(path, f"# Imported by `shc import openshc` from {pose_yaml.name}.\n{dump_toml(pose_set)}")
            written.append(path)
    return written
