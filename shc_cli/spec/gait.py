"""Gait files: OpenSHC's phase model (study §4, §11.4) for any number of legs."""

from __future__ import annotations

from pydantic import Field, field_validator

from shc_cli.spec.robot import Strict


class Gait(Strict):
    """A gait as OpenSHC defines it: base stance/swing lengths and per-leg phase offsets.

    One base cycle has ``stance_phase + swing_phase`` units; leg ``j`` is offset by
    ``phase_offset × offset_multiplier[j]`` units. Durations follow from the robot's step frequency
    (≈ 1 / swing duration) and control period.
    """

    name: str = Field(description="short name, e.g. 'tripod'")
    description: str = Field("", description="one sentence for people")
    stance_phase: int = Field(ge=0, description="stance share of the base cycle [units]; use even values")
    swing_phase: int = Field(gt=0, description="swing share of the base cycle [units]")
    phase_offset: int = Field(ge=0, description="base offset between legs [units]")
    offset_multiplier: dict[str, int] = Field(description="leg id → multiple of phase_offset")

    @field_validator("offset_multiplier")
    @classmethod
    def _has_legs(cls, offset_multiplier: dict[str, int]) -> dict[str, int]:
        """On the field, so the error points at the [offset_multiplier] table."""
        if not offset_multiplier:
            raise ValueError("names no leg; give one multiplier per leg, e.g. AR = 0")
        return offset_multiplier

    @property
    def base_length(self) -> int:
        """Units in one base cycle, ``N = stance_phase + swing_phase``."""
        return self.stance_phase + self.swing_phase

    @property
    def duty_factor(self) -> float:
        """Share of the cycle a leg spends in stance, ``β = stance / (stance + swing)``."""
        return self.stance_phase / self.base_length
