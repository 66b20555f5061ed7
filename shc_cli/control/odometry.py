"""Leg odometry: the body's planar pose (x, y, yaw) in the odom frame from the stance feet, fused with the IMU.

Pure computation (no I/O, no clock), advanced once a control cycle by the controller
(:meth:`shc_cli.control.controller.Controller.step`). The odom frame is the robot's start pose: origin at the body's
start position, x along its start heading, z up.

Method (an shc addition; OpenSHC has no odometry):

1. **Feet in a levelled body frame.** Each leg's foot in base_link comes from forward kinematics of the measured
   joints (``Sensors.joints``), or of the commanded joints on a robot without feedback (``plan``, a servo bus that
   reads nothing back). The feet are turned by the body's roll and pitch — from the IMU orientation when there is
   one, else the controller's own commanded body pose — so they are expressed in a frame that moves with the body
   but stays level (its yaw is the body's).
2. **Rigid fit of the stance feet.** A foot is used when it stood on the ground through the cycle: in the gait's
   stance phase during it (a foot that has just landed counts from its first stance cycle, a foot that lifts off no
   longer does) and, where the backend reports contact, touching at both ends. Feet in stance do not move in the world,
   so their positions before (``p``) and after (``q``) one cycle satisfy ``p ≈ R(dψ)·q + d`` where ``(d, dψ)`` is
   the body's motion over the cycle, in the body's previous level frame. The least-squares ``(d, dψ)`` is the 2-D
   Kabsch/Umeyama solution: ``dψ = atan2(Σ w q̃×p̃, Σ w q̃·p̃)`` over the centred points, ``d = p̄ − R(dψ)·q̄``, each
   foot weighted by its measured normal force where the backend measures it (a lightly loaded foot — touching
   down, lifting off — slips more), else equally. With one foot only ``d`` is found (``dψ`` = 0, or the IMU's);
   with none the pose holds (or turns with the IMU) — except through a contact dropout (feet standing by the gait,
   none touching at both readings, no other foot touching) of at most :data:`HOLD_TIME`, where the last measured
   translation is repeated (and its turn, without an IMU: with one, the IMU measures the turn).
3. **Yaw fusion (complementary filter with a gyro-bias state).** With an IMU, its heading change over the cycle
   ``dψ_imu`` — the yaw change of its orientation (an IMU integrates its gyro at its own, faster rate), or without
   an orientation its body rates turned into the Euler yaw rate ``(ω_y sin φ + ω_z cos φ)/cos θ`` × dt — minus the
   estimated gyro bias ``b`` carries the heading: ``ψ ← ψ + (dψ_imu − b·dt) + k·(ψ_ref − ψ − (dψ_imu − b·dt))``,
   ``k = dt/τ`` (:data:`YAW_TIME_CONSTANT`). The reference heading ``ψ_ref`` and the bias come from the legs only
   while the body is steady — the gait's commanded yaw rate and the smoothed bias-corrected gyro rate both within
   :data:`STEADY_YAW_RATE`: then ``ψ_ref`` takes the legs' turn and ``b`` is the IMU's minus the legs' yaw rate,
   low-passed over ``τ_b`` (:data:`BIAS_TIME_CONSTANT`, with two or more feet fitted); while the body turns,
   ``ψ_ref`` follows the bias-corrected gyro. Feet misread turns by a few % (the quadruped's over-read by 4 %), a
   gyro's bias is a rate: so a turn is the gyro's and the legs bound its drift where their turn is zero.
4. **Composition.** ``x, y ← x, y + R(ψ)·d``: each increment is rotated by the heading it was walked at.

Compared with CHAMP (``champ/odometry``): CHAMP averages each stance foot's displacement in the body frame and the
change of each foot's bearing ``atan2(y, x)`` as the yaw increment, with no levelling and no gyro; the averaged
bearing change is exact only for feet at equal distance from the body origin, and a turn leaks into the
translation. The rigid fit above is exact for any rigid motion of any number of feet (tested), and uses every
stance foot. NUbots' anchor-foot method (``SensorFilter``) fixes the world pose of a foot when it lands and reads
the torso pose through that one foot's kinematics until the next foot lands (fed to a UKF/Mahony filter with the
IMU): natural for a biped with one support foot, but on a hexapod with 3–5 feet in stance it throws away the other
feet's information. Per-cycle increments from all stance feet also need no re-anchoring at a support change.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

YAW_TIME_CONSTANT = 10.0
"""Time constant τ of the yaw filter's heading correction [s]: the heading is pulled towards the filter's reference
heading (the legs' while the body does not turn, the bias-corrected IMU's while it turns) over τ."""

BIAS_TIME_CONSTANT = 10.0
"""Time constant τ_b of the yaw filter's gyro-bias estimate [s]: the IMU's yaw rate minus the legs', low-passed
over τ_b of the cycles in which the legs are trusted (the body standing or walking straight)."""

STEADY_YAW_RATE = 0.05
"""The body counts as not turning — its legs' turn is trusted, and the gyro's bias learned from it — while the
smoothed, bias-corrected IMU yaw rate stays within this [rad/s] (2.9°/s). Feet over- or under-read a turn by a few
% (the quadruped's quad_wave over-reads its turns on the spot by 4 %, bullet's tripod under-reads an arc), a
gyro's bias is a rate: so the legs are believed where their turn is zero, and the gyro carries every turn."""

RATE_TIME_CONSTANT = 0.5
"""Time constant of the smoothing of the bias-corrected IMU yaw rate compared with :data:`STEADY_YAW_RATE` [s]
(about a gait cycle: the body's yaw wobble within a step does not count as a turn)."""


HOLD_TIME = 0.1
"""Longest contact dropout the odometry bridges with the body's last measured motion [s]. When feet stand by the
gait but the contact sensors report none of them touching at both ends of a cycle (a light robot bouncing, a foot
lifting as the body rocks), there is no foot to fit; holding the pose still loses the body's motion over the
dropout (the quadruped's quad_wave so lost 393 cycles of its 104 s square, 8 cm of its first 2 m: 6.8 cm the body
walked in them). The body's velocity changes little in a few cycles, so the last measured increment is repeated
instead, for at most this long (the quadruped's dropouts last 1–7 cycles). Not when a foot the gait has lifted
touches meanwhile: the body may then rest or drag on a moving foot (bullet_mammalian's bipod sinks onto its
swinging feet in 164 of its 166 dropouts; the body moved a third of its last speed there), so its motion is
unknown and the pose holds, as it does after this time or with no foot standing by the gait."""


def euler_yaw_rate(roll: float, pitch: float, rate: np.ndarray) -> float:
    """Rate of the Z-Y-X Euler yaw from the body angular rate ``rate`` (x, y, z) [rad/s] at ``roll``, ``pitch``
    [rad]."""
    return float((rate[1] * math.sin(roll) + rate[2] * math.cos(roll)) / max(math.cos(pitch), 1e-6))


def quaternion_yaw(q: np.ndarray) -> float:
    """Z-Y-X Euler yaw [rad] of a unit quaternion (x, y, z, w): ``atan2(R₁₀, R₀₀)`` from the two entries it needs."""
    x, y, z, w = np.asarray(q, dtype=float).tolist()
    return math.atan2(2 * (x * y + z * w), 1 - 2 * (y * y + z * z))


def level(feet: np.ndarray, roll: float, pitch: float) -> np.ndarray:
    """Feet ``(L, 3)`` in base_link turned by ``Ry(pitch)·Rx(roll)`` into the body's level frame [m]."""
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    rotation = np.array([[cp, sp * sr, sp * cr], [0.0, cr, -sr], [-sp, cp * sr, cp * cr]])
    return np.asarray(np.asarray(feet, dtype=float) @ rotation.T)


def rigid_increment(before: np.ndarray, after: np.ndarray,
                    weights: np.ndarray | None = None) -> tuple[float, float, float]:
    """Body motion ``(dx, dy, dψ)`` [m, m, rad] over one cycle, in the body's earlier level frame, from the
    planar positions ``(K, 2)`` of the same K ≥ 1 world-fixed feet before and after (least squares, 2-D Kabsch;
    ``weights`` ``(K,)`` ≥ 0 weigh the feet, default — or all zero — equally)."""
    total = float(np.sum(weights)) if weights is not None else 0.0
    if weights is not None and total > 0.0:
        w = np.asarray(weights, dtype=float) / total
        p_mean, q_mean = w @ before, w @ after
        p, q = before - p_mean, after - q_mean
        turn = math.atan2(float(w @ (q[:, 0] * p[:, 1] - q[:, 1] * p[:, 0])),
                          float(w @ (q[:, 0] * p[:, 0] + q[:, 1] * p[:, 1]))) if len(before) > 1 else 0.0
        c, s = math.cos(turn), math.sin(turn)
        return (float(p_mean[0] - (c * q_mean[0] - s * q_mean[1])), float(p_mean[1] - (s * q_mean[0] + c * q_mean[1])),
                turn)
    if len(before) < PAIRWISE_FROM:
        return _increment_of_lists(np.asarray(before, dtype=float).tolist(), np.asarray(after, dtype=float).tolist())
    p_mean, q_mean = before.mean(axis=0), after.mean(axis=0)
    if len(before) > 1:
        p, q = before - p_mean, after - q_mean
        turn = math.atan2(float(np.sum(q[:, 0] * p[:, 1] - q[:, 1] * p[:, 0])),
                          float(np.sum(q[:, 0] * p[:, 0] + q[:, 1] * p[:, 1])))
    else:
        turn = 0.0
    c, s = math.cos(turn), math.sin(turn)
    dx = float(p_mean[0] - (c * q_mean[0] - s * q_mean[1]))
    dy = float(p_mean[1] - (s * q_mean[0] + c * q_mean[1]))
    return dx, dy, turn


PAIRWISE_FROM = 8
"""From this many elements NumPy sums a 1-D array pairwise; below it, element by element from the first (as a mean
over the first axis always does) — the order :func:`_increment_of_lists` repeats."""


def _increment_of_lists(before: list[list[float]], after: list[list[float]]) -> tuple[float, float, float]:
    """:func:`rigid_increment` of fewer than :data:`PAIRWISE_FROM` feet given as lists of (x, y[, …]): NumPy's
    operations in NumPy's order on Python floats (the same bits, tested), without NumPy's per-call cost — the
    odometry runs every control cycle."""
    k = len(before)
    px, py = before[0][0], before[0][1]
    qx, qy = after[0][0], after[0][1]
    for i in range(1, k):
        px += before[i][0]
        py += before[i][1]
        qx += after[i][0]
        qy += after[i][1]
    px, py, qx, qy = px / k, py / k, qx / k, qy / k
    if k > 1:
        cross = dot = 0.0
        for i in range(k):
            bx, by = before[i][0] - px, before[i][1] - py
            ax, ay = after[i][0] - qx, after[i][1] - qy
            if i == 0:
                cross, dot = ax * by - ay * bx, ax * bx + ay * by
            else:
                cross += ax * by - ay * bx
                dot += ax * bx + ay * by
        turn = math.atan2(cross, dot)
    else:
        turn = 0.0
    c, s = math.cos(turn), math.sin(turn)
    return px - (c * qx - s * qy), py - (s * qx + c * qy), turn


class LegOdometry:
    """The body's planar pose in the odom frame, from stance-foot increments and (optionally) the IMU's heading.

    Each cycle is one call of the compiled :func:`shc_cli.control.odometry_kernels.odometry_cycle` (the formulas of
    :func:`level` and :func:`rigid_increment` above, which stay as the reference: tests/test_odometry.py).

    Args:
        time_delta: control period [s].
        yaw_time_constant: τ of the yaw filter's heading correction [s] (used only with an IMU; 0 or less: none,
            the bias-corrected IMU heading alone).
        hold_time: longest contact dropout bridged by the last measured motion [s] (:data:`HOLD_TIME`).
        bias_time_constant: τ_b of the yaw filter's gyro-bias estimate [s] (0 or less: no bias estimated).
        steady_yaw_rate: the smoothed yaw rate [rad/s] up to which the legs' turn is trusted
            (:data:`STEADY_YAW_RATE`).
    """

    def __init__(self, time_delta: float, yaw_time_constant: float = YAW_TIME_CONSTANT,
                 hold_time: float = HOLD_TIME, bias_time_constant: float = BIAS_TIME_CONSTANT,
                 steady_yaw_rate: float = STEADY_YAW_RATE) -> None:
        self.dt = time_delta
        self.gain = min(time_delta / yaw_time_constant, 1.0) if yaw_time_constant > 0.0 else 0.0
        """The heading gain dt/τ."""
        self.bias_gain = min(time_delta / bias_time_constant, 1.0) if bias_time_constant > 0.0 else 0.0
        """The bias gain dt/τ_b."""
        self.rate_gain = min(time_delta / RATE_TIME_CONSTANT, 1.0)
        """The smoothing gain of the yaw rate that tells turning from steady."""
        self.steady_yaw_rate = steady_yaw_rate
        self.hold = max(round(hold_time / time_delta), 0) if time_delta > 0.0 else 0
        """Cycles a contact dropout repeats the last measured increment (:data:`HOLD_TIME`)."""
        self._state = np.array([0.0, 0.0, 0.0, 0.0, math.nan, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        """x [m], y [m], yaw [rad], the legs' heading [rad], the IMU's last heading [rad], whether foot contact
        was measured last cycle, the last measured increment (dx, dy [m], turn [rad]) and the cycles it was held,
        the yaw filter's reference heading [rad], gyro-bias estimate [rad/s] and smoothed yaw rate [rad/s]
        (:mod:`shc_cli.control.odometry_kernels`)."""
        self._feet: np.ndarray | None = None
        self._spare: np.ndarray | None = None
        self._zeros: np.ndarray | None = None
        self._contact_before: np.ndarray | None = None
        self._no_orientation = np.zeros(4)
        self._kernel: Callable[..., int] | None = None
        """The compiled cycle, imported at the first :meth:`cycle` (an import statement costs ≈ 1 µs a cycle)."""
        self.feet_used = 0
        """Stance feet in the last increment."""

    @property
    def x(self) -> float:
        """x in the odom frame [m]."""
        return float(self._state[0])

    @property
    def y(self) -> float:
        """y in the odom frame [m]."""
        return float(self._state[1])

    @property
    def yaw(self) -> float:
        """Heading in the odom frame [rad]."""
        return float(self._state[2])

    @property
    def leg_yaw(self) -> float:
        """Heading from the legs alone [rad] (their turns integrated, whether trusted or not)."""
        return float(self._state[3])

    @property
    def reference_yaw(self) -> float:
        """The yaw filter's reference heading [rad]: the legs' turns while the body does not turn, the
        bias-corrected IMU's while it does (the legs' heading without an IMU)."""
        return float(self._state[10])

    @property
    def gyro_bias(self) -> float:
        """The yaw filter's estimate of the IMU's yaw-rate bias [rad/s] (0 without an IMU)."""
        return float(self._state[11])

    @property
    def pose(self) -> tuple[float, float, float]:
        """(x [m], y [m], yaw [rad]) in the odom frame."""
        x, y, yaw = self._state.tolist()[:3]
        return (x, y, yaw)

    def update(self, feet: np.ndarray, stance: np.ndarray, turn: float | None = None,
               weights: np.ndarray | None = None) -> tuple[float, float, float]:
        """Advance one cycle with feet already in the body's level frame (:func:`level`); see :meth:`cycle`."""
        return self.cycle(feet, 0.0, 0.0, stance, turn, weights)

    def cycle(self, feet: np.ndarray, roll: float, pitch: float, stance: np.ndarray, turn: float | None = None,
              forces: np.ndarray | None = None, orientation: np.ndarray | None = None,
              contact: np.ndarray | None = None, commanded_turn_rate: float = 0.0) -> tuple[float, float, float]:
        """Advance one cycle.

        Args:
            feet: every foot in base_link ``(L, 3)`` [m], now.
            roll, pitch: the body's roll and pitch [rad], which level the feet (:func:`level`), when there is no
                ``orientation``.
            stance: feet that stood on the ground since the last update ``(L,)``.
            turn: the heading change over the cycle from the IMU's rates [rad] (:func:`euler_yaw_rate` × dt) when
                there is no ``orientation``, or None.
            forces: each foot's weight in the fit ``(L,)`` (its measured normal force [N]; negative counts as 0),
                or None (equal).
            orientation: the IMU's orientation (x, y, z, w), or None: it gives roll, pitch and the heading change
                (the yaw change of the orientation since the last one: the IMU integrates its gyro at its own rate).
            contact: measured foot contact ``(L,)``, or None: a foot counts only when touching at both readings.
            commanded_turn_rate: the yaw rate the gait walks at [rad/s] (the walker's desired angular velocity):
                beyond :attr:`steady_yaw_rate` the body is turning and its legs' turn is not trusted.

        Returns:
            the new pose (x, y, yaw).
        """
        kernel = self._kernel
        if kernel is None:
            from shc_cli.control.odometry_kernels import odometry_cycle

            kernel = self._kernel = odometry_cycle
        feet = np.ascontiguousarray(feet, dtype=float)
        legs = len(feet)
        after = self._spare
        if after is None or after.shape != feet.shape:
            after = np.empty_like(feet)
        before = self._feet
        zeros = self._zeros
        if zeros is None or len(zeros) != legs:
            zeros = self._zeros = np.zeros(legs)
        if self._contact_before is None or len(self._contact_before) != legs:
            self._contact_before = np.zeros(legs, dtype=bool)
        has_orientation = orientation is not None
        self.feet_used = kernel(
            feet, np.ascontiguousarray(orientation, dtype=float) if has_orientation else self._no_orientation,
            has_orientation, roll, pitch, after if before is None else before, after,
            np.ascontiguousarray(stance, dtype=bool),
            np.ascontiguousarray(contact, dtype=bool) if contact is not None else self._contact_before,
            self._contact_before, contact is not None,
            np.ascontiguousarray(forces, dtype=float) if forces is not None else zeros, forces is not None,
            before is not None, math.nan if turn is None else turn, self.gain, self.hold, self.bias_gain,
            self.rate_gain, self.steady_yaw_rate, self.dt, commanded_turn_rate, self._state)
        self._feet, self._spare = after, before
        x, y, yaw = self._state.tolist()[:3]
        return (x, y, yaw)
