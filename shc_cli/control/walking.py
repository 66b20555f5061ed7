"""The walking of the controller: workspaces, walkspace and OpenSHC's limits (study §5), gait and step-frequency
changes (§4.3, §9.6), cruise control (§6), the stance span, the step-plane input, admittance and declared leg
failures. A collaborator of :class:`~shc_cli.control.controller.Controller`: it keeps the cruise and failure-timing
state and works on the controller's shared state (:class:`~shc_cli.control.core.ControllerCore`).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.control import stepping
from shc_cli.control.admittance import AdmittanceController, tip_forces_from_efforts
from shc_cli.control.autopose import AutoPoser
from shc_cli.control.gait import StepCycle, step_cycle
from shc_cli.control.leg_failure import LegFailure
from shc_cli.control.limits import Limits, generate_limits
from shc_cli.control.sensing import Sensors
from shc_cli.control.states import LegMode, RobotState, WalkState
from shc_cli.control.step_plane import StepPlanes, StepPlaneSettings, TerrainMap
from shc_cli.control.walk import WalkController
from shc_cli.model.workspace import plane_at, search_workspaces, volumetric_workspaces, walkspace
from shc_cli.spec.robot import Perception

if TYPE_CHECKING:
    from shc_cli.control.core import ControllerCore
    from shc_cli.model.chains import FloatArray

_RUNNING = RobotState.RUNNING
_STOPPED = WalkState.STOPPED
_WALKING_LEG = int(LegMode.WALKING)


class Walking:
    """Limits, gait and parameter changes, cruise control, step planes, admittance and leg failures."""

    def __init__(self, core: ControllerCore) -> None:
        self.c = core
        self._walking_cycles = 0
        self.cruise_on = False
        self.cruise_velocity = (np.zeros(2), 0.0)
        self.cruise_end = math.inf
        self._step_planes: StepPlanes | None = None

    def generate_limits(self) -> None:
        """Workspaces, walkspace and limits from the default configuration; (re)create the walker."""
        clearance = self.c.robot.walker.body_clearance
        identity = np.array([[x, y, -clearance] for x, y in self.c.stance.values()])
        if self.c.robot.walker.rough_terrain_mode:  # OpenSHC: the volumetric workspace, its layer at the stance
            layers = volumetric_workspaces(self.c.model.chains, self.c.default_joints, identity, self.c.dt)
            self.c.planes = {leg: plane_at(stack, 0.0) for leg, stack in layers.items()}
        else:
            self.c.planes = search_workspaces(self.c.model.chains, self.c.default_joints, identity, self.c.dt).planes
        planes = self.c.planes if self.c.failure is None else self.c.failure.walking(self.c.planes)
        self.c.walkspace = walkspace(planes, self.c.stance, self.c.robot.walker.overlapping_walkspaces)
        limits = self.limits_for(self.c.cycle)
        walker_spec = self.c.robot.walker
        if self.c.walker is None:
            self.c.walker = WalkController(self.c.stance, self.c.cycle, limits, self.c.dt,
                                           walker_spec.swing_height.default, walker_spec.swing_width.default,
                                           walker_spec.velocity_input_mode, walker_spec.rough_terrain_mode)
        else:
            self.c.walker.set_cycle(self.c.cycle, limits)

    def declare_failure(self, failure: LegFailure) -> None:
        """Failed legs from this cycle on (a detected fault): held at once (``locked``: where they are), the
        re-planned gait requested as a gait change (the walker stops, then walks on it)."""
        failure.at_s = 0.0
        self.c.failure = self.c.scheduled_failure = failure

    def schedule_failure(self, failure: LegFailure) -> None:
        """Count walking cycles; at the failure's time request its re-planned gait (:meth:`change_gait` then
        installs the failure)."""
        if self.c.state == _RUNNING and self.c.walker is not None and (self._walking_cycles
                                                                  or self.c.walker.state != _STOPPED):
            self._walking_cycles += 1
        assert failure.at_s is not None and failure.gait is not None
        due = self._walking_cycles * self.c.dt >= failure.at_s
        if due and self.c.pending_gait is None and self.c.gait is not failure.gait:
            self.c.pending_gait = failure.gait

    def install_failure(self, failure: LegFailure) -> None:
        """The declared failure from now on: the walking legs' walkspace and OpenSHC's limits of it."""
        self.c.failure, self.c.scheduled_failure, self.c.speed_shares = failure, None, None
        self.c.walkspace = walkspace(failure.walking(self.c.planes), self.c.stance,
                                     self.c.robot.walker.overlapping_walkspaces)

    def hold_failed(self, failure: LegFailure) -> None:
        """Failed legs back at their held pose (before the joint speed guard, which paces the first move)."""
        held = failure.hold(self.c.model.joints, self.c.state == _RUNNING)
        if held is not None:
            velocities = self.c.model.joint_velocities.copy()
            velocities[failure.index] = 0.0
            tips = self.c.model.tips.copy()
            tips[failure.index] = failure.tips(held)
            self.c.model.joints, self.c.model.joint_velocities, self.c.model.tips = held, velocities, tips


    def set_cruise(self, on: bool) -> None:
        """Cruise control (study §6): hold the configured (or the current) velocity, optionally for a time."""
        if on and not self.cruise_on:
            cruise, scaler = self.c.robot.cruise, self.c.robot.walker.body_velocity_scaler
            if cruise.force_velocity:
                self.cruise_velocity = (np.array(cruise.linear, dtype=float) * scaler, cruise.angular * scaler)
            else:
                self.cruise_velocity = (self.c.velocity_input.copy(), self.c.angular_input)
            limit = cruise.time_limit
            self.cruise_end = self.c.cycles * self.c.dt + limit if limit > 0.0 else math.inf
        self.cruise_on = on

    def step_plane(self, terrain: TerrainMap) -> tuple[FloatArray, FloatArray]:
        """This cycle's step-plane input from the map (:mod:`shc_cli.control.step_plane`)."""
        assert self.c.walker is not None
        if self._step_planes is None:
            spec = self.c.robot.perception or Perception()
            self._step_planes = StepPlanes(len(self.c.stance), StepPlaneSettings(
                spec.edge_margin, spec.edge_step, spec.max_shift, spec.clearance_margin, spec.max_clearance,
                spec.max_slope, self.c.robot.body.size[0], self.c.robot.body.size[1], spec.lookahead))
            self.c.walker.max_plane_slope, self.c.walker.floor_deadband = spec.max_slope, spec.edge_step
        legs, cycle, walk = self.c.walker.legs, self.c.walker.cycle, self.c.walker.desired_velocity()
        pose = self.c.poser.current
        planes = self._step_planes
        self.c.walker.body_floor = planes.body_floor  # (the last cycle's: the walk plane is fitted after the legs)
        vectors = legs.vectors
        return planes.update(terrain, vectors[:, stepping.DEFAULT] + 0.5 * vectors[:, stepping.STRIDE],
                             vectors[:, stepping.CURRENT], pose.position, pose.rotation,
                             legs.floats[:, stepping.SWING_PROGRESS], self.c.parameters["swing_height"], walk[:2],
                             cycle.swing_period / cycle.period / cycle.frequency)

    def apply_admittance(self, admittance: AdmittanceController, leg_modes: np.ndarray) -> None:
        """Raise each walking leg's tip target by its admittance offset (paper eq. 20, z_d = z_r − Δz)."""
        assert self.c.walker is not None
        sensors = self.c.sensors or Sensors()
        spec = self.c.robot.admittance
        if spec.use_joint_effort and sensors.joint_efforts is not None:
            joints = sensors.joints if sensors.joints is not None else self.c.model.joints
            chains = self.c.model.chains
            leg_forces = tip_forces_from_efforts(chains.jacobians(joints), sensors.joint_efforts)
            # τ_motor = −Jᵀ·G holds a ground force G on the foot: G = −F, in base_link through the leg frames.
            force_z = -np.einsum("lj,lj->l", chains.base[:, 2, :3], leg_forces)
        elif sensors.foot_forces is not None:
            force_z = np.asarray(sensors.foot_forces, dtype=float)
        else:
            force_z = np.zeros(len(self.c.stance))
        legs = self.c.walker.legs
        swinging = legs.floats[:, stepping.SWING_PROGRESS] >= 0.0
        height = max(self.c.parameters["swing_height"], 1e-6)
        reach = np.where(swinging, np.clip(np.abs(legs.vectors[:, stepping.CURRENT, 2]
                                                  - legs.vectors[:, stepping.DEFAULT, 2]) / height, 0.0, 1.0), -1.0)
        admittance.mass = self.c.parameters["virtual_mass"]
        admittance.stiffness = self.c.parameters["virtual_stiffness"]
        admittance.damping_ratio = self.c.parameters["virtual_damping_ratio"]
        admittance.force_gain = self.c.parameters["force_gain"]
        delta = admittance.update(force_z, reach, self.c.walker.state != _STOPPED)
        walking = leg_modes == _WALKING_LEG
        self.c.poser_tips = self.c.poser_tips.copy()
        self.c.poser_tips[walking, 2] += delta[walking]


    def change_gait(self) -> None:
        """Switch gait once stopped: new step cycle, limits and offsets (study §4.3); bipod included."""
        assert self.c.walker is not None and self.c.pending_gait is not None
        if self.c.walker.state != WalkState.STOPPED:
            self.c.stop_walking()
            return
        self.c.gait = self.c.pending_gait
        self.c.pending_gait = None
        if self.c.scheduled_failure is not None and self.c.gait is self.c.scheduled_failure.gait:
            self.install_failure(self.c.scheduled_failure)
        self.c.cycle = step_cycle(self.c.gait, self.c.parameters["step_frequency"], self.c.dt)
        self.c.walker.set_cycle(self.c.cycle, self.limits_for(self.c.cycle))
        self.reset_auto_pose()
        if self.c.posture is not None:
            self.c.posture.period = max(self.c.cycle.period, 2)

    def reset_auto_pose(self) -> None:
        """New step cycle or gait: re-synchronise auto posing (OpenSHC does this on gait changes only; doing
        it on step-frequency changes too fixes study §14 quirk 18)."""
        if not self.c.robot.pose.auto:
            return
        pose_set = self.c.pose_sets.get(self.c.gait.name)
        if self.c.autoposer is not None:
            self.c.autoposer.reset(self.c.cycle, self.c.gait, pose_set)
        elif pose_set is not None:
            self.c.autoposer = AutoPoser(pose_set, self.c.gait, self.c.cycle, list(self.c.robot.legs), self.c.dt)

    def limits_for(self, cycle: StepCycle) -> Limits:
        """Limits for ``cycle``; the angular lever arm is leg 0's current default tip, re-read every time."""
        first = self.c.walker.legs.vectors[0, stepping.DEFAULT] if self.c.walker else self.c.identity_walker_tips[0]
        limits = generate_limits(self.c.walkspace, cycle, self.c.dt, math.hypot(first[0], first[1]))
        return limits if self.c.speed_shares is None else self.c.speed_shares(self.c.gait).apply(limits)

    def adjust_parameter(self) -> None:
        """Apply the first pending parameter change (study §9.6). A new step frequency waits until the
        walker has slowed to within the new speed limits, then re-phases the legs."""
        assert self.c.walker is not None
        name, value = self.c.pending_parameters[0]
        spec = getattr(self.c.robot.walker, name, None) or getattr(self.c.robot.admittance, name)
        value = min(max(value, spec.min), spec.max)
        if name == "step_frequency":
            cycle = step_cycle(self.c.gait, value, self.c.dt)
            limits = self.limits_for(cycle)
            self.c.walker.install_speed_limits(limits)
            if not self.c.walker.within_limits_for(limits, self.c.velocity_input, self.c.angular_input):
                return  # slow down to a safe speed first
            self.c.cycle = cycle
            self.c.walker.set_cycle(cycle, limits, rephase=True)
            self.reset_auto_pose()
            if self.c.posture is not None:
                self.c.posture.period = max(self.c.cycle.period, 2)
        elif name == "stance_span_modifier":
            self._set_stance_span(value)
        self.c.parameters[name] = value
        self.c.pending_parameters.pop(0)

    def _set_stance_span(self, modifier: float) -> None:
        """Widen (+) or narrow (−) the stance by a share of each leg's lateral workspace radius (study §5.5);
        it takes effect when the legs next return to their defaults (a stop)."""
        assert self.c.walker is not None
        span = []
        for leg, (_, y) in self.c.stance.items():
            left = y > 0.0
            radius = self.c.planes[leg][90 if left else 270]
            span.append(radius * modifier * (1.0 if left else -1.0))
        self.c.walker.legs.floats[:, stepping.SPAN_CHANGE] = span

