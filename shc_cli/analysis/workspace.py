"""What ``shc workspace`` reports: workspaces, walkspace and limits of a robot and gait.

The computation follows OpenSHC's start-up exactly: plan the direct start-up from the joint
defaults (which gives the default stance configuration), search each leg's workspace from there,
intersect them into the walkspace and derive speed limits for the gait (study §3, §9.2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shc_cli.control.gait import StepCycle, step_cycle
from shc_cli.control.limits import Limits, generate_limits
from shc_cli.control.startup import plan_direct_startup
from shc_cli.control.verified_limits import source_for
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.workspace import (
    Workplane,
    plane_at,
    polygon_area,
    search_workspaces,
    volumetric_workspaces,
    walkspace,
)
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot


@dataclass(frozen=True)
class WorkspaceReport:
    """Everything ``shc workspace`` prints, writes and plots."""

    robot: Robot
    gait: Gait
    step_frequency: float
    cycle: StepCycle
    default_joints: FloatArray
    identity_tips: FloatArray
    planes: dict[str, Workplane]
    layers: dict[str, dict[float, Workplane]] | None
    walkspace: Workplane
    limits: Limits
    verified: Limits | None = None
    """The limits the controller walks when the robot verifies them (``walker.verify_speed_limits``) or keeps verified
    shares below 1 for this gait (``walker.speed_shares``), else None."""

    def area(self, leg: str) -> float:
        """Area of a leg's workplane polygon [m²]."""
        return polygon_area(self.planes[leg])

    def forward_stride(self, leg: str) -> float:
        """Longest straight stride along x through the identity position, ``r(0°) + r(180°)`` [m]."""
        plane = self.planes[leg]
        return plane[0] + plane[180]

    def walkspace_area(self) -> float:
        """Area of the walkspace polygon (the common, symmetric, non-overlapping region every foot may use about its
        stance position, OpenSHC's ``generateWalkspace``) [m²]: our reading of the OpenSHC paper's Table II "area"."""
        return polygon_area(self.walkspace)

    def walkspace_stride(self) -> float:
        """Walkspace extent along x, ``W(0°) + W(180°)`` [m]: the 100 % stride before OpenSHC's overshoot scaling,
        our reading of the paper's Table II "stride length"."""
        return self.walkspace[0] + self.walkspace[180]

    def to_json(self) -> dict[str, object]:
        """The ``--json`` document: radii in m, speeds in m/s and rad/s, keyed by bearing in degrees."""
        by_bearing = self.limits.bearings
        document: dict[str, object] = {
            "robot": self.robot.name,
            "gait": self.gait.name,
            "step_frequency": self.step_frequency,
            "legs": {leg: {str(b): r for b, r in plane.items()} for leg, plane in self.planes.items()},
            "leg_area_m2": {leg: self.area(leg) for leg in self.planes},
            "leg_forward_stride_m": {leg: self.forward_stride(leg) for leg in self.planes},
            "walkspace": {str(b): r for b, r in self.walkspace.items()},
            "walkspace_area_m2": self.walkspace_area(),
            "walkspace_stride_m": self.walkspace_stride(),
            "max_linear_speed": {str(b): lim.linear_speed for b, lim in by_bearing.items()},
            "max_linear_acceleration": {str(b): lim.linear_acceleration for b, lim in by_bearing.items()},
            "max_angular_speed": {str(b): lim.angular_speed for b, lim in by_bearing.items()},
            "max_angular_acceleration": {str(b): lim.angular_acceleration for b, lim in by_bearing.items()},
            "step_period_cycles": self.cycle.period,
            "swing_period_cycles": self.cycle.swing_period,
            "stance_period_cycles": self.cycle.stance_period,
            "cycle_frequency_hz": self.cycle.frequency,
            "duty_factor": self.cycle.duty_factor,
            "time_to_max_stride_s": self.limits.time_to_max_stride,
            "verified_max_linear_speed": None if self.verified is None else {
                str(b): lim.linear_speed for b, lim in self.verified.bearings.items()},
            "verified_max_angular_speed": None if self.verified is None else {
                str(b): lim.angular_speed for b, lim in self.verified.bearings.items()},
            "default_joints": {
                leg: dict(zip(self.robot.legs[leg].joints, map(float, self.default_joints[i]), strict=False))
                for i, leg in enumerate(self.robot.legs)
            },
        }
        if self.layers is not None:
            document["layers"] = {
                leg: {f"{h:.6f}": {str(b): r for b, r in plane.items()} for h, plane in stack.items()}
                for leg, stack in self.layers.items()
            }
        return document


def analyse_workspace(
    robot: Robot,
    gait: Gait,
    step_frequency: float | None = None,
    bearing_count: int = 8,
    volumetric: bool = False,
) -> WorkspaceReport:
    """Run OpenSHC's start-up computations for ``robot`` walking ``gait``."""
    chains = Chains.from_robot(robot)
    default_joints = plan_direct_startup(robot, chains, chains.default_joints())
    clearance = robot.walker.body_clearance
    identity = np.array([[leg.stance.x, leg.stance.y, -clearance] for leg in robot.legs.values()])
    layers = None
    if volumetric:
        layers = volumetric_workspaces(chains, default_joints, identity, robot.time_delta, bearing_count)
        planes = {leg: plane_at(stack, 0.0) for leg, stack in layers.items()}
    else:
        planes = search_workspaces(chains, default_joints, identity, robot.time_delta, bearing_count).planes
    stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}
    common = walkspace(planes, stance, robot.walker.overlapping_walkspaces)
    frequency = robot.walker.step_frequency.default if step_frequency is None else step_frequency
    cycle = step_cycle(gait, frequency, robot.time_delta)
    first = next(iter(robot.legs.values())).stance
    limits = generate_limits(common, cycle, robot.time_delta, math.hypot(first.x, first.y))
    source = source_for(robot)
    shares = None if source is None else source(gait)
    verified = None if shares is None or not shares.reduced else shares.apply(limits)
    return WorkspaceReport(robot, gait, frequency, cycle, default_joints, identity, planes, layers, common, limits,
                           verified)
