"""The controller's state enums, the one home of each (OpenSHC's values; light: no numpy, readers of runs and bags
use them too)."""

from __future__ import annotations

from enum import IntEnum


class RobotState(IntEnum):
    """OpenSHC ``RobotState``."""

    UNKNOWN = -1
    PACKED = 0
    READY = 1
    RUNNING = 2


class WalkState(IntEnum):
    """OpenSHC ``WalkState``."""

    STARTING = 0
    MOVING = 1
    STOPPING = 2
    STOPPED = 3


class LegMode(IntEnum):
    """OpenSHC ``LegState``: who drives a leg."""

    WALKING = 0
    MANUAL = 1
    WALKING_TO_MANUAL = 2
    MANUAL_TO_WALKING = 3
