"""One leg's stepping: phase, step state and the Bézier tip trajectory (study §4–§5).

A :class:`LegStepper` owns the walker tip of one leg in the walk-plane frame. Each control cycle
the walk controller calls :meth:`LegStepper.update_tip_position` and then
:meth:`LegStepper.iterate_phase`. Swing and stance both *integrate* the derivative of a quartic
Bézier curve (OpenSHC's behaviour), so the stance is velocity-controlled and the tip lands where
the integration takes it. Operation order follows OpenSHC so recordings match to their precision.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import IntEnum

import numpy as np

from shc_cli.control.bezier import quartic_dot
from shc_cli.control.gait import StepCycle, even_up

Vector = np.ndarray


class StepState(IntEnum):
    """Where a leg is in its step (OpenSHC ``StepState``)."""

    SWING = 0
    STANCE = 1
    FORCE_STANCE = 2
    FORCE_STOP = 3


def rejection(vector: Vector, normal: Vector) -> Vector:
    """Component of ``vector`` perpendicular to ``normal`` (OpenSHC ``getRejection``)."""
    return np.asarray(vector - projection(vector, normal))


def projection(vector: Vector, onto: Vector) -> Vector:
    """Projection of ``vector`` on ``onto``; zero if either is zero (OpenSHC ``getProjection``)."""
    if not np.any(vector) or not np.any(onto):
        return np.zeros(3)
    return np.asarray((float(np.dot(vector, onto)) / float(np.dot(onto, onto))) * onto)


@dataclass
class WalkInputs:
    """What every leg stepper reads from the walk controller in one cycle.

    Attributes:
        linear_velocity: desired body velocity (x, y) after limits and ramp [m/s].
        angular_velocity: desired yaw rate [rad/s].
        cycle: the current step cycle.
        time_delta: control period [s].
        swing_height: apex height above the higher of liftoff and touchdown [m].
        swing_width: outward shift of the swing apex [m].
        walk_plane: plane coefficients (a, b, c) of ``z = a·x + b·y + c``.
        walk_plane_normal: unit normal of the walk plane.
    """

    linear_velocity: Vector
    angular_velocity: float
    cycle: StepCycle
    time_delta: float
    swing_height: float
    swing_width: float
    walk_plane: Vector
    walk_plane_normal: Vector


class LegStepper:
    """Stepping state of one leg (OpenSHC ``LegStepper``); positions in the walk-plane frame [m]."""

    def __init__(self, identity_tip: Vector, offset: int, swing_height: float) -> None:
        self.identity_tip = np.array(identity_tip, dtype=float)
        self.default_tip = self.identity_tip.copy()
        self.current_tip = self.identity_tip.copy()
        self.target_tip = self.identity_tip.copy()
        self.tip_velocity = np.zeros(3)
        self.stride = np.zeros(3)
        self.swing_origin = self.default_tip.copy()
        self.swing_origin_velocity = np.zeros(3)
        self.stance_origin = self.default_tip.copy()
        self.swing_clearance = np.array([0.0, 0.0, swing_height])
        self.walk_plane = np.zeros(3)
        self.walk_plane_normal = np.array([0.0, 0.0, 1.0])
        self.phase = 0
        self.offset = offset
        self.step_state = StepState.STANCE
        self.swing_progress = -1.0
        self.stance_progress = -1.0
        self.step_progress = 0.0
        self.at_correct_phase = False
        self.completed_first_step = False
        self.swing_delta_t = 0.0
        self.stance_delta_t = 0.0
        self.primary_nodes = np.zeros((5, 3))
        self.secondary_nodes = np.zeros((5, 3))
        self.stance_nodes = np.zeros((5, 3))
        self.is_left = bool(self.identity_tip[1] > 0.0)

    # -- phase ------------------------------------------------------------------------------------------------

    def update_step_state(self, cycle: StepCycle) -> None:
        """Step state from the phase; FORCE_STOP is sticky, FORCE_STANCE lasts until the swing window ends."""
        if self.step_state == StepState.FORCE_STOP:
            return
        if cycle.swing_start <= self.phase < cycle.swing_end and self.step_state != StepState.FORCE_STANCE:
            self.step_state = StepState.SWING
        elif self.phase < cycle.stance_end or self.phase >= cycle.stance_start:
            self.step_state = StepState.STANCE

    def iterate_phase(self, cycle: StepCycle) -> None:
        """Advance one iteration and recompute the progress values (which then describe the next cycle)."""
        period = cycle.period
        self.phase = (self.phase + 1) % period
        self.update_step_state(cycle)
        self.step_progress = self.phase / period
        if self.step_state == StepState.SWING:
            progress = (self.phase - cycle.swing_start + 1) / (cycle.swing_end - cycle.swing_start)
            self.swing_progress = min(max(progress, 0.0), 1.0)
            self.stance_progress = -1.0
        elif self.step_state == StepState.STANCE:
            progress = (((self.phase + period - cycle.stance_start) % period) + 1) / (
                (cycle.stance_end - cycle.stance_start) % period
            )
            self.stance_progress = min(max(progress, 0.0), 1.0)
            self.swing_progress = -1.0
        elif self.step_state == StepState.FORCE_STOP:
            self.stance_progress = 0.0
            self.swing_progress = -1.0

    def update_phase(self, cycle: StepCycle) -> None:
        """Re-map the phase onto a new step cycle, keeping the step progress (step frequency change)."""
        self.phase = int(self.step_progress * cycle.period)
        self.update_step_state(cycle)

    # -- trajectory -------------------------------------------------------------------------------------------

    def update_stride(self, inputs: WalkInputs) -> None:
        """Stride vector: body displacement during one stance at the desired velocity (study §5.1)."""
        self.walk_plane = inputs.walk_plane
        self.walk_plane_normal = inputs.walk_plane_normal
        # linear + ω ẑ × (tip with z removed); written out, as np.cross costs more than the rest of the cycle.
        omega, (x, y, _) = inputs.angular_velocity, self.current_tip
        vx, vy = inputs.linear_velocity
        cycle = inputs.cycle
        scale = (cycle.stance_period / cycle.period) / cycle.frequency
        self.stride = np.array([(vx + (0.0 * 0.0 - omega * y)) * scale, (vy + (omega * x - 0.0 * 0.0)) * scale,
                                (0.0 + (0.0 * y - 0.0 * x)) * scale])
        normal = inputs.walk_plane_normal
        self.swing_clearance = inputs.swing_height * (normal / np.linalg.norm(normal))

    def update_tip_position(self, inputs: WalkInputs) -> None:
        """Move the walker tip one control cycle along its swing or stance curve (study §5)."""
        cycle = inputs.cycle
        period = cycle.period
        dt = inputs.time_delta
        standard = self.step_state == StepState.SWING or self.completed_first_step
        stance_start = cycle.stance_start if standard else self.offset
        stance_period = (cycle.stance_end - stance_start) % period
        if cycle.stance_end == stance_start:
            stance_period = period
        swing_iterations = even_up(math.trunc((cycle.swing_period / period) / (cycle.frequency * dt)))
        self.swing_delta_t = 1.0 / (swing_iterations / 2.0)
        stance_iterations = math.trunc((stance_period / period) / (cycle.frequency * dt))
        self.stance_delta_t = 1.0 / stance_iterations
        self.target_tip = self.default_tip + 0.5 * self.stride  # the previous cycle's stride, as in OpenSHC

        if self.step_state == StepState.SWING:
            self.update_stride(inputs)
            iteration = self.phase - cycle.swing_start + 1
            first_half = iteration <= swing_iterations // 2
            if iteration == 1:
                self.swing_origin = self.current_tip.copy()
                self.swing_origin_velocity = self.tip_velocity.copy()
            self._primary_swing_nodes(inputs)
            self._secondary_swing_nodes(dt)
            if first_half:
                t = self.swing_delta_t * iteration
                delta = self.swing_delta_t * quartic_dot(self.primary_nodes, t)
            else:
                t = self.swing_delta_t * (iteration - swing_iterations // 2)
                delta = self.swing_delta_t * quartic_dot(self.secondary_nodes, t)
            self.current_tip = self.current_tip + delta
            self.tip_velocity = delta / dt
        elif self.step_state in (StepState.STANCE, StepState.FORCE_STANCE):
            self.update_stride(inputs)
            iteration = (self.phase + (period - stance_start)) % period + 1
            if iteration == 1:
                self.stance_origin = self.current_tip.copy()
            scaler = stance_period / ((cycle.stance_end - cycle.stance_start) % period)
            step = ((-self.stride) * scaler) * 0.25
            self.stance_nodes = np.stack([self.stance_origin + k * step for k in (0.0, 1.0, 2.0, 3.0, 4.0)])
            t = iteration * self.stance_delta_t
            delta = self.stance_delta_t * quartic_dot(self.stance_nodes, t)
            self.current_tip = self.current_tip + delta
            self.tip_velocity = delta / dt

    def _primary_swing_nodes(self, inputs: WalkInputs) -> None:
        """Lift-off to apex: C0/C1/C2 continuous with the stance, apex over the mid-point (study §5.2)."""
        origin, target = self.swing_origin, self.target_tip
        mid = (origin + target) / 2.0
        mid[2] = max(origin[2], target[2])
        mid = mid + self.swing_clearance
        mid[1] += inputs.swing_width if self.is_left else -inputs.swing_width
        scale = (0.25 * self.swing_origin_velocity) * (inputs.time_delta / self.swing_delta_t)
        p2 = origin + 2.0 * scale
        p3 = (mid + p2) / 2.0
        p3[2] = mid[2]
        self.primary_nodes = np.stack([origin, origin + scale, p2, p3, mid])

    def _secondary_swing_nodes(self, dt: float) -> None:
        """Apex to touchdown, arriving at the stance velocity (study §5.3)."""
        final_velocity = (-self.stride) * (self.stance_delta_t / dt)
        scale = (0.25 * final_velocity) * (dt / self.swing_delta_t)
        apex, before = self.primary_nodes[4], self.primary_nodes[3]
        target = self.target_tip
        self.secondary_nodes = np.stack(
            [apex, apex - (before - apex), target - 2.0 * scale, target - scale, target]
        )

    def update_default_tip(self, default_body_position: Vector) -> None:
        """New default tip after a stop: identity x, y; height through the last stance origin (study §5.5)."""
        point = self.identity_tip + np.zeros(3)  # stance span change (0 without stance_span_modifier)
        point = default_body_position + point
        self.default_tip = point + projection(self.stance_origin - point, self.walk_plane_normal)

    def at_target(self) -> bool:
        """In-plane distance from the tip to its touchdown target below ``TIP_TOLERANCE``."""
        error = rejection(self.current_tip - self.target_tip, self.walk_plane_normal)
        return bool(np.linalg.norm(error) < TIP_TOLERANCE)


TIP_TOLERANCE = 0.01
"""Tip-to-target distance [m] within which a stopping leg counts as back at its default."""
