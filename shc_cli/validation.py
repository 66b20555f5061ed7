"""Semantic checks of a schema-valid robot and its gaits: what pydantic alone cannot see.

Each check returns :class:`~shc_cli.errors.Issue` objects located at the line the user wrote. The checks need the
kinematics (:mod:`shc_cli.model`), gait timing (:mod:`shc_cli.control.gait`) and the servo models
(:mod:`shc_cli.hardware.models`), so they sit above those layers and below the run loop, not in :mod:`shc_cli.spec`;
those imports stay inside the checks that need them (``shc validate`` of a file with schema errors starts fast).
"""

from __future__ import annotations

import itertools
import math
import re

import numpy as np

from shc_cli.errors import Issue
from shc_cli.spec.gait import Gait
from shc_cli.spec.loading import LoadedGait, LoadedRobot, one_per_mistake
from shc_cli.spec.robot import Robot

REACH_TOLERANCE = 0.001
"""Largest stance-position error [m] the reachability check accepts."""
MIN_STANCE_SEPARATION = 0.02
"""Smallest distance between two legs' stance positions [m] (or two foot diameters, if larger)."""
MIN_LEGS_IN_STANCE = 2
GROUND_TOLERANCE = 0.002
"""How far a link's joint origins may reach below the ground in the standing pose before validation refuses it
[m]."""


def check_robot(loaded: LoadedRobot) -> list[Issue]:
    """Every semantic check of a robot file, cheapest first; each mistake reported once."""
    robot = loaded.robot
    issues = _joint_positions(loaded, robot) + _stance_overlap(loaded, robot)
    if not issues:
        issues = _mirrors(loaded, robot)
    if not issues:
        issues = _stance_reachable(loaded, robot)
    if not issues:
        issues = _standing_in_ground(loaded, robot)
    if not issues:
        issues = _hardware(loaded, robot)
    return one_per_mistake(issues, loaded.mirrors)


OPENSHC_LEG_NAME = re.compile(r"^([A-F])([LR])$")
"""OpenSHC's leg names: a letter from the front (A) to the rear, then the side (R right, L left): AR front right,
BR middle right, CR rear right, CL, BL, AL."""


def leg_position_warnings(robot: Robot) -> list[str]:
    """Warnings (not errors: other naming schemes exist) for legs named in OpenSHC's scheme that stand where their
    name says they do not: an R leg on the left (stance y > 0) or an L leg on the right, or a side's legs not
    running from A at the front to the rear (a leg behind the next letter's). Legs named otherwise are not
    checked."""
    sides: dict[str, list[tuple[str, str, float]]] = {"R": [], "L": []}
    warnings: list[str] = []
    for name, leg in robot.legs.items():
        match = OPENSHC_LEG_NAME.match(name)
        if match is None:
            continue
        letter, side = match.groups()
        x, y = leg.stance.x, leg.stance.y
        sides[side].append((letter, name, x))
        wrong = y > 0 if side == "R" else y < 0
        if wrong:
            said, stands = ("right", "left") if side == "R" else ("left", "right")
            warnings.append(f"leg {name}: OpenSHC's name says {said} side, but it stands on the {stands} (stance "
                            f"x {x:+.3f}, y {y:+.3f} m); OpenSHC names the legs AR, BR, CR down the right side, front "
                            "to rear, and AL, BL, CL down the left")
    for legs in sides.values():
        legs.sort()
        for (_, front, front_x), (_, rear, rear_x) in itertools.pairwise(legs):
            if front_x <= rear_x:
                warnings.append(f"leg {front}: OpenSHC's name says it is in front of {rear}, but it stands behind "
                                f"or beside it (stance x {front_x:+.3f} m against {rear_x:+.3f} m); OpenSHC's "
                                "letters run A (front) to the rear")
    return warnings


def servo_range_problem(robot: Robot, key: str, direction: int | None = None, zero_ticks: int | None = None
                        ) -> str | None:
    """Why joint ``key``'s limits do not fit its servo's range of ticks (0 … resolution − 1 of its model: an AX-12A's
    1024 ticks over 300°), with ``direction`` and ``zero_ticks`` (None: the file's), or None when they fit — one
    tick of rounding allowed, as the servos' own angle-limit check on the bus. A multi-turn ``generic`` servo has no
    range. ``shc validate`` and ``shc hw jog`` (before it writes a zero) use this one rule."""
    from shc_cli.hardware.models import MODELS

    hardware = robot.hardware
    servo = hardware.servos[key]
    model = MODELS.get(servo.model or hardware.model)
    if model is None or model.name == "generic":
        return None
    leg, _, joint = key.partition("_")
    spec = robot.legs[leg].joints[joint]
    zero = (servo.zero_ticks if zero_ticks is None else zero_ticks)
    zero = model.centre if zero is None else zero
    sign = servo.direction if direction is None else direction
    ends = sorted(round(zero + sign * (angle + spec.offset) * model.ticks_per_radian) for angle in (spec.min, spec.max))
    last = model.resolution - 1
    if ends[0] >= -1 and ends[1] <= last + 1:
        return None
    return (f"the joint limits {spec.min:.3f}..{spec.max:.3f} rad are ticks {ends[0]}..{ends[1]} with zero_ticks "
            f"{zero} and direction {sign:+d}, outside the {model.name}'s 0..{last}")


def _hardware(loaded: LoadedRobot, robot: Robot) -> list[Issue]:
    """The servo table: every joint mapped once, known models, unique IDs per bus, zero offsets inside a turn."""
    from shc_cli.hardware.models import FAMILY_NAMES, MODELS

    hardware = robot.hardware
    families: dict[int, tuple[str, str]] = {}
    if not hardware.servos:
        return []
    joints = [f"{leg}_{joint}" for leg, spec in robot.legs.items() for joint in spec.joints]
    issues: list[Issue] = []
    for key in hardware.servos:
        if key not in joints:
            issues.append(loaded.issue(("hardware", "servos", key), f"'{key}' is not a joint of this robot",
                                       f"keys are <LEG>_<joint>, e.g. {joints[0]}"))
    missing = [key for key in joints if key not in hardware.servos]
    if missing:
        issues.append(loaded.issue(("hardware", "servos"), f"no servo for {', '.join(missing[:3])}"
                                   + (f" and {len(missing) - 3} more" if len(missing) > 3 else ""),
                                   "map every joint to a servo id"))
    if hardware.model not in MODELS:
        issues.append(loaded.issue(("hardware", "model"), f"unknown servo model '{hardware.model}'",
                                   f"use one of {', '.join(MODELS)}"))
    seen: dict[tuple[int, int], str] = {}
    for key, servo in hardware.servos.items():
        if servo.model is not None and servo.model not in MODELS:
            issues.append(loaded.issue(("hardware", "servos", key, "model"), f"unknown servo model '{servo.model}'",
                                       f"use one of {', '.join(MODELS)}"))
        model = MODELS.get(servo.model or hardware.model)
        ticks = hardware.ticks_per_revolution if model is None or model.name == "generic" else model.resolution
        if servo.zero_ticks is not None and servo.zero_ticks >= ticks:
            span = "one turn" if model is None or model.range_degrees == 360.0 else (
                f"the {model.name}'s {model.range_degrees:g}° range")
            issues.append(loaded.issue(("hardware", "servos", key, "zero_ticks"),
                                       f"zero_ticks {servo.zero_ticks} is outside {span}", f"use 0 … {ticks - 1}"))
        elif key in joints and model is not None:
            problem = servo_range_problem(robot, key)
            if problem is not None:
                issues.append(loaded.issue(("hardware", "servos", key, "zero_ticks"), problem,
                                           "narrow the joint limits, or zero the servo nearer the middle of its "
                                           "range (shc hw jog, answer h with the joint at angle 0)"))
        if model is not None:
            family = families.setdefault(servo.bus, (model.family, key))
            if family[0] != model.family:
                issues.append(loaded.issue(("hardware", "servos", key, "model"),
                                           f"{model.name} speaks {FAMILY_NAMES[model.family]}, but {family[1]} on "
                                           f"bus {servo.bus} speaks {FAMILY_NAMES[family[0]]}",
                                           "put each protocol on a bus of its own (bus = N)"))
        other = seen.get((servo.bus, servo.id))
        if other is not None:
            issues.append(loaded.issue(("hardware", "servos", key, "id"),
                                       f"id {servo.id} on bus {servo.bus} is also {other}'s",
                                       "give each servo its own id"))
        seen[(servo.bus, servo.id)] = key
    return issues


def _joint_positions(loaded: LoadedRobot, robot: Robot) -> list[Issue]:
    issues = []
    for leg_id, leg in robot.legs.items():
        for name, joint in leg.joints.items():
            if not joint.min <= joint.unpacked <= joint.max:
                issues.append(loaded.issue(
                    ("legs", leg_id, "joints", name, "unpacked"),
                    f"unpacked ({joint.unpacked:g}) lies outside [min, max] = [{joint.min:g}, {joint.max:g}]",
                    "move it inside the joint limits",
                ))
    return issues


def _stance_overlap(loaded: LoadedRobot, robot: Robot) -> list[Issue]:
    """No two stance positions closer than the feet allow; a pair's mirror image is not reported again."""
    issues = []
    legs = list(robot.legs.items())
    source = {leg_id: mirrored[0] for leg_id, mirrored in loaded.mirrors.items()}
    reported: set[frozenset[str]] = set()
    for i, (leg_id, leg) in enumerate(legs):
        for other_id, other in legs[:i]:
            gap = math.hypot(leg.stance.x - other.stance.x, leg.stance.y - other.stance.y)
            needed = max(MIN_STANCE_SEPARATION, leg.foot_radius + other.foot_radius)
            pair = frozenset(source.get(name, name) for name in (leg_id, other_id))
            if gap < needed and pair not in reported:
                reported.add(pair)
                issues.append(loaded.issue(
                    ("legs", leg_id, "stance"),
                    f"stance ({leg.stance.x:g}, {leg.stance.y:g}) is {gap * 1000:.0f} mm from leg {other_id}'s stance "
                    f"(at least {needed * 1000:.0f} mm needed)",
                    "give each leg its own stance position",
                ))
    return issues


def _mirrors(loaded: LoadedRobot, robot: Robot) -> list[Issue]:
    """A mirrored leg must be the reflection of its source through the x–z plane.

    With a ``[mirror]`` table its rules are the likely mistake: one issue there for all failing legs.
    """
    from shc_cli.model.chains import Chains

    if not loaded.mirrors:
        return []
    chains = Chains.from_robot(robot)
    order = {leg: i for i, leg in enumerate(robot.legs)}
    rng = np.random.default_rng(0)
    failures: list[tuple[str, str, float]] = []
    for leg_id, (source_id, negated) in loaded.mirrors.items():
        source, mirror = order[source_id], order[leg_id]
        pair = chains.take(np.array([source, mirror]))
        lo, hi = pair.lower[0], pair.upper[0]
        q = rng.uniform(lo, hi, size=(8, len(lo)))
        names = list(robot.legs[source_id].joints)
        sign = np.array([-1.0 if name in negated else 1.0 for name in names] + [1.0] * (len(lo) - len(names)))
        tips_source = pair.take(np.zeros(8, dtype=np.int64)).tips(q)
        tips_mirror = pair.take(np.ones(8, dtype=np.int64)).tips(q * sign)
        error = float(np.abs(tips_mirror - tips_source * np.array([1.0, -1.0, 1.0])).max())
        if error > 1e-3:
            failures.append((leg_id, source_id, error))
    fix = "check [mirror] negate_dh and negate_joints against the leg's DH chain"
    if failures and any(path[0] == "mirror" for path in loaded.origin_map):
        pairs = ", ".join(f"{source_id} -> {leg_id}" for leg_id, source_id, _ in failures)
        worst = max(error for *_, error in failures)
        return [loaded.issue(("mirror",), f"these rules do not reflect {pairs}: tips differ by up to "
                                          f"{worst * 1000:.0f} mm", fix)]
    return [loaded.issue(("legs", leg_id), f"the mirror of {source_id} is not its reflection: tips differ by "
                                           f"up to {error * 1000:.0f} mm", fix)
            for leg_id, source_id, error in failures]


def _stance_reachable(loaded: LoadedRobot, robot: Robot) -> list[Issue]:
    """Each stance position at the body clearance must be reachable within the joint limits."""
    from shc_cli.model.chains import Chains
    from shc_cli.model.ik import solve

    chains = Chains.from_robot(robot)
    clearance = robot.walker.body_clearance
    targets = np.array([[leg.stance.x, leg.stance.y, -clearance] for leg in robot.legs.values()])
    best = np.full(chains.size, np.inf)
    seeds = [chains.default_joints(), _unpacked(robot, chains.joints), (chains.lower + chains.upper) / 2.0]
    for seed in seeds:
        _, error = solve(chains, seed, targets, tolerance=REACH_TOLERANCE / 10, max_steps=400, dt=robot.time_delta)
        best = np.minimum(best, error)
        if (best < REACH_TOLERANCE).all():
            return []
    if len(robot.legs) > 1 and (best >= REACH_TOLERANCE).all():
        short = sorted({f"{error:.3f}" for error in (best.min(), best.max())}, key=float)
        return [loaded.issue(
            ("walker", "body_clearance"),
            f"no leg reaches its stance at body_clearance {clearance:g} m (short by {' to '.join(short)} m "
            "within the joint limits)",
            "lower walker.body_clearance, move the stances towards the legs' bases or widen the joint limits",
        )]
    issues = []
    for i, (leg_id, leg) in enumerate(robot.legs.items()):
        if best[i] >= REACH_TOLERANCE:
            issues.append(loaded.issue(
                ("legs", leg_id, "stance"),
                f"stance ({leg.stance.x:g}, {leg.stance.y:g}) at body_clearance {clearance:g} m is out of reach "
                f"by {best[i]:.3f} m within the joint limits",
                "move the stance towards the leg's base, lower walker.body_clearance or widen the joint limits",
            ))
    return issues


def standing_depths(robot: Robot) -> list[tuple[str, float]]:
    """How far below the ground each link stands in the pose the direct start-up ends in (``plan_direct_startup``
    from OpenSHC's initial joints, the body at ``body_clearance`` and the feet on the ground), deepest first: the
    body box and, per leg, the link each joint moves — the straight line between its joint's origin and the next
    (a knee), not the simulation's capsule round it (:mod:`shc_cli.model.body`) — as ``(name, depth [m])`` for
    those deeper than :data:`GROUND_TOLERANCE`. The ground is where the simulation stands the feet: the largest
    foot radius below the walk plane."""
    from shc_cli.control.startup import plan_direct_startup
    from shc_cli.model.body import body_model
    from shc_cli.model.chains import Chains

    chains = Chains.from_robot(robot)
    model = body_model(robot)
    ground = -robot.walker.body_clearance - max(leg.foot.radius for leg in model.legs)
    depths = []
    torso = model.torso
    depths.append(("body", ground - (torso.com[2] - torso.size[2] / 2.0)))
    standing = plan_direct_startup(robot, chains, chains.default_joints())
    origins = chains.frames_in_base(standing[None])[0][:, :, :3, 3]
    for i, leg in enumerate(model.legs):
        for k, segment in enumerate(leg.segments):
            lowest = min(float(origins[i, k, 2]), float(origins[i, k + 1, 2]))
            depths.append((f"link {segment.link} (leg {leg.id})", ground - lowest))
    deep = [(name, depth) for name, depth in depths if depth > GROUND_TOLERANCE]
    return sorted(deep, key=lambda item: -item[1])


def _standing_in_ground(loaded: LoadedRobot, robot: Robot) -> list[Issue]:
    """No link of the standing pose the direct start-up reaches may stand in the ground (a knee below the feet:
    the physics would throw the robot up as it rises). Not checked with the stepped start-up sequence, whose
    pose comes from the pack/unpack configurations."""
    if robot.start_up.sequence:
        return []
    deep = standing_depths(robot)
    if not deep:
        return []
    name, depth = deep[0]
    more = f" (and {len(deep) - 1} more links)" if len(deep) > 1 else ""
    return [loaded.issue(
        ("walker", "body_clearance"),
        f"the standing pose puts {name} {depth:.3f} m below the ground{more}: the start-up would push it "
        "through the floor",
        "raise walker.body_clearance, move the stances so the knees stay above the feet, or set joint limits that "
        "keep them up",
    )]


def _unpacked(robot: Robot, joints: int) -> np.ndarray:
    out = np.zeros((len(robot.legs), joints))
    for i, leg in enumerate(robot.legs.values()):
        for k, joint in enumerate(leg.joints.values()):
            out[i, k] = joint.unpacked
    return out


def check_gait(loaded_gait: LoadedGait, robot: Robot) -> list[Issue]:
    """The gait must name exactly the robot's legs and keep enough legs on the ground."""
    from shc_cli.control.gait import step_cycle

    gait = loaded_gait.gait
    missing = [leg for leg in robot.legs if leg not in gait.offset_multiplier]
    extra = [leg for leg in gait.offset_multiplier if leg not in robot.legs]
    if missing or extra:
        parts = []
        if missing:
            parts.append(f"has no offset for {', '.join(missing)}")
        if extra:
            parts.append(f"names legs the robot does not have: {', '.join(extra)}")
        return [loaded_gait.issue(("offset_multiplier",),
                                  f"gait '{gait.name}' does not fit robot '{robot.name}': {'; '.join(parts)}",
                                  f"give one multiplier for each of {', '.join(robot.legs)}")]
    frequency = robot.walker.step_frequency.default
    try:
        cycle = step_cycle(gait, frequency, robot.time_delta)
    except ZeroDivisionError:  # a cycle of 0 iterations: the frequency is above what time_delta resolves
        cycle = None
    if cycle is None or cycle.period == 0:
        return [loaded_gait.issue(("swing_phase",),
                                  f"step frequency {frequency:g} Hz is too high for time_delta {robot.time_delta:g} s",
                                  "lower walker.step_frequency")]
    fewest, at = _fewest_in_stance(cycle.period, cycle.swing_start, cycle.swing_end, cycle.offsets)
    needed = min(MIN_LEGS_IN_STANCE, len(robot.legs))
    if fewest < needed:
        return [loaded_gait.issue(("offset_multiplier",),
                                  f"offsets make no walking pattern: at phase {at} of {cycle.period} only {fewest} "
                                  f"of {len(robot.legs)} legs are on the ground",
                                  "spread the offset multipliers so swings do not all coincide")]
    return []


def _fewest_in_stance(period: int, swing_start: int, swing_end: int,
                      offsets: dict[str, int]) -> tuple[int, int]:
    """Fewest legs in stance over one cycle, and the first iteration where it happens."""
    phases = np.arange(period)
    counts = np.zeros(period, dtype=int)
    for offset in offsets.values():
        phase = (phases + offset) % period
        counts += ~((phase >= swing_start) & (phase < swing_end))
    at = int(np.argmin(counts))
    return int(counts[at]), at


def check_gait_pattern(loaded_gait: LoadedGait) -> list[Issue]:
    """A gait on its own: enough legs on the ground at every phase (robot-independent, normaliser 2)."""
    gait = loaded_gait.gait
    normaliser = 2
    period = gait.base_length * normaliser
    swing_start = (gait.stance_phase // 2) * normaliser
    swing_end = swing_start + gait.swing_phase * normaliser
    offsets = {leg: (gait.phase_offset * normaliser * m) % period for leg, m in gait.offset_multiplier.items()}
    fewest, at = _fewest_in_stance(period, swing_start, swing_end, offsets)
    needed = min(MIN_LEGS_IN_STANCE, len(offsets))
    if fewest < needed:
        return [loaded_gait.issue(("offset_multiplier",),
                                  f"offsets make no walking pattern: at {at / normaliser:g} of {gait.base_length} "
                                  f"base units only {fewest} of {len(offsets)} legs are on the ground",
                                  "spread the offset multipliers so swings do not all coincide")]
    return []


def load_checked(robot_name: str, gait_name: str | None) -> tuple[Robot, Gait, LoadedRobot]:
    """A robot and a gait (the robot's own unless named), both loaded and fully checked; raises SpecError.

    The robot's own gait is looked up from the folder of the file that names it.
    """
    from shc_cli.errors import SpecError
    from shc_cli.spec.loading import load_gait, load_robot

    loaded = load_robot(robot_name)
    robot = loaded.robot
    problems = check_robot(loaded)
    if problems:
        raise SpecError(problems)
    gait_file, _ = loaded.where(("walker", "gait"))
    gait_loaded = load_gait(gait_name or robot.walker.gait, relative_to=None if gait_name else gait_file.parent)
    problems = check_gait(gait_loaded, robot)
    if problems:
        raise SpecError(problems)
    return robot, gait_loaded.gait, loaded
