"""What real URDFs carry that is not a leg joint, found before and after the legs are traced (``shc import urdf``).

Each rule is a class of description seen in the wild, not one robot:

* **Sensor stand-ins**: a prismatic joint with at most :data:`STUB_TRAVEL` of travel (a force sensor modelled as a
  slide of ±0.1 mm at a foot) is taken as fixed at 0.
* **Dummy foot joints**: revolute joints at the end of a leg whose axes pass through the tip (zero-length joints
  a description adds at the feet) do not move the tip: they are taken as fixed at 0 when the leg keeps at
  least :data:`MIN_LEG_JOINTS` joints that do.
* **Non-leg chains**: a head, camera pan/tilt or tail chain is not a leg: when at least :data:`MIN_LEGS` chains
  have the same number of joints, the legs are those with the most common number (ties: the larger number), and
  of those the ones at least :data:`SHORT` of the median length.
* **Forward**: a body frame whose +x points at a leg (legs straight ahead and behind) is turned so that the legs
  pair up left and right: a quarter turn, or (legs all round, as an octopod's every 45°) halfway between two
  neighbouring legs.
* **Continuous joints** (a vendor's actuator macro writes every joint so unless limits are passed) are revolute
  joints without limits: they get :data:`WHOLE_TURN` (−π … π), inside which the stance search and the walk
  choose their angles, and a note names them.
* **Placeholders**: inertial data no real robot has (a total mass below :data:`TINY_MASS`; most links with a
  radius of gyration beyond twice the leg's length; every link the same mass) and one joint speed limit below
  :data:`SLOW` (or at least :data:`FAST`) rad/s everywhere, and one effort limit far beyond what the robot's weight
  needs (:data:`STRONG`), are named, and a plausible value from the legs' size is used instead.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

STUB_TRAVEL = 0.001
"""Largest travel of a prismatic joint taken as a fixed sensor stand-in [m]."""
ON_AXIS = 1e-6
"""A tip this close to a joint's axis is not moved by it [m]."""
MIN_LEG_JOINTS = 3
"""Dummy foot joints are dropped only when the leg keeps this many joints that move its tip."""
MIN_LEGS = 4
"""Chains are sorted into legs and others only when at least this many have the same number of joints."""
SHORT = 0.5
"""A chain shorter than this share of the median leg is not a leg."""
TINY_MASS = 0.01
"""A robot lighter than this in total has placeholder masses [kg]."""
SLOW = 1.0
"""A joint speed limit below this on every joint is a placeholder [rad/s]: hobby servos turn ≥ 5 rad/s unloaded."""
DEFAULT_SPEED = 5.0
"""Joint speed limit used instead of a placeholder [rad/s] (shc's default ``max_vel``)."""
FAST = 100.0
"""A joint speed limit at or above this on every joint is a placeholder too [rad/s] (1000: "unlimited")."""
STRONG = 20.0
"""A joint effort limit above this many times the torque of the robot's weight at a leg's length, the same on
every joint, is a placeholder (1000 N·m on a 2.5 kg robot)."""
SERVO_MASS = 0.07
"""Mass of one hobby servo with its bracket, used for placeholder masses [kg] (AX-12A 54.6 g + bracket)."""


WHOLE_TURN = (-math.pi, math.pi)
"""Limits given to a continuous joint [rad]: one whole turn, centred on the URDF's zero."""


def open_continuous(joints: list[Any]) -> list[str]:
    """Make every continuous joint revolute with :data:`WHOLE_TURN` limits (its effort and velocity kept); returns
    their names."""
    import yourdfpy

    names = []
    for joint in joints:
        if joint.type == "continuous":
            given = joint.limit
            joint.type = "revolute"
            joint.limit = yourdfpy.Limit(effort=getattr(given, "effort", None),
                                         velocity=getattr(given, "velocity", None), lower=WHOLE_TURN[0],
                                         upper=WHOLE_TURN[1])
            names.append(joint.name)
    return names


def stub_joints(joints: list[Any]) -> dict[str, str]:
    """Joints taken as fixed before the legs are traced: ``{name: why}``."""
    out = {}
    for joint in joints:
        if joint.type == "prismatic" and joint.limit is not None:
            travel = float(joint.limit.upper or 0.0) - float(joint.limit.lower or 0.0)
            if travel <= STUB_TRAVEL:
                out[joint.name] = f"prismatic with {travel * 1000:g} mm of travel (a sensor stand-in)"
    return out


def dummy_tail(points: list[FloatArray], directions: list[FloatArray], tip: FloatArray) -> int:
    """How many trailing joints (given at the zero pose by a point on and the direction of each axis) have the
    tip on their axis and can go: 0 unless :data:`MIN_LEG_JOINTS` joints that move the tip stay."""
    count = 0
    for point, direction in zip(reversed(points), reversed(directions), strict=True):
        offset = tip - point
        unit = direction / np.linalg.norm(direction)
        if np.linalg.norm(offset - np.dot(offset, unit) * unit) >= ON_AXIS:
            break
        count += 1
    return count if len(points) - count >= MIN_LEG_JOINTS else 0


def leg_chains(counts: list[int], lengths: list[float]) -> list[int]:
    """Indices of the chains that are legs (module docstring)."""
    tally = Counter(counts)
    most = max(tally.values(), default=0)
    if most < MIN_LEGS:
        return list(range(len(counts)))
    joints = max(count for count, seen in tally.items() if seen == most)
    kept = [i for i, count in enumerate(counts) if count == joints]
    median = float(np.median([lengths[i] for i in kept]))
    return [i for i in kept if lengths[i] >= SHORT * median]


def forward_turn(hips: list[FloatArray]) -> float:
    """Yaw [rad] to turn the body frame by so that no leg is straight ahead or behind and the legs split evenly
    left and right: 0 if that holds already; else π/2 (legs ahead and behind, none beside the body); else (legs
    all round, as an octopod's every 45°) the smallest turn halfway between two neighbouring hips that makes it
    hold. A hip is on an axis within a twentieth of the farthest hip's distance."""
    if len(hips) < 4 or len(hips) % 2:
        return 0.0
    reach = max(float(np.hypot(h[0], h[1])) for h in hips)
    spread = [(float(np.hypot(h[0], h[1])), math.atan2(float(h[1]), float(h[0]))) for h in hips]

    def even(yaw: float) -> bool:
        sides = [r * math.sin(a - yaw) for r, a in spread]
        ahead = [abs(r * math.cos(a - yaw)) for r, a in spread]
        on_x = any(abs(s) < 0.05 * reach and x > 0.05 * reach for s, x in zip(sides, ahead, strict=True))
        return not on_x and sum(s > 0.0 for s in sides) == sum(s < 0.0 for s in sides)

    if not any(abs(float(h[1])) < 0.05 * reach and abs(float(h[0])) > 0.05 * reach for h in hips):
        return 0.0  # no leg straight ahead or behind: the URDF's +x (whatever the split)
    angles = sorted(a for r, a in spread if r > 0.05 * reach)
    halfway = [0.5 * (a + b) for a, b in zip(angles, [*angles[1:], angles[0] + 2.0 * math.pi], strict=True)]
    turns = [math.remainder(a, math.pi) for a in halfway]  # forward or backward along the same line
    for yaw in [math.pi / 2, *sorted(turns, key=lambda t: (round(abs(t), 9), -t))]:
        if even(yaw):
            return yaw
    return 0.0


@dataclass(frozen=True)
class Placeholders:
    """What looked like a placeholder and what is used instead."""

    notes: list[str]
    masses: bool
    speed: float | None
    torque: float | None = None


def placeholders(masses: list[float], inertias: list[float], sizes: list[float], speeds: list[float],
                 efforts: list[float] | None = None) -> Placeholders:
    """Check the URDF's link masses [kg], their largest principal inertias [kg·m²], the legs' lengths [m] (one per
    leg) and the leg joints' speed [rad/s] and effort [N·m] limits (module docstring)."""
    notes = []
    total = sum(masses)
    size = max(sizes) if sizes else 0.1
    heavy = [i for i, (mass, inertia) in enumerate(zip(masses, inertias, strict=True))
             if inertia > mass * (2.0 * size) ** 2]
    same = len(masses) >= 6 and len({round(m, 9) for m in masses if m > 0.0}) == 1
    placeholder_mass = total < TINY_MASS or same or len(heavy) > len(masses) // 2
    if placeholder_mass:
        why = (f"total mass {total:.2g} kg" if total < TINY_MASS else
               f"every link {masses[0]:g} kg" if same else
               f"{len(heavy)} of {len(masses)} links with inertias a leg of {size:.2g} m cannot have")
        notes.append(f"the URDF's inertial data look like placeholders ({why}): masses used instead are "
                     f"{SERVO_MASS:g} kg per joint (a servo and its bracket) and the body as many servos' worth as "
                     "the legs have joints; measure and write body.mass and each joint's mass")
    speed = None
    if speeds and (max(speeds) < SLOW or min(speeds) >= FAST):
        speed = DEFAULT_SPEED
        given = f"{speeds[0]:g}" if len(set(speeds)) == 1 else f"{min(speeds):g}–{max(speeds):g}"
        notes.append(f"every joint's velocity limit is {given} rad/s, which looks like a placeholder (a servo "
                     f"turns 5–50 rad/s): max_vel and servo.no_load_speed are {DEFAULT_SPEED:g} rad/s instead; "
                     "write your servo's")
    torque = None
    if placeholder_mass:  # the masses used instead: a servo's per joint and as much again for the body
        total = 2.0 * SERVO_MASS * len(efforts or [])
    weight = total * 9.81 * size
    if efforts and len(set(efforts)) == 1 and efforts[0] > STRONG * weight > 0.0:
        # The weight on a third of the legs, half a leg's length out from each.
        torque = float(f"{1.5 * weight / max(len(sizes), 1):.3g}")  # 3 figures: a small robot's is not 0.00
        notes.append(f"every joint's effort limit is {efforts[0]:g} N·m, which looks like a placeholder (the "
                     f"robot's {total:.3g} kg at a leg's {size:.2g} m is {weight:.2g} N·m): servo.stall_torque is "
                     f"{torque:g} N·m instead (its weight on a third of the legs, half a leg out); write your "
                     "servo's")
    return Placeholders(notes, placeholder_mass, speed, torque)
