"""The shares of OpenSHC's speed limits a robot keeps (:mod:`shc_cli.control.verified_limits` finds them by trial
walks): the types the controller applies, apart from the trials that need the controller itself."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from shc_cli.control.limits import Limits

if TYPE_CHECKING:
    from shc_cli.spec.gait import Gait


@dataclass(frozen=True)
class SpeedShares:
    """Shares of OpenSHC's limits a robot keeps.

    Attributes:
        linear: bearing [deg] → share of that bearing's linear speed and acceleration limit (360 repeats 0).
        angular: share of every bearing's angular speed and acceleration limit.
    """

    linear: dict[int, float]
    angular: float

    def apply(self, limits: Limits) -> Limits:
        """``limits`` with every bearing's speeds and accelerations scaled by its shares."""
        bearings = {
            b: replace(lim, linear_speed=lim.linear_speed * self.linear.get(b, 1.0),
                       linear_acceleration=lim.linear_acceleration * self.linear.get(b, 1.0),
                       angular_speed=lim.angular_speed * self.angular,
                       angular_acceleration=lim.angular_acceleration * self.angular)
            for b, lim in limits.bearings.items()}
        return replace(limits, bearings=bearings)

    @property
    def reduced(self) -> dict[str, float]:
        """The shares below 1, as summary.json records them: ``{"90": 0.5, "turn": 0.75}``."""
        out = {str(b): s for b, s in sorted(self.linear.items()) if b != 360 and s < 1.0}
        if self.angular < 1.0:
            out["turn"] = self.angular
        return out


UNCHANGED = SpeedShares({}, 1.0)

ShareSource = Callable[["Gait"], SpeedShares]
"""The controller's source of shares for a gait."""

