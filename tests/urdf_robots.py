"""URDF text of made-up legged robots for the `shc import urdf` tests (written here, not by shc)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass(frozen=True)
class Element:
    """One joint of a leg: ``kind`` revolute/fixed/prismatic/continuous, its origin, axis and limits."""

    kind: str
    xyz: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rpy: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    lower: float = -1.5
    upper: float = 1.5


@dataclass(frozen=True)
class LegSpec:
    """A leg: its joints body to tip and the foot sphere on the last link (None: no collision geometry)."""

    name: str
    elements: list[Element]
    sphere: tuple[float, float, float] | None = None
    radius: float = 0.01
    masses: list[float] = field(default_factory=list)


def _vec(values: tuple[float, ...]) -> str:
    return " ".join(repr(float(v)) for v in values)


def robot_urdf(legs: list[LegSpec], name: str = "made_up", body_mass: float = 2.0) -> str:
    """A body box ``base_link`` (behind a massless root ``root_link`` with a fixed joint) and the legs."""
    lines = [f'<?xml version="1.0"?>\n<robot name="{name}">', '  <link name="root_link"/>',
             '  <joint name="root_fixed" type="fixed"><parent link="root_link"/><child link="base_link"/></joint>',
             '  <link name="base_link">',
             f'    <inertial><origin xyz="0 0 0.01"/><mass value="{body_mass!r}"/>',
             '      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/></inertial>',
             '    <collision><origin xyz="0 0 0"/><geometry><box size="0.3 0.2 0.05"/></geometry></collision>',
             "  </link>"]
    for leg in legs:
        parent = "base_link"
        for k, element in enumerate(leg.elements):
            child = f"{leg.name}_link{k}"
            last = k == len(leg.elements) - 1
            mass = leg.masses[k] if k < len(leg.masses) else 0.1
            lines.append(f'  <link name="{child}">')
            lines.append(f'    <inertial><origin xyz="0.01 0 0"/><mass value="{mass!r}"/>'
                         '<inertia ixx="1e-4" ixy="0" ixz="0" iyy="1e-4" iyz="0" izz="1e-4"/></inertial>')
            if last and leg.sphere is not None:
                lines.append(f'    <collision><origin xyz="{_vec(leg.sphere)}"/>'
                             f'<geometry><sphere radius="{leg.radius!r}"/></geometry></collision>')
            lines.append("  </link>")
            kind = "fix" if element.kind == "fixed" else "joint"
            lines.append(f'  <joint name="{leg.name}_{kind}{k}" type="{element.kind}">')
            lines.append(f'    <parent link="{parent}"/><child link="{child}"/>')
            lines.append(f'    <origin xyz="{_vec(element.xyz)}" rpy="{_vec(element.rpy)}"/>')
            if element.kind != "fixed":
                lines.append(f'    <axis xyz="{_vec(element.axis)}"/>')
                lines.append(f'    <limit lower="{element.lower!r}" upper="{element.upper!r}" effort="5.0" '
                             'velocity="4.0"/>')
            lines.append("  </joint>")
            parent = child
    lines.append("</robot>\n")
    return "\n".join(lines)


def insect_leg(name: str, x: float, y: float, standing: bool) -> LegSpec:
    """A 3-DOF leg at hip (x, y): coxa yaw, femur and tibia pitch; pointing away from the body's x axis.

    ``standing``: at the zero pose the tibia points down (the feet stand 0.12 m below the hips); otherwise the
    leg is stretched out flat."""
    side = -1.0 if y < 0 else 1.0
    yaw = side * math.pi / 2 + (0.4 if x > 0 else -0.4 if x < 0 else 0.0) * side
    tibia_pitch = -math.pi / 2 if standing else 0.0
    return LegSpec(name, [
        Element("revolute", (x, y, 0.0), (0.0, 0.0, yaw), (0.0, 0.0, 1.0), -0.8, 0.8),
        Element("revolute", (0.04, 0.0, 0.0), (math.pi / 2, 0.0, 0.0), (0.0, 0.0, 1.0), -1.5, 1.5),
        Element("revolute", (0.08, 0.0, 0.0), (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), -2.4, 2.4),
        Element("fixed", (0.0, 0.0, 0.0), (0.0, 0.0, tibia_pitch)),
    ], sphere=(0.12, 0.0, 0.0), masses=[0.05, 0.08, 0.06, 0.01])


def dog_leg(name: str, x: float, y: float) -> LegSpec:
    """A mammal leg at hip (x, y): abduction about x, thigh and calf pitch about y, straight down at the zero pose,
    the calf limited to a bent knee (−2.7 … −0.9 rad, as many quadruped URDFs have it)."""
    side = -1.0 if y < 0 else 1.0
    return LegSpec(name, [
        Element("revolute", (x, y, 0.0), (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), -0.8, 0.8),
        Element("revolute", (0.0, side * 0.08, 0.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), -1.0, 2.5),
        Element("revolute", (0.0, 0.0, -0.2), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0), -2.7, -0.9),
        Element("fixed", (0.0, 0.0, -0.2)),
    ], sphere=(0.0, 0.0, 0.0), radius=0.02, masses=[0.5, 1.0, 0.2, 0.05])
