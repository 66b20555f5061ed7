"""The walk controller: velocity limits, the STOPPED/STARTING/MOVING/STOPPING machine, odometry (study §4.4, §6).

Each cycle :meth:`WalkController.update` fits the velocity input into the walkspace-derived limits,
ramps the desired velocity under the acceleration limits, runs the walk state machine, moves every
walking leg's tip (compiled in :mod:`shc_cli.control.stepping`) and integrates ideal odometry.
"""

from __future__ import annotations

import numpy as np

from shc_cli.control import stepping
from shc_cli.control.gait import StepCycle
from shc_cli.control.limits import Limits
from shc_cli.control.states import WalkState as WalkState  # re-exported
from shc_cli.control.stepping import LegArrays

Vector = np.ndarray


class WalkController:
    """Walking of all legs (OpenSHC ``WalkController``).

    Args:
        stance_positions: each leg's identity tip (x, y) in the walk plane [m], legs in id order.
        cycle: the gait's step cycle.
        limits: speed/acceleration limits per bearing (from the walkspace).
        time_delta: control period [s].
        swing_height: swing apex height [m].
        swing_width: outward apex shift [m].
        velocity_input_mode: 'throttle' (inputs −1..1 of the maximum) or 'real' (m/s, rad/s).
        rough_terrain: OpenSHC's rough-terrain mode (study §5.5, §5.7).
    """

    def __init__(
        self,
        stance_positions: dict[str, tuple[float, float]],
        cycle: StepCycle,
        limits: Limits,
        time_delta: float,
        swing_height: float,
        swing_width: float,
        velocity_input_mode: str = "throttle",
        rough_terrain: bool = False,
    ) -> None:
        self.cycle = cycle
        self.rough_terrain = rough_terrain
        """OpenSHC ``rough_terrain_mode``: default tips follow the footholds; step depth and touchdown with sensing."""
        self._install_limits(limits)
        self.time_delta = time_delta
        self.swing_height = swing_height
        self.swing_width = swing_width
        self.velocity_input_mode = velocity_input_mode
        self.leg_ids = list(stance_positions)
        identity = np.array([[x, y, 0.0] for x, y in stance_positions.values()])
        self.legs = LegArrays(identity, [cycle.offsets[leg] for leg in self.leg_ids], swing_height)
        self.counters = np.zeros(3, dtype=np.int64)
        self.state = WalkState.STOPPED
        self._walk = np.zeros(stepping.WALK_SLOTS)
        """Desired velocity and ideal odometry (slots in :mod:`stepping`), updated by the compiled cycle."""
        self._throttle = velocity_input_mode == "throttle"
        self.walk_plane = np.zeros(3)
        self.walk_plane_normal = np.array([0.0, 0.0, 1.0])
        self._plane_tips: np.ndarray | None = None
        self._no_contacts = np.zeros(len(self.leg_ids), dtype=np.bool_)
        self.step_plane: tuple[np.ndarray, np.ndarray] | None = None
        """This cycle's step-plane input (:mod:`shc_cli.control.step_plane`): each leg's target shift ``(L, 3)``
        in the walk-plane frame and swing clearance ``(L,)`` [m]; ``None``: blind (OpenSHC's behaviour)."""
        self.max_plane_slope = 0.0
        self.body_floor = -np.inf
        """With a step-plane input, the walk plane's height at the body is at least this (walk-plane frame) [m]."""
        self.floor_deadband = 0.0
        """A floor less than this above the walk plane is map noise and leaves the plane as it is [m]."""
        """With a step-plane input, the walk plane's slope is clamped to this (tan of its pitch and roll)."""
        self._no_offsets = np.zeros((len(self.leg_ids), 3))
        self._no_clearances = np.zeros(len(self.leg_ids))

    @property
    def cycle(self) -> StepCycle:
        """The step cycle the legs follow."""
        return self._cycle

    @cycle.setter
    def cycle(self, cycle: StepCycle) -> None:
        self._cycle = cycle
        self._cycle_values = (cycle.period, cycle.swing_start, cycle.swing_end, cycle.stance_start, cycle.stance_end,
                              cycle.swing_period, cycle.stance_period, cycle.frequency)
        """What the compiled cycle reads of it, in its argument order (read once, not every cycle)."""

    # -- limits -----------------------------------------------------------------------------------------------

    def limits_for(self, linear_input: Vector, angular_input: float) -> tuple[float, float, float, float]:
        """(speed, yaw rate, acceleration, yaw acceleration) limits for this input at the current tips."""
        stepping.walk_limits(self.legs.vectors[:, stepping.CURRENT], float(linear_input[0]), float(linear_input[1]),
                             float(angular_input), self._table, self._bearing_step, self._limit_out)
        speed, angular, acceleration, angular_acceleration = self._limit_out
        return float(speed), float(angular), float(acceleration), float(angular_acceleration)

    def _install_limits(self, limits: Limits) -> None:
        """Limits as a table ``(bearings, 4)`` for the compiled lookup."""
        self.limits = limits
        keys = sorted(limits.bearings)
        self._bearing_step = keys[1] - keys[0]
        self._table = np.array([[limits.bearings[k].linear_speed, limits.bearings[k].angular_speed,
                                 limits.bearings[k].linear_acceleration, limits.bearings[k].angular_acceleration]
                                for k in keys])
        self._limit_out = np.empty(4)

    # -- the cycle ---------------------------------------------------------------------------------------------

    def update(self, linear_input: Vector, angular_input: float, default_body_position: Vector,
               legs_walking: bool = True, posing_complete: bool = True, contacts: Vector | None = None,
               step_depth: float = 0.0) -> None:
        """One control cycle of walking (OpenSHC ``updateWalk``; compiled in :func:`stepping.walk_update`).

        Args:
            linear_input: body velocity input (x, y), throttle or m/s.
            angular_input: yaw-rate input, throttle or rad/s.
            default_body_position: position of the walk-plane body pose (for default-tip updates) [m].
            legs_walking: False while any leg is manually manipulated (walking is then suspended).
            posing_complete: the auto poser has finished its cycles (STOPPING → STOPPED waits for it).
            contacts: feet on the ground by their force sensors (rough-terrain mode), ``None`` without sensing.
            step_depth: reactive target lowering in rough-terrain mode [m].
        """
        legs = self.legs
        plane_input = self.step_plane
        perceive = plane_input is not None
        offsets, clearances = (self._no_offsets, self._no_clearances) if plane_input is None else plane_input
        state, moved = stepping.walk_update(
            legs.vectors, legs.nodes, legs.floats, legs.integers, self.counters, self._walk, int(self.state),
            self._table, self._bearing_step, *self._cycle_values, self.time_delta, float(linear_input[0]),
            float(linear_input[1]), float(angular_input),
            self._throttle, self.swing_height, self.swing_width, self.walk_plane, self.walk_plane_normal,
            np.asarray(default_body_position, dtype=float), legs_walking, posing_complete, self._limit_out,
            self.rough_terrain, float(step_depth), contacts is not None,
            self._no_contacts if contacts is None else np.asarray(contacts, dtype=np.bool_),
            perceive, offsets, clearances,
        )
        if state != self.state:
            self.state = WalkState(state)
        if plane_input is not None:  # seeing the ground: the plane of the predicted footholds
            self._update_walk_plane(stepping.TARGET)
        elif moved or self._plane_tips is None:  # the plane only depends on the default tips
            self._plane_tips = self.legs.vectors[:, stepping.DEFAULT].copy()
            self._update_walk_plane()

    @property
    def desired_linear(self) -> Vector:
        """Desired body velocity (x, y) after limits and ramp [m/s]."""
        return np.array([self._walk[stepping.DESIRED_X], self._walk[stepping.DESIRED_Y]])

    def desired_velocity(self) -> tuple[float, float, float]:
        """Desired body velocity after limits and ramp: (x [m/s], y [m/s], yaw rate [rad/s])."""
        walk = self._walk
        return float(walk[stepping.DESIRED_X]), float(walk[stepping.DESIRED_Y]), float(walk[stepping.DESIRED_YAW_RATE])

    @property
    def desired_angular(self) -> float:
        """Desired yaw rate [rad/s]."""
        return float(self._walk[stepping.DESIRED_YAW_RATE])

    @property
    def odometry_position(self) -> Vector:
        """Ideal odometry: integrated commanded position in the start frame [m]."""
        return np.array(self._walk[stepping.ODOMETRY_X:stepping.ODOMETRY_Z + 1])

    @property
    def odometry_yaw(self) -> float:
        """Ideal odometry heading [rad]."""
        return float(self._walk[stepping.ODOMETRY_YAW])

    def _update_walk_plane(self, slot: int = stepping.DEFAULT) -> None:
        """Least-squares plane through the legs' default tips (study §7.6).

        With a step-plane input, through the legs' targets (the predicted footholds, ATHENA-style), its slope
        clamped to :attr:`max_plane_slope`: the body rises and tilts before the feet step up.
        """
        if len(self.leg_ids) < 3:
            return
        tips = self.legs.vectors[:, slot]
        design = np.column_stack([tips[:, 0], tips[:, 1], np.ones(len(tips))])
        self.walk_plane = np.linalg.inv(design.T @ design) @ design.T @ tips[:, 2]
        if slot != stepping.DEFAULT:
            limit = self.max_plane_slope
            self.walk_plane[:2] = np.clip(self.walk_plane[:2], -limit, limit)
            if self.body_floor > self.walk_plane[2] + self.floor_deadband:  # (a few mm of map noise: nothing)
                self.walk_plane[2] = self.body_floor
        normal = np.array([-self.walk_plane[0], -self.walk_plane[1], 1.0])
        self.walk_plane_normal = normal / np.linalg.norm(normal)

    def set_cycle(self, cycle: StepCycle, limits: Limits, rephase: bool = False) -> None:
        """Install a new step cycle and limits; offsets are reassigned (OpenSHC ``generateLimits``).

        With ``rephase`` (a step-frequency change) walking legs keep their place in the step:
        ``phase = int(step_progress·P_new)`` (OpenSHC ``updatePhase``).
        """
        self.cycle = cycle
        self._install_limits(limits)
        self.legs.integers[:, stepping.OFFSET] = [cycle.offsets[leg] for leg in self.leg_ids]
        if rephase and self.state != WalkState.STOPPED:
            integers, floats = self.legs.integers, self.legs.floats
            for leg in range(len(self.leg_ids)):
                integers[leg, stepping.PHASE] = int(floats[leg, stepping.STEP_PROGRESS] * cycle.period)
                stepping.update_step_state(integers, leg, cycle.swing_start, cycle.swing_end, cycle.stance_start,
                                           cycle.stance_end)

    def install_speed_limits(self, limits: Limits) -> None:
        """Use only the new speed limits (accelerations unchanged), as OpenSHC does while a new step
        frequency waits for the robot to slow down."""
        keys = sorted(limits.bearings)
        self._table[:, 0] = [limits.bearings[k].linear_speed for k in keys]
        self._table[:, 1] = [limits.bearings[k].angular_speed for k in keys]

    def within_limits_for(self, limits: Limits, linear_input: Vector, angular_input: float) -> bool:
        """Whether the desired velocity is already within the targets the new limits allow (OpenSHC's
        component-wise test, kept as it is: ``v_x ≤ target_x``, ``v_y ≤ target_y``, ``|ω| ≤ |target_ω|``)."""
        max_speed, max_angular, _, _ = self.limits_for(linear_input, angular_input)
        if self.velocity_input_mode == "throttle":
            target = np.array(stepping.clamped_norm(float(linear_input[0]), float(linear_input[1]), 1.0))
            target = target * max_speed * (1.0 - abs(angular_input))
            target_angular = min(max(angular_input, -1.0), 1.0) * max_angular
        else:
            target = np.array(stepping.clamped_norm(float(linear_input[0]), float(linear_input[1]), max_speed))
            target_angular = min(max(angular_input, -max_angular), max_angular)
        return bool(self.desired_linear[0] <= target[0] and self.desired_linear[1] <= target[1]
                    and abs(self.desired_angular) <= abs(target_angular))
