"""Speed and acceleration limits per bearing from the walkspace and the step cycle (study §3.3)."""

from __future__ import annotations

from dataclasses import dataclass

from shc_cli.control.gait import StepCycle
from shc_cli.model.workspace import Workplane

UNLIMITED_ACCELERATION = 2147483647.0
"""OpenSHC's value for an acceleration limit where the walkspace radius is zero."""


@dataclass(frozen=True)
class BearingLimit:
    """Limits in one direction of travel.

    Attributes:
        walkspace_radius: usable tip travel from the default position [m].
        scaled_radius: radius after removing stance and swing overshoot [m].
        stance_overshoot: extra stance travel of legs that start mid-swing [m].
        swing_overshoot: travel during the acceleration of one swing [m].
        linear_speed: maximum body speed [m/s].
        linear_acceleration: maximum body acceleration [m/s²].
        angular_speed: maximum yaw rate [rad/s].
        angular_acceleration: maximum yaw acceleration [rad/s²].
    """

    walkspace_radius: float
    scaled_radius: float
    stance_overshoot: float
    swing_overshoot: float
    linear_speed: float
    linear_acceleration: float
    angular_speed: float
    angular_acceleration: float


@dataclass(frozen=True)
class Limits:
    """Limits of every bearing, plus the quantities they came from."""

    bearings: dict[int, BearingLimit]
    time_to_max_stride: float
    max_stance_extension: int
    stance_radius: float


def generate_limits(walkspace: Workplane, cycle: StepCycle, time_delta: float, stance_radius: float) -> Limits:
    """OpenSHC's ``generateLimits``.

    Args:
        walkspace: radius per bearing [m].
        cycle: the current step cycle.
        time_delta: control period [s].
        stance_radius: |xy| of leg 0's default tip, the lever arm for angular limits [m].
    """
    frequency = cycle.frequency
    duty = cycle.duty_factor
    extension = max(
        (cycle.swing_end - o for o in cycle.offsets.values() if cycle.swing_start < o < cycle.swing_end),
        default=0,
    )
    time_to_max = (extension + cycle.stance_period + cycle.swing_period) * time_delta
    out: dict[int, BearingLimit] = {}
    for bearing, radius in walkspace.items():
        if radius <= 0.0:
            out[bearing] = BearingLimit(radius, 0.0, 0.0, 0.0, 0.0, UNLIMITED_ACCELERATION, 0.0,
                                        UNLIMITED_ACCELERATION)
            continue
        speed = 2.0 * radius * frequency / duty
        acceleration = speed / time_to_max
        stance_overshoot = 0.0
        for offset in cycle.offsets.values():
            t = offset * time_delta
            start_speed = acceleration * (time_to_max - t)
            stride = start_speed * duty / frequency
            first = -stride / 2.0 + start_speed * t + 0.5 * acceleration * t * t
            second = speed * (cycle.stance_period * time_delta - t)
            stance_overshoot = max(stance_overshoot, first + second - radius)
        swing_overshoot = 0.5 * speed * cycle.swing_period / (2.0 * cycle.period * frequency)
        scaled = radius * radius / (radius + stance_overshoot + swing_overshoot)
        max_speed = 2.0 * scaled * frequency / duty
        max_acc = max_speed / time_to_max
        angular = max_speed / stance_radius
        out[bearing] = BearingLimit(radius, scaled, stance_overshoot, swing_overshoot, max_speed, max_acc,
                                    angular, angular / time_to_max)
    return Limits(out, time_to_max, extension, stance_radius)
