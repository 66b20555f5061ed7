"""``shc import urdf``: a legged robot's URDF (or xacro) → an shc robot file with its servo map.

* **Body**: the URDF's root link and every link fixed to it. shc's ``base_link`` is the URDF link
  ``base_link`` if it is one of them, else the root; the body's mass, centre of mass and principal moments
  (the diagonal of the summed inertia) are those of these links; its box is the collision box of the base
  link, else the box around the hips.
* **Legs**: the serial chains from the body to each leaf link that pass a revolute joint (``--legs auto``); a
  leaf whose moving joints are all on a longer chain (a sensor fixed to a femur) is not a leg of its own, and
  of leaves on the same joints the one with a sphere (else the deepest) is the foot. Fixed joints fold into
  the transforms. ``--legs LINK,…`` (or ``ID=LINK,…``) names the tip links instead, ``--tip PATTERN[@X,Y,Z]``
  names tip links by glob pattern and the tip point in their frame.
* **Tip**: the centre of the tip link's first collision sphere, else its frame origin (``--tip`` names it); a
  frame origin on the last joint's axis (a tibia frame on the knee and no foot frame) is replaced by the point of
  the link's mesh farthest from that axis, else by the end of its cylinders and boxes (collision or visual)
  farthest from it, else the import is refused with the ``--tip`` that would fix it.
* **What is not a leg** (:mod:`shc_cli.interop.urdf_import_clean`): sensor stand-ins and dummy foot joints are
  fixed, head and camera chains left out, placeholder inertias and speed limits replaced (and named), and a
  body frame whose +x points at a leg turned a quarter (``--forward`` chooses). Axes less than
  nearly parallel axes are snapped without being asked (:data:`SNAP_STEPS`, if the tips move less than
  :data:`SNAP_MOVE` of a leg's length; the note says by how much).
* **Detached parts** (:mod:`shc_cli.interop.urdf_import_detached`): links hanging off the root by floating
  joints (a CAD export's feet) are fixed to the leg ends they sit at, else refused naming them.
* **Servo map**: ``[hardware.servos]`` (:mod:`shc_cli.interop.servo_map`): ids numbered, each joint's URDF name.
* **DH**: :mod:`shc_cli.interop.urdf_import_dh`: exact for any axes; URDF angle = shc angle.
* **Leg ids** by position (the mean of the leg's joint origins and tip at the zero pose: a joint's origin may
  be anywhere on its axis), clockwise from the front right: with as many legs on the right (y < 0) as on the
  left, ``AR, BR, …`` down the right side and ``…, BL, AL`` up the left
  (4 legs: AR BR BL AL, 6: AR BR CR CL BL AL, 8: AR BR CR DR DL CL BL AL); otherwise ``L1 … Ln`` in that order.
* **Joint names**: the URDF names without what all joints of the leg share (``AR_coxa_joint`` → ``coxa``), else
  ``joint1 …``.
* **Limits**: URDF ``lower``/``upper``, ``velocity`` → ``max_vel``, the most common ``effort`` and ``velocity``
  → ``servo.stall_torque`` and ``servo.no_load_speed``. **Masses**: each joint carries the links it moves
  up to the next joint of its leg; links moved by joints that are in no leg count as body (listed).
* **Stance**: candidates are tried in order and the first whose walkspace (``shc workspace``'s smallest radius) is
  within 5 % of the best is taken; every leg must reach its foot, and the swing apex a fifth of the clearance above
  it, within its limits, with no joint below the feet (knees in the ground). If the zero pose's feet stand below the
  hips (by at least a quarter of the leg's length), the candidates are the zero pose and the body lowered to 0.9 …
  0.6 of the feet's depth (not the zero pose itself if a leg is straight there: a singular pose). Otherwise, or if
  none of those is reachable, each foot is put 0.5, 0.4, 0.6, 0.3, 0.7 or 0.2 of the leg's length out from its hip
  (along the zero pose's leg direction) with the body as many shares of a leg's length above the hips, then (a knee
  limit that keeps the leg nearly straight) 0.75 … 0.9 out with the body 0.05 … 0.7 of it above the hips; then
  (narrow limits) the feet where every joint is at the centre of its range, then where the first three joints are at
  0.3, 0.5 or 0.7 of theirs, with the swing height as high as the limits lift every foot (at least 1 cm) if a fifth
  of the clearance is too high; a refusal names the leg and the limits that stop it. ``--clearance`` and ``--reach``
  fix either (a stance they ask for that a leg cannot take is refused naming the leg, the joint limit and the range
  that stands). ``unpacked`` is the pose the IK finds there from every joint at 0, else (a zero pose far from any
  stance: legs straight up) from each leg's pose nearest its foot among :data:`SEED_POSES` spread over its joint
  ranges.
"""
from __future__ import annotations

import math
import re
import tempfile
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.errors import SpecError
from shc_cli.interop.servo_map import guess_model, servo_angle_range, servo_table, with_check_note
from shc_cli.interop.urdf_import_clean import (
    ON_AXIS,
    SERVO_MASS,
    WHOLE_TURN,
    dummy_tail,
    forward_turn,
    leg_chains,
    open_continuous,
    placeholders,
    stub_joints,
)
from shc_cli.interop.urdf_import_detached import attach_detached
from shc_cli.interop.urdf_import_dh import Axis, NearlyParallel, chain_dh
from shc_cli.interop.urdf_import_source import SUGGESTED_SNAP, parse_urdf, read_source
from shc_cli.interop.urdf_import_stance import _finish, _length
from shc_cli.interop.urdf_import_tip import _mesh_tip, _off_axis, _tip_hint, primitive_tip
from shc_cli.interop.urdf_import_tree import (
    Imported,
    LegChain,
    TipSpec,
    Tree,
    _body,
    _dh_values,
    _fail,
    _inertial,
    _moved_by,
    _round,
    find_legs,
    joint_names,
    leg_ids,
    turn,
)
from shc_cli.spec.toml_out import dump_toml

FloatArray = NDArray[np.float64]


GAITS = {4: "quad_wave", 6: "tripod", 8: "octo_alternating"}
"""Gait written for a robot with this many legs (others get ``wave``, which fits none but six legs)."""
SNAP_STEPS = (0.001, 0.002, 0.005, 0.01, 0.02)
"""Snap tolerances tried in turn without being asked when two axes are nearly parallel [rad] (1.57 is 0.0008
from π/2, 3.14 0.0016 from π); the first that makes every leg's axes parallel or skew enough is kept."""
SNAP_MOVE = 0.005
"""An automatic snap is kept only if it moves no tip (against the unsnapped URDF, at random joint vectors) more
than this share of the longest leg's length; beyond, the import refuses naming the ``--snap`` that accepts it."""
BEYOND = (0.05, 0.1, 0.2)
"""Snap tolerances tried only to name a ``--snap`` in a refusal when none of :data:`SNAP_STEPS` helps [rad]."""
FK_SAMPLES = 200
"""Random joint vectors per leg of the forward-kinematics check after writing."""


# -- the robot -------------------------------------------------------------------------------------------------


def import_tree(model: Any, file: Path, name: str, legs: str = "auto", tips: list[TipSpec] | None = None,
                clearance: float | None = None, reach: float | None = None, forward: float | None = None,
                stubs: dict[str, str] | None = None, opened: list[str] | None = None,
                base: str | None = None) -> Imported:
    """The shc robot table tree of a parsed URDF (module docstring).

    ``forward``: the turn of the shc body frame from base_link about z [rad] (None: π/2 if the legs' layout says
    the URDF's +x is not forward, :func:`~shc_cli.interop.urdf_import_clean.forward_turn`, else 0)."""
    stubs = stub_joints(model.robot.joints) if stubs is None else stubs
    opened = open_continuous(model.robot.joints) if opened is None else opened
    tree = Tree(model, stubs, forward or 0.0, base)
    found = find_legs(tree, legs, tips or [], file)
    notes: list[str] = [f"{joint} is taken as fixed: {why}" for joint, why in stubs.items()]
    if tree.base_note:
        notes.append(tree.base_note)
    if tree.skipped:
        notes.append(f"the root {tree.skipped[0]} holds the robot by a free joint: the body starts at {tree.root}")
    for _, chain in found:
        _trace(tree, chain, file, notes)
    if legs == "auto" and not tips:
        kept = leg_chains([len(c.joints) for _, c in found], [_length(c) for _, c in found])
        if len(kept) < len(found):
            notes.append("chains left out as not legs (their links count as body): "
                         + ", ".join(f"{c.end} ({len(c.joints)} joints)" for i, (_, c) in enumerate(found)
                                     if i not in kept))
            found = [found[i] for i in kept]
    chains = [chain for _, chain in found]
    on_axis = [chain for chain in chains if abs(chain.rows[-1].r) < ON_AXIS]
    refusal = None
    if on_axis:
        refusal = (f"the tip of the leg to {on_axis[0].end} ({on_axis[0].tip_source}) lies on the axis of "
                   f"{on_axis[0].joints[-1].name}, which then does not move it (a link frame on the joint axis and no "
                   "foot frame after it)", f"name the tip point with {_tip_hint(tree, on_axis)}")
    if forward is None and legs == "auto":
        yaw = forward_turn([np.mean([c.hip, *c.points, c.tip], axis=0) for c in chains])
        if yaw:
            again = import_tree(model, file, name, legs, tips, clearance, reach, yaw, stubs, opened, base)
            quarter = abs(abs(yaw) - math.pi / 2) < 1e-9
            way = (f"base_link's {'+y' if yaw > 0 else '-y'}" if quarter else
                   f"{math.degrees(yaw):g} deg from base_link's +x towards {'+y' if yaw > 0 else '-y'}, halfway "
                   "between two legs")
            again.notes.append(f"the URDF's +x points at a leg (legs straight ahead and behind): shc's forward is "
                               f"{way} (--forward +x keeps the URDF's)")
            return again
    ids, order = leg_ids([np.mean([chain.hip, *chain.points, chain.tip], axis=0) for chain in chains])
    for (given, chain), leg_id in zip(found, ids, strict=True):
        chain.leg_id = given or leg_id
    if legs != "auto" and all(given for given, _ in found):
        order = list(range(len(chains)))  # --legs ID=LINK,…: the order given
    chains = [chains[i] for i in order]
    if len({c.leg_id for c in chains}) < len(chains):
        raise _fail(file, "two legs have the same id", "give each leg its own id in --legs ID=LINK,…")
    for chain, names in zip(chains, joint_names([[j.name for j in c.joints] for c in chains]), strict=True):
        chain.names = names
    # Masses: every link goes to the last moving joint above it; links of no leg's joints go to the body.
    leg_joints = {j.name: (chain, k) for chain in chains for k, j in enumerate(chain.joints)}
    for chain in chains:
        chain.masses = [0.0] * len(chain.joints)
    extra, unused = [], []
    for link in tree.links:
        if link in tree.body:
            continue
        mover = _moved_by(tree, link)
        part = _inertial(tree, link)
        if mover in leg_joints:
            owner, k = leg_joints[mover]
            owner.masses[k] += part[0] if part is not None else 0.0
        else:
            extra.append(link)
    for joint in tree.joints.values():
        if not tree.is_fixed(joint) and joint.name not in leg_joints:
            unused.append(joint.name)
    body, body_notes = _body(tree, extra, [c.hip for c in chains])
    notes += body_notes
    parts = [p for p in (_inertial(tree, link) for link in tree.links) if p is not None]
    found_placeholders = placeholders(
        [p[0] for p in parts], [float(np.linalg.eigvalsh(p[2]).max()) for p in parts], [_length(c) for c in chains],
        [float(j.limit.velocity) for c in chains for j in c.joints if j.limit.velocity],
        [float(j.limit.effort) for c in chains for j in c.joints if j.limit.effort])
    notes += found_placeholders.notes
    if found_placeholders.masses:
        for chain in chains:
            chain.masses = [SERVO_MASS] * len(chain.joints)
        body.pop("com", None)
        body.pop("inertia", None)
        body["mass"] = _round(SERVO_MASS * sum(len(c.joints) for c in chains), 6)
    continuous = [j.name for c in chains for j in c.joints if j.name in opened]
    if continuous:
        notes.append(f"{len(continuous)} leg joints are continuous in the URDF ({_names(continuous)}): a continuous "
                     f"joint is revolute without limits, so they get {WHOLE_TURN[0]:.4g} … {WHOLE_TURN[1]:.4g} rad "
                     "(a whole turn; the stance and the walk choose angles inside it); write your servos' limits")
    if unused:
        notes.append(f"URDF joints in no leg (their links count as body): {', '.join(sorted(unused))}")
    efforts = Counter(j.limit.effort for c in chains for j in c.joints if j.limit.effort)
    speeds = Counter(j.limit.velocity for c in chains for j in c.joints if j.limit.velocity)
    servo: dict[str, Any] = {"model": "from the URDF's joint limits"}
    if efforts:
        servo["stall_torque"] = float(efforts.most_common(1)[0][0])
        if len(efforts) > 1:
            notes.append(f"joint efforts differ ({', '.join(f'{e:g}' for e in sorted(efforts))} N·m): "
                         "servo.stall_torque is the most common")
    if speeds:
        servo["no_load_speed"] = float(speeds.most_common(1)[0][0])
    if found_placeholders.speed is not None:
        servo["no_load_speed"] = found_placeholders.speed
    if found_placeholders.torque is not None:
        servo["stall_torque"] = found_placeholders.torque
    legs_out: dict[str, Any] = {}
    low, high = servo_angle_range(guess_model(servo.get("stall_torque")))
    narrowed: list[str] = []
    for chain in chains:
        joints = {}
        for joint_name, joint, row, mass in zip(chain.names, chain.joints, chain.rows, chain.masses, strict=True):
            entry: dict[str, Any] = {**_dh_values(row), "min": float(joint.limit.lower or 0.0),
                                     "max": float(joint.limit.upper or 0.0)}
            if entry["min"] < low or entry["max"] > high:
                narrowed.append(f"{chain.leg_id}_{joint_name} {entry['min']:g}..{entry['max']:g}")
                entry["min"], entry["max"] = max(entry["min"], low), min(entry["max"], high)
            if found_placeholders.speed is not None:
                entry["max_vel"] = found_placeholders.speed
            elif joint.limit.velocity:
                entry["max_vel"] = float(joint.limit.velocity)
            entry["mass"] = _round(mass, 6)
            joints[joint_name] = entry
        assert chain.base is not None
        legs_out[chain.leg_id] = {"base": _dh_values(chain.base),
                                  "foot_radius": _round(chain.sphere, 6), "joints": joints}
    if narrowed:
        guessed = guess_model(servo.get("stall_torque"))
        notes.append(f"{len(narrowed)} joint limits wider than one turn of the servo map's {guessed} "
                     f"({low:.4f}..{high:.4f} rad) narrowed to it ({', '.join(narrowed[:3])}"
                     f"{', …' if len(narrowed) > 3 else ''} rad): the servo model is a guess; a multi-turn actuator "
                     "takes hardware.model = \"generic\" and the URDF's limits")
    gait = GAITS.get(len(chains), "wave")
    from shc_cli.spec.loading import load_gait

    named = load_gait(gait).gait
    if named is not None and set(named.offset_multiplier) != {c.leg_id for c in chains}:
        notes.append(f"walker.gait '{gait}' names legs {', '.join(named.offset_multiplier)}, not these: write a gait "
                     "file for them (docs/robot-files.md section 5) before shc validate, plan or simulate")
    tree_out: dict[str, Any] = {"name": name, "description": f"imported from {file.name} by shc import urdf",
                                "time_delta": 0.01, "body": body, "walker": {"gait": gait}, "servo": servo,
                                "legs": legs_out}
    return Imported(tree_out, chains, tree.base_frame, notes, tree.yaw, refusal)


def _trace(tree: Tree, chain: LegChain, file: Path, notes: list[str]) -> None:
    """The chain's axes, tip and DH rows; dummy joints at its foot become fixed (``tree.fixed``)."""
    axes = []
    for joint in chain.joints:
        frame = tree.joint_frame(joint)
        axis = np.array([1.0, 0.0, 0.0]) if joint.axis is None else np.asarray(joint.axis, dtype=float)
        if not np.linalg.norm(axis) > 0.0:
            raise _fail(file, f"joint {joint.name} has the axis (0, 0, 0)", "give it a direction, e.g. xyz=\"0 0 1\"")
        axes.append(Axis(frame[:3, 3].copy(), frame[:3, :3] @ (axis / np.linalg.norm(axis))))
    chain.tip = (tree.pose[chain.end] @ np.append(chain.tip_local, 1.0))[:3]
    dummies = dummy_tail([a.point for a in axes], [a.direction for a in axes], chain.tip)
    if dummies:
        for joint in chain.joints[-dummies:]:
            tree.fixed[joint.name] = "a joint at the foot whose axis passes through the tip (it moves nothing)"
        notes.append(f"{', '.join(j.name for j in chain.joints[-dummies:])} at the foot of the leg to {chain.end} "
                     "pass through the tip: taken as fixed")
        chain.joints, axes = chain.joints[:-dummies], axes[:-dummies]
    if chain.tip_source.startswith("the origin of") and _off_axis(chain.tip, axes[-1]) < ON_AXIS:
        found = _mesh_tip(tree, chain.end, axes[-1], file) or primitive_tip(tree, chain.end, axes[-1])
        if found is not None:
            chain.tip, chain.tip_source = found
            chain.tip_local = (np.linalg.inv(tree.pose[chain.end]) @ np.append(chain.tip, 1.0))[:3]
    chain.hip = axes[0].point
    chain.points = [a.point for a in axes[1:]]
    if len(axes) > 6:
        raise _fail(file, f"the leg to {chain.end} has {len(axes)} revolute joints; shc legs have 1 to 6",
                    "name a link nearer the body with --tip")
    try:
        chain.base, chain.rows = chain_dh(axes, chain.tip)
    except NearlyParallel as error:
        names = ["base_link z", *[j.name for j in chain.joints]]
        raise NeedsSnap(f"axes of {names[error.index]} and {names[error.index + 1]} are {error.angle:.2g} rad from "
                        f"parallel: the DH table would need an offset of {error.offset:.3g} m",
                        max(error.angle * 2, SUGGESTED_SNAP)) from None


def _names(names: list[str], shown: int = 3) -> str:
    """The first ``shown`` names and how many more."""
    return ", ".join(names[:shown]) + (f" and {len(names) - shown} more" if len(names) > shown else "")


class NeedsSnap(Exception):
    """Two axes of a leg are nearly parallel: the URDF needs snapping (by at least ``snap`` rad) to import."""

    def __init__(self, problem: str, snap: float) -> None:
        super().__init__(problem)
        self.problem, self.snap = problem, snap


def factor_legs(legs: dict[str, Any]) -> tuple[dict[str, Any], dict[str, Any]]:
    """Templates of the values legs with the same joints share; each leg keeps its stance and what differs.

    Legs with the same joint names use one template (``leg``, or ``leg_a``, ``leg_b``, … for several kinds);
    a value goes to the template when at least two of its legs have it (as ``shc import openshc`` does)."""
    from shc_cli.interop.openshc import _factor_legs

    kinds: dict[tuple[str, ...], list[str]] = {}
    for leg_id, spec in legs.items():
        kinds.setdefault(tuple(spec["joints"]), []).append(leg_id)
    templates, out = {}, {}
    for index, members in enumerate(kinds.values()):
        label = "leg" if len(kinds) == 1 else f"leg_{chr(ord('a') + index)}"
        template, factored = _factor_legs({leg_id: legs[leg_id] for leg_id in members})
        templates[label] = template["leg"]
        for leg_id, spec in factored.items():
            out[leg_id] = {**spec, "template": label}
    return templates, {leg_id: out[leg_id] for leg_id in legs}


def fk_error(model: Any, legs: list[LegChain], base_frame: str, robot: Any, samples: int = FK_SAMPLES,
             seed: int = 0, yaw: float = 0.0) -> float:
    """Largest tip distance between the robot's DH chains and the URDF model (yourdfpy) at random joint
    vectors inside the limits, every leg [m]."""
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(seed)
    worst = 0.0
    for _ in range(samples):
        q = rng.uniform(chains.lower, chains.upper)
        cfg = {name: 0.0 for name in model.actuated_joint_names}
        for i, chain in enumerate(legs):
            for k, joint in enumerate(chain.joints):
                cfg[joint.name] = float(q[i, k])
        model.update_cfg(cfg)
        ours = chains.tips(q)
        for i, chain in enumerate(legs):
            transform = turn(yaw).T @ np.asarray(model.get_transform(frame_to=chain.end, frame_from=base_frame),
                                                 dtype=float)
            theirs = (transform @ np.append(chain.tip_local, 1.0))[:3]
            worst = max(worst, float(np.linalg.norm(ours[i] - theirs)))
    return worst


def _tip_lines(legs: list[LegChain]) -> list[str]:
    """Header lines saying where each tip is; one line when every leg's is the same point of its own link."""
    generic = {leg.tip_source.replace(leg.end, "its leg's last link") for leg in legs}
    if len(generic) == 1:
        return [f"# Tip of every leg: {generic.pop()}."]
    return [f"# Tip of {leg.leg_id}: {leg.tip_source}." for leg in legs]


@dataclass(frozen=True)
class Result:
    """Files written and figures of one import."""

    robot_path: Path
    notes: list[str]
    fk_error: float
    fk_error_unsnapped: float
    snap: float
    pose_path: Path | None = None
    """The auto-pose set written for the robot (a quadruped walking quad_wave), if any."""
    tips: dict[str, tuple[str, FloatArray]] = field(default_factory=dict)
    """Each leg's first URDF joint → its tip link and the tip point in that link [m]."""
    base_frame: str = ""
    yaw: float = 0.0


def import_urdf(file: Path, out: Path | None = None, name: str | None = None, legs: str = "auto",
                tips: list[str] | None = None, clearance: float | None = None, reach: float | None = None,
                snap: float = 0.0, args: dict[str, str] | None = None, forward: float | None = None,
                base: str | None = None, given: str | None = None, command: str = "urdf",
                overwrite: bool = False) -> Result:
    """Write ``OUT/robots/NAME.toml`` (its ``[hardware.servos]`` the servo map, to check) from a URDF or xacro
    file; check the robot
    (``shc validate``'s checks) and its forward kinematics against the URDF before returning.

    A URDF that yourdfpy reads but whose numbers or structure the import cannot use (a link outside the tree, a
    zero-length chain, values the robot model refuses) is one line naming the file (found by
    ``tests/test_fuzz_inputs.py``). An existing robot (or pose) file is refused unless ``overwrite``, before anything
    is written (the output rule of every command)."""
    try:
        return _import_urdf(file, out, name, legs, tips, clearance, reach, snap, args, forward, base, given, command,
                            overwrite)
    except (ValueError, LookupError, ArithmeticError) as error:  # pydantic's ValidationError is a ValueError
        lines = str(error).strip().splitlines()
        raise _fail(file, f"cannot import it: {type(error).__name__}: {lines[0] if lines else ''}",
                    "check the URDF's links, joints, limits and inertias (check_urdf)") from None


def _import_urdf(file: Path, out: Path | None, name: str | None, legs: str, tips: list[str] | None,
                 clearance: float | None, reach: float | None, snap: float, args: dict[str, str] | None,
                 forward: float | None, base: str | None, given: str | None, command: str,
                 overwrite: bool) -> Result:
    from shc_cli.outputs import refuse_existing, write_text
    from shc_cli.spec.loading import load_gait, load_robot
    from shc_cli.validation import check_robot

    source = read_source(file, args or {}, snap, given)
    model, attached = _parse(file, source.snapped_text)
    robot_name = name or re.sub(r"[^A-Za-z0-9_-]", "_", str(model.robot.name or file.stem))
    out = out if out is not None else Path("imported") / robot_name
    tip_specs = [TipSpec.parse(t) for t in tips or []]
    needed: NeedsSnap | None = None
    try:
        imported = import_tree(model, file, robot_name, legs, tip_specs, clearance, reach, forward, base=base)
    except NeedsSnap as refused:
        needed = refused
        if snap > 0.0:
            raise _fail(file, needed.problem, f"snap the URDF's angles with --snap {needed.snap:.1g} or fix them")\
                from None
        for step in (*SNAP_STEPS, *BEYOND):
            source = read_source(file, args or {}, step, given)
            model, attached = _parse(file, source.snapped_text)
            try:
                imported = import_tree(model, file, robot_name, legs, tip_specs, clearance, reach, forward,
                                       base=base)
            except NeedsSnap:
                continue
            snap = step
            break
        else:
            raise _fail(file, f"{needed.problem}, and snapping angles by up to {BEYOND[-1]:g} rad does not make the "
                        "axes parallel", "fix the URDF's joint origins and axes") from None
        if snap > SNAP_STEPS[-1]:
            raise _fail(file, f"{needed.problem} (a skew the import does not snap on its own: snapping angles within "
                        f"{snap:g} rad of a multiple of pi/2 makes them parallel)",
                        f"accept that with --snap {snap:g}, or fix the URDF's angles") from None
    if imported.refusal is not None:
        raise _fail(file, *imported.refusal)
    imported.notes += [*attached, *source.warnings]
    imported.tree["description"] = f"imported from {file.name} by shc import {command}"
    _finish(imported, clearance, reach, file)
    imported.tree["templates"], imported.tree["legs"] = factor_legs(imported.tree["legs"])
    imported.tree["hardware"] = servo_table(
        {c.leg_id: c.names for c in imported.legs}, imported.tree["servo"].get("stall_torque"),
        {f"{c.leg_id}_{name}": joint.name for c in imported.legs for name, joint in zip(c.names, c.joints,
                                                                                      strict=True)})
    sway = _sway(imported, robot_name)
    keys = ("name", "description", "time_delta", "body", "walker", "pose", "servo", "templates", "legs", "hardware")
    tree: dict[str, Any] = {key: imported.tree[key] for key in keys if key in imported.tree}
    robot_path = out / "robots" / f"{robot_name}.toml"
    text = _header(file, imported, snap, source.snap, command) + with_check_note(dump_toml(tree))
    pose_path = out / "poses" / sway[0] if sway is not None else None
    refuse_existing([path for path in (robot_path, pose_path) if path is not None], overwrite)
    with tempfile.TemporaryDirectory() as folder:  # checked before anything is written
        draft = Path(folder) / "robots" / robot_path.name
        draft.parent.mkdir()
        draft.write_text(text, encoding="utf-8")
        loaded = load_robot(draft)
        problems = check_robot(loaded)
        if sway is not None:
            from shc_cli.spec.autopose import compatibility_issues, load_pose_set

            (Path(folder) / "poses").mkdir()
            (Path(folder) / "poses" / sway[0]).write_text(sway[1], encoding="utf-8")
            gait = load_gait(loaded.robot.walker.gait).gait
            problems += compatibility_issues(load_pose_set(POSES_FROM_ROBOT + sway[0], draft.parent), gait,
                                             list(loaded.robot.legs))
        if problems:
            raise SpecError(problems)
    error = fk_error(model, imported.legs, imported.base_frame, loaded.robot, yaw=imported.yaw)
    unsnapped = error
    if source.snap > 0.0:
        unsnapped = fk_error(_parse(file, source.text)[0], imported.legs, imported.base_frame, loaded.robot,
                             yaw=imported.yaw)
    if needed is not None:
        limit = SNAP_MOVE * max(_length(leg) for leg in imported.legs)
        moved = (f"angles within {snap:g} rad of a multiple of pi/2 snapped (--snap), which moves the tips "
                 f"{unsnapped:.2g} m at most")
        if unsnapped > limit:
            raise _fail(file, f"{needed.problem}; {moved}, more than the {limit:.2g} m ({SNAP_MOVE:.1%} of the leg's "
                        "length) the import accepts on its own", f"accept it with --snap {snap:g}, or fix the URDF's "
                        "angles")
        imported.notes.append(f"{needed.problem}: {moved} (accepted up to {limit:.2g} m, {SNAP_MOVE:.1%} of the "
                              "leg's length)")
        text = _header(file, imported, snap, source.snap, command) + with_check_note(dump_toml(tree))
    if pose_path is not None and sway is not None:
        write_text(pose_path, sway[1])
    write_text(robot_path, text)
    tips_at = {leg.joints[0].name: (leg.end, leg.tip_local) for leg in imported.legs}
    return Result(robot_path, imported.notes, error, unsnapped, source.snap, pose_path, tips_at, imported.base_frame,
                  imported.yaw)


def _parse(file: Path, text: str) -> tuple[Any, list[str]]:
    """yourdfpy's model of the text, with parts hanging off the root by floating joints fixed to the leg ends they
    sit at (:mod:`shc_cli.interop.urdf_import_detached`), and the notes on it."""
    model, notes, problem = attach_detached(parse_urdf(file, text))
    if problem is not None:
        raise _fail(file, problem, "fix them to the links they belong to (fixed joints), or delete them")
    return model, notes


def _header(file: Path, imported: Imported, snap: float, largest: float, command: str = "urdf") -> str:
    """The robot file's comment lines: where it came from, the base frame, the tips, the notes."""
    header = [f"# Imported by `shc import {command}` from {file.name}. Units: m, rad, s, kg.",
              f"# base_link is the URDF link '{imported.base_frame}'"
              + (f" turned {math.degrees(imported.yaw):g} deg about z (forward)" if imported.yaw else "")
              + ". Joint angles are the URDF's; [hardware.servos] names each joint's URDF joint.",
              *_tip_lines(imported.legs),
              *(f"# Note: {note}." for note in imported.notes)]
    if largest > 0.0:
        header.append(f"# rpy values within {snap:g} rad of a multiple of pi/2 snapped to it (largest change "
                      f"{largest:.2g} rad).")
    header.append("# Not read: visuals, meshes (but a foot's, when its link frame is on the knee axis), transmissions, "
                  "gazebo tags, dynamics (damping, friction).")
    return "\n".join(header) + "\n"


POSES_FROM_ROBOT = "../poses/"
"""Where the robot file finds the pose set the import writes (``OUT/poses/``, relative to ``OUT/robots/``)."""


def _sway(imported: Imported, robot_name: str) -> tuple[str, str] | None:
    """A quadruped walking ``quad_wave``: auto posing on, with a body-sway set sized for its stance (file name
    and text; :mod:`shc_cli.spec.sway`); ``None`` for any other robot."""
    from shc_cli.spec.sway import quad_wave_sway_toml, sway_amplitude

    if imported.tree["walker"]["gait"] != "quad_wave":
        return None
    amplitude = sway_amplitude(leg["stance"]["y"] for leg in imported.tree["legs"].values())
    file_name = f"{robot_name}_quad_wave.toml"
    imported.tree["pose"] = {"auto": True, "auto_pose_type": POSES_FROM_ROBOT + file_name}
    imported.notes.append(f"auto posing on: the body sways {amplitude:g} m sideways towards the three standing "
                          f"feet (poses/{file_name}, a third of the feet's lateral half-spread)")
    return file_name, quad_wave_sway_toml(f"{robot_name}_quad_wave", amplitude, robot_name)

