"""The robot model the controller drives (:class:`Model`): its desired joints, the tips they put the legs at, and
the per-cycle IK step and joint speed guard on them (a part of :class:`~shc_cli.control.controller.Controller`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shc_cli.control.speed_guard import SpeedGuard
from shc_cli.model import kernels
from shc_cli.model.chains import Chains, FloatArray

_OFF_TARGET = tuple(int(not flags & 1) for flags in range(8))
"""Per IK flags value (bit 0 on target, bits 1–2 a position or a velocity clamped): 1 if the leg missed its target."""
_CLAMPED = tuple(int(flags & 6 != 0) for flags in range(8))
"""Per IK flags value: 1 if a joint of the leg was clamped."""
_SPEED_CLAMPED = tuple(int(flags & 4 != 0) for flags in range(8))
"""Per IK flags value: 1 if the IK clamped a joint of the leg to its speed limit (``clamp_joint_velocities``)."""


@dataclass
class Model:
    """The robot model the controller drives: desired joints and the tips they put the legs at."""

    chains: Chains
    joints: FloatArray
    joint_velocities: FloatArray
    avoidance_cap: float = 0.0
    """``ik.limit_avoidance_cap`` (0: OpenSHC's IK step, :func:`~shc_cli.model.kernels.ik_step_one`)."""
    tips: FloatArray = field(init=False)

    def __post_init__(self) -> None:
        self.tips = self.chains.tips(self.joints)
        self._flags = np.zeros(self.chains.size, dtype=np.int64)
        self._frames = np.empty((self.chains.size, self.chains.d.shape[1] + 1, 4, 4))
        self._frames_q = np.full(self.chains.d.shape, np.nan)
        """Each leg's frames of the joints ``_frames_q`` (:func:`~shc_cli.model.kernels.ik_step_frames_kernel`)."""
        self._proximity = np.ones(self.chains.size)
        self._last_targets: FloatArray | None = None
        """The tip targets of the last IK step (how far each target moved feeds ``avoidance_cap``'s blend)."""
        self._no_motion = np.zeros(self.chains.size)
        self._flags[:] = 1
        self.guard: SpeedGuard | None = None
        """The joint speed guard, once :meth:`start_cycle` has been given the control period."""

    def start_cycle(self, dt: float) -> FloatArray:
        """Begin a control cycle: returns the joints it starts from (the last command), for :meth:`limit_speed`."""
        if self.guard is None or self.guard.dt != dt:
            self.guard = SpeedGuard(self.chains, dt)
        self.guard.limited[:] = 0
        return self.joints

    def limit_speed(self, before: FloatArray) -> int:
        """The last step of every cycle (:mod:`shc_cli.control.speed_guard`): no joint moves further than
        ``max_vel·dt`` from ``before``; returns the legs whose joint speed was limited this cycle (by the guard or by
        the IK's velocity clamp)."""
        assert self.guard is not None
        limited = self.guard.apply(before, self.joints, self.joint_velocities)
        if limited is not None:
            self.joints, self.joint_velocities, self.tips = limited
        return int(self.guard.limited.sum())

    def step_ik(self, targets: FloatArray, dt: float, clamp_positions: bool, clamp_velocities: bool,
                active: np.ndarray | None = None) -> tuple[int, int]:
        """One OpenSHC IK step of every leg (or of the ``active`` legs) towards ``targets`` (base_link) [m].

        The step of :func:`shc_cli.model.ik.ik_step`, called directly on the model's own arrays (no input copies, no
        :class:`~shc_cli.model.ik.StepResult`): this is the per-cycle hot path, ≈ 8 µs against ≈ 12 µs for
        ``ik_step`` on 6 legs, so it does not go through that wrapper; and each leg's frames of its last result are
        kept, which its next step starts from (:func:`~shc_cli.model.kernels.ik_step_frames_kernel`). Legs not active
        keep their joints, velocities and tips. Returns (legs off target by > 5 mm, legs with a clamped joint);
        :attr:`proximity` then holds OpenSHC's ``applyIK`` result per leg.
        """
        c = self.chains
        joints, velocities, tips = np.empty_like(self.joints), np.empty_like(self.joints), np.empty_like(self.tips)
        last = self._last_targets
        motion = self._no_motion if last is None else np.sqrt(((targets - last) ** 2).sum(axis=1))
        self._last_targets = np.array(targets, dtype=float)
        kernels.ik_step_frames_kernel(c.base, c.d, c.theta, c.r, c.alpha, c.lower, c.upper, c.max_vel, self.joints,
                                      self.joint_velocities, self.tips, targets, dt, clamp_positions,
                                      clamp_velocities, joints, velocities, tips, self._flags, self._proximity,
                                      self._frames, self._frames_q, motion, 1.0, self.avoidance_cap)
        flags = self._flags.tolist()
        if active is not None:
            keep = ~np.asarray(active, dtype=bool)
            joints[keep], velocities[keep], tips[keep] = self.joints[keep], self.joint_velocities[keep], self.tips[keep]
            flags = [1 if kept else f for kept, f in zip(keep.tolist(), flags, strict=True)]
        self.joints, self.joint_velocities, self.tips = joints, velocities, tips
        if clamp_velocities and self.guard is not None:
            self.guard.clamped_by_ik(np.fromiter(map(_SPEED_CLAMPED.__getitem__, flags), np.int64, len(flags)))
        return sum(map(_OFF_TARGET.__getitem__, flags)), sum(map(_CLAMPED.__getitem__, flags))

    @property
    def proximity(self) -> FloatArray:
        """OpenSHC's ``applyIK`` result of the last step per leg: limit proximity, or 0 if the tip missed its
        target by more than 5 mm on an axis."""
        return np.where((self._flags & 1) != 0, self._proximity, 0.0)

