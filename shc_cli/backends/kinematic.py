"""The kinematic backend of ``plan``: the commanded joints are the robot's joints; nothing is measured."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from shc_cli.control.controller import CycleOutput
    from shc_cli.control.sensing import Sensors


class KinematicBackend:
    """An ideal robot: every target is reached within the cycle; no sensors, no clock."""

    def start(self) -> np.ndarray | None:
        return None  # the controller's own start

    def begin(self) -> None:
        """Nothing to switch on."""

    def sensors(self, wanted: bool) -> Sensors | None:
        return None

    def apply(self, out: CycleOutput) -> np.ndarray:
        return out.joints

    def advance(self) -> None:
        """No time passes outside the controller."""

    def read(self) -> None:
        return None

    def fault(self) -> str | None:
        return None

    def close(self, faulted: bool = False) -> None:
        """Nothing to release."""
