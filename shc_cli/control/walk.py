"""The walk controller: velocity limits, the STOPPED/STARTING/MOVING/STOPPING machine, odometry (study §4.4, §6).

Each cycle :meth:`WalkController.update` fits the velocity input into the walkspace-derived limits,
ramps the desired velocity under the acceleration limits, runs the walk state machine, moves every
walking leg's tip (:class:`~shc_cli.control.stepper.LegStepper`) and integrates ideal odometry.
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np

from shc_cli.control.gait import StepCycle
from shc_cli.control.limits import BearingLimit, Limits
from shc_cli.control.stepper import LegStepper, StepState, WalkInputs

Vector = np.ndarray


class WalkState(IntEnum):
    """OpenSHC ``WalkState``."""

    STARTING = 0
    MOVING = 1
    STOPPING = 2
    STOPPED = 3


def round_half_away(value: float) -> int:
    """OpenSHC ``roundToInt``: halves round away from zero."""
    return int(value + 0.5) if value >= 0 else -int(0.5 - value)


def clamped_norm(vector: Vector, limit: float) -> Vector:
    """``vector`` scaled down to norm ``limit`` if it is longer."""
    norm = float(np.linalg.norm(vector))
    return vector * (limit / norm) if norm > limit else vector


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
    ) -> None:
        self.cycle = cycle
        self.limits = limits
        self._keys = sorted(limits.bearings)
        self.time_delta = time_delta
        self.swing_height = swing_height
        self.swing_width = swing_width
        self.velocity_input_mode = velocity_input_mode
        self.legs = {
            leg: LegStepper(np.array([x, y, 0.0]), cycle.offsets[leg], swing_height)
            for leg, (x, y) in stance_positions.items()
        }
        self.state = WalkState.STOPPED
        self.desired_linear = np.zeros(2)
        self.desired_angular = 0.0
        self.legs_at_correct_phase = 0
        self.legs_completed_first_step = 0
        self.return_to_default_attempted = False
        self.walk_plane = np.zeros(3)
        self.walk_plane_normal = np.array([0.0, 0.0, 1.0])
        self.odometry_position = np.zeros(3)
        self.odometry_yaw = 0.0

    # -- limits -----------------------------------------------------------------------------------------------

    def sectors(self, linear_input: Vector, angular_input: float) -> list[tuple[int, int, int]]:
        """Per leg, the limit-table keys (lower, upper) and the integer weight of ``upper`` for the stride
        direction at the leg's current walker tip (OpenSHC ``getLimit``: the weight is an integer
        division, so the table is read at the sector *below* the stride bearing)."""
        keys = self._keys
        step = keys[1] - keys[0]
        out = []
        for stepper in self.legs.values():
            tip = stepper.current_tip
            dx = linear_input[0] + angular_input * -tip[1]
            dy = linear_input[1] + angular_input * tip[0]
            bearing = round_half_away((math.atan2(dy, dx) / (2.0 * math.pi)) * 360.0) % 360
            upper = next(k for k in keys if k >= bearing)
            lower = (upper - step) % 360
            if bearing < lower:
                bearing += 360
            if upper < lower:
                upper += 360
            out.append((lower, upper % 360, (bearing - lower) // (upper - lower)))
        return out

    def limit(self, sectors: list[tuple[int, int, int]], field: str) -> float:
        """Smallest limit ``field`` over the legs' sectors."""
        table = self.limits.bearings
        return min((1.0 - share) * _field(table[lower], field) + share * _field(table[upper], field)
                   for lower, upper, share in sectors)

    # -- the cycle ---------------------------------------------------------------------------------------------

    def update(self, linear_input: Vector, angular_input: float, default_body_position: Vector,
               legs_walking: bool = True) -> None:
        """One control cycle of walking (OpenSHC ``updateWalk``).

        Args:
            linear_input: body velocity input (x, y), throttle or m/s.
            angular_input: yaw-rate input, throttle or rad/s.
            default_body_position: position of the walk-plane body pose (for default-tip updates) [m].
            legs_walking: False while any leg is manually manipulated (walking is then suspended).
        """
        linear_input = np.asarray(linear_input, dtype=float)
        sectors = self.sectors(linear_input, angular_input)
        max_speed = self.limit(sectors, "linear_speed")
        max_angular = self.limit(sectors, "angular_speed")
        max_acceleration = self.limit(sectors, "linear_acceleration")
        max_angular_acceleration = self.limit(sectors, "angular_acceleration")
        new_linear, new_angular = np.zeros(2), 0.0
        if self.state != WalkState.STOPPING:
            if self.velocity_input_mode == "throttle":
                new_linear = clamped_norm(linear_input, 1.0) * max_speed
                new_angular = min(max(angular_input, -1.0), 1.0) * max_angular
                new_linear = new_linear * (1.0 - abs(angular_input))
            else:
                new_angular = min(max(angular_input, -max_angular), max_angular)
                new_linear = clamped_norm(linear_input, max_speed)
                new_linear = new_linear * (1.0 - abs(new_angular / max_angular) if max_angular != 0.0 else 0.0)
        has_command = bool(np.linalg.norm(linear_input) != 0.0 or angular_input != 0.0)
        if not legs_walking:
            return
        self._ramp(new_linear, new_angular, max_acceleration, max_angular_acceleration)
        if self._transition(has_command):
            return
        inputs = WalkInputs(self.desired_linear, self.desired_angular, self.cycle, self.time_delta,
                            self.swing_height, self.swing_width, self.walk_plane, self.walk_plane_normal)
        count = len(self.legs)
        for stepper in self.legs.values():
            self._leg_state(stepper, count, default_body_position)
            stepper.update_tip_position(inputs)
            stepper.iterate_phase(self.cycle)
        self._update_walk_plane()
        self._integrate_odometry()

    def _ramp(self, new_linear: Vector, new_angular: float, max_acceleration: float,
              max_angular_acceleration: float) -> None:
        """Acceleration-limited approach of the desired velocity to the new target (study §6)."""
        dt = self.time_delta
        change = new_linear - self.desired_linear
        size = float(np.linalg.norm(change))
        if size < max_acceleration * dt:
            self.desired_linear = self.desired_linear + change
        else:
            self.desired_linear = self.desired_linear + ((change / size) * max_acceleration) * dt
        angular_change = new_angular - self.desired_angular
        if abs(angular_change) < max_angular_acceleration * dt:
            self.desired_angular += angular_change
        else:
            sign = 1.0 if angular_change > 0.0 else -1.0  # OpenSHC: sign(0) = −1
            self.desired_angular += (sign * max_angular_acceleration) * dt

    def _transition(self, has_command: bool) -> bool:
        """Walk state transitions; True when the cycle ends here (the STARTING cycle moves no tip)."""
        count = len(self.legs)
        if self.state == WalkState.STOPPED and has_command:
            self.state = WalkState.STARTING
            for stepper in self.legs.values():
                stepper.at_correct_phase = False
                stepper.completed_first_step = False
                stepper.step_state = StepState.STANCE
                stepper.phase = stepper.offset
                stepper.update_step_state(self.cycle)
            return True
        if (self.state == WalkState.STARTING and self.legs_at_correct_phase == count
                and self.legs_completed_first_step == count):
            self.legs_at_correct_phase = 0
            self.legs_completed_first_step = 0
            self.state = WalkState.MOVING
        elif self.state == WalkState.MOVING and not has_command:
            self.state = WalkState.STOPPING
        elif self.state == WalkState.STOPPING and self.legs_at_correct_phase == count:
            self.legs_at_correct_phase = 0
            self.state = WalkState.STOPPED
        return False

    def _leg_state(self, stepper: LegStepper, count: int, default_body_position: Vector) -> None:
        """Per-leg part of the walk state machine (counters change during the leg loop, as in OpenSHC)."""
        cycle = self.cycle
        if self.state == WalkState.STARTING:
            if (self.legs_at_correct_phase == count and stepper.phase == cycle.swing_end
                    and not stepper.completed_first_step):
                stepper.completed_first_step = True
                self.legs_completed_first_step += 1
            if not stepper.at_correct_phase:
                if cycle.swing_start < stepper.offset < cycle.swing_end and stepper.phase != cycle.swing_end:
                    stepper.step_state = StepState.FORCE_STANCE
                else:
                    self.legs_at_correct_phase += 1
                    stepper.at_correct_phase = True
        elif self.state == WalkState.MOVING:
            stepper.at_correct_phase = False
        elif self.state == WalkState.STOPPING:
            zero_stride = not np.any(stepper.stride)
            if zero_stride and not stepper.at_correct_phase and stepper.phase == cycle.swing_end:
                if stepper.at_target() or self.return_to_default_attempted:
                    self.return_to_default_attempted = False
                    stepper.update_default_tip(default_body_position)
                    stepper.step_state = StepState.FORCE_STOP
                    stepper.at_correct_phase = True
                    self.legs_at_correct_phase += 1
                else:
                    self.return_to_default_attempted = True
        elif self.state == WalkState.STOPPED:
            stepper.step_state = StepState.FORCE_STOP
            stepper.phase = 0

    def _update_walk_plane(self) -> None:
        """Least-squares plane through the legs' default tips (study §7.6)."""
        if len(self.legs) < 3:
            return
        tips = np.array([s.default_tip for s in self.legs.values()])
        design = np.column_stack([tips[:, 0], tips[:, 1], np.ones(len(tips))])
        self.walk_plane = np.linalg.inv(design.T @ design) @ design.T @ tips[:, 2]
        normal = np.array([-self.walk_plane[0], -self.walk_plane[1], 1.0])
        self.walk_plane_normal = normal / np.linalg.norm(normal)

    def _integrate_odometry(self) -> None:
        """Ideal odometry: compose this cycle's commanded motion (study §4.4)."""
        dt = self.time_delta
        step = np.array([self.desired_linear[0] * dt, self.desired_linear[1] * dt, 0.0])
        c, s = math.cos(self.odometry_yaw), math.sin(self.odometry_yaw)
        self.odometry_position = self.odometry_position + np.array([c * step[0] - s * step[1],
                                                                    s * step[0] + c * step[1], 0.0])
        self.odometry_yaw += self.desired_angular * dt

    def set_cycle(self, cycle: StepCycle, limits: Limits) -> None:
        """Install a new step cycle and limits; offsets are reassigned (OpenSHC ``generateLimits``)."""
        self.cycle = cycle
        self.limits = limits
        self._keys = sorted(limits.bearings)
        for leg, stepper in self.legs.items():
            stepper.offset = cycle.offsets[leg]


def _field(limit: BearingLimit, field: str) -> float:
    return float(getattr(limit, field))
