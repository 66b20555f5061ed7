"""Gait timing: OpenSHC's integer step cycle (study §4.1).

Every duration is a whole number of control cycles ("iterations"). The arithmetic below keeps
OpenSHC's operation order and truncations so the periods match the original bit for bit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from shc_cli.spec.gait import Gait


def even_up(n: int) -> int:
    """``n`` if even, else ``n + 1`` (OpenSHC ``roundToEvenInt`` applied to a truncated value)."""
    return n if n % 2 == 0 else n + 1


@dataclass(frozen=True)
class StepCycle:
    """One gait cycle in control iterations.

    Attributes:
        period: iterations per cycle ``P = k·N``.
        normaliser: ``k``, iterations per base unit of the gait.
        swing_start: first swing iteration (= stance end); phase 0 is mid-stance.
        swing_end: first stance iteration after the swing (= stance start).
        swing_period: ``Wp`` iterations of swing.
        stance_period: ``S`` iterations of stance.
        frequency: cycle frequency ``1/(P·dt)`` [Hz].
        offsets: phase offset of each leg in iterations, by leg id.
    """

    period: int
    normaliser: int
    swing_start: int
    swing_end: int
    swing_period: int
    stance_period: int
    frequency: float
    offsets: dict[str, int]

    @property
    def stance_start(self) -> int:
        return self.swing_end

    @property
    def stance_end(self) -> int:
        return self.swing_start

    @property
    def duty_factor(self) -> float:
        """Stance share ``β = S/P``."""
        return self.stance_period / self.period


def step_cycle(gait: Gait, step_frequency: float, time_delta: float) -> StepCycle:
    """The step cycle of ``gait`` at ``step_frequency`` [Hz] and control period ``time_delta`` [s]."""
    base = gait.stance_phase + gait.swing_phase
    swing_ratio = gait.swing_phase / base
    raw_period = ((1.0 / step_frequency) / time_delta) / swing_ratio
    normaliser = even_up(math.trunc(raw_period / base))
    period = base * normaliser
    swing_start = math.trunc(gait.stance_phase * 0.5) * normaliser
    swing_end = swing_start + gait.swing_phase * normaliser
    offsets = {
        leg: (math.trunc(gait.phase_offset * normaliser) * multiplier) % period
        for leg, multiplier in gait.offset_multiplier.items()
    }
    return StepCycle(
        period=period,
        normaliser=normaliser,
        swing_start=swing_start,
        swing_end=swing_end,
        swing_period=gait.swing_phase * normaliser,
        stance_period=gait.stance_phase * normaliser,
        frequency=1.0 / (period * time_delta),
        offsets=offsets,
    )
