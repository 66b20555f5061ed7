"""shc's joint speed guard: no control cycle commands a joint faster than its ``max_vel`` (docs/deviations.md).

OpenSHC limits joint speed only inside the IK step, and only with ``clamp_joint_velocities`` (study §2.2); its
joint-space transitions (start-up, pack, unpack) and an IK without the clamp may move a joint further in one
cycle than its servo can. The guard is the controller's last step of every cycle: each joint moves at most
``max_vel·dt`` from the joints the cycle started from (the last command). A limited joint stops at that bound with
velocity ``± max_vel``; the model's tips follow (FK), so the next IK step carries the rest, as after OpenSHC's own
velocity clamp. On motion within the limits (every recording of the real binary) it changes nothing.
"""

from __future__ import annotations

import numpy as np

from shc_cli.model import kernels
from shc_cli.model.chains import Chains, FloatArray


class SpeedGuard:
    """The per-cycle joint speed limit of one robot's legs, and which legs were limited this cycle.

    Args:
        chains: the legs (their ``max_vel``).
        dt: the control period [s].
    """

    def __init__(self, chains: Chains, dt: float) -> None:
        self.chains, self.dt = chains, dt
        self.bound = chains.max_vel * dt
        """Each joint's largest motion in one cycle, ``max_vel·dt`` [rad]."""
        self._check = self.bound + kernels.SPEED_TOLERANCE
        self.limited = np.zeros(chains.size, dtype=np.int64)
        """Per leg, 1 where a joint's speed was limited this cycle (the IK's velocity clamp or the guard)."""
        self._guarded = np.zeros(chains.size, dtype=np.int64)

    def clamped_by_ik(self, legs: np.ndarray) -> None:
        """Record the legs (1/0 per leg) whose joint speeds the IK's velocity clamp limited this cycle."""
        self.limited |= legs

    def apply(self, before: FloatArray, joints: FloatArray, velocities: FloatArray
              ) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """Limit ``joints`` (this cycle's command) to ``before ± max_vel·dt``: the new joints, velocities and tips,
        or None when no joint moved too far."""
        if not kernels.joint_speed_exceeded(before, joints, self._check):
            return None
        out, rates = np.empty_like(joints), np.empty_like(joints)
        kernels.limit_joint_speed_kernel(before, joints, self.bound, out, velocities, rates, self.dt, self._guarded)
        self.limited |= self._guarded
        return out, rates, self.chains.tips(out)
