"""Sensor feedback for the controller, and the posing terms driven by it.

* :class:`Sensors` — what a backend measured during the last control period (all optional: ``plan`` has none).
* :class:`ContactDetector` — touchdown/lift-off of each foot from its force, with hysteresis.
* :class:`ImuPoser` — OpenSHC IMU posing (study §7.4): roll/pitch PID levelling against the IMU.
* :func:`inclination_pose` — OpenSHC inclination posing (study §7.5): a body shift against the tilt,
  ``x = −h·tan(pitch)``, ``y = h·tan(roll)``; or, as an option, the paper's intent: shift the body so the
  gravity projection of the centre of mass falls on the centroid of the stance feet's support polygon.
* :class:`PostureController` — the ATHENA posture controller (seed 003 §4.2, eq. 24–31): once per gait
  cycle, a plane through the feet in contact and the body height give height, pitch and roll corrections,
  scaled by ``k_z``, ``k_α``, ``k_β`` ∈ [0, 1], which the feet trajectories take in linearly over the next
  half cycle (eq. 31).

Each term is a :class:`~shc_cli.control.pose.Pose` the pose controller composes into the body pose
(``walk_plane → base_link``): a rotation θ there tilts the body by θ relative to its feet.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from shc_cli.control.pose import IDENTITY, Pose, euler_from_matrix, rot_x, rot_y, rot_z

IMU_DERIVATIVE_FILTER = 0.15
"""Low-pass share of the new angular-rate sample in the IMU posing derivative term (OpenSHC)."""
IMU_STABILITY_THRESHOLD = 100.0
"""OpenSHC stops when an IMU posing correction exceeds this [rad]; here the correction is only clamped."""


@dataclass(slots=True)
class Sensors:
    """Measurements of the last control period (legs in id order); ``None`` where the backend has none.

    Made once a control cycle, so not a frozen dataclass (slower to make); the controller never changes it.

    Attributes:
        orientation: IMU orientation quaternion (x, y, z, w), body → world.
        angular_rate: IMU angular velocity in the body frame [rad/s].
        joints: measured joint positions ``(L, n)`` [rad].
        joint_efforts: measured joint torques ``(L, n)`` [N·m].
        foot_forces: contact normal force per foot ``(L,)`` [N].
        foot_contact: foot touching the ground ``(L,)``.
        body_height: body height above the terrain below it [m] (ATHENA's infrared sensor).
    """

    orientation: np.ndarray | None = None
    angular_rate: np.ndarray | None = None
    joints: np.ndarray | None = None
    joint_efforts: np.ndarray | None = None
    foot_forces: np.ndarray | None = None
    foot_contact: np.ndarray | None = None
    body_height: float | None = None


class ContactDetector:
    """Touchdown and lift-off from foot forces with hysteresis (OpenSHC study §8.4): a foot touches down when its
    force rises above ``touchdown`` and lifts off when it falls below ``liftoff``.

    Args:
        legs: number of legs.
        touchdown: force above which a foot is down [N].
        liftoff: force below which a foot is up [N] (≤ ``touchdown``).
    """

    def __init__(self, legs: int, touchdown: float, liftoff: float) -> None:
        self.touchdown, self.liftoff = touchdown, min(liftoff, touchdown)
        self.down = np.zeros(legs, dtype=bool)

    def update(self, forces: np.ndarray) -> np.ndarray:
        """This cycle's contact state from the feet's force magnitudes [N]."""
        forces = np.asarray(forces, dtype=float)
        self.down = np.where(self.down, forces >= self.liftoff, forces > self.touchdown)
        return self.down


def quaternion_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (x, y, z, w); for an array of quaternions ``(..., 4)``, ``(..., 3, 3)``."""
    q = np.asarray(q, dtype=float)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)], axis=-1),
        np.stack([2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)], axis=-1),
        np.stack([2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1),
    ], axis=-2)


def quaternion_roll_pitch(q: np.ndarray) -> tuple[float, float]:
    """Roll and pitch [rad] of a unit quaternion (x, y, z, w): ``euler_from_matrix(quaternion_matrix(q))[:2]`` from
    the three matrix entries they need, with the same operations in the same order (the same bits; the leg odometry
    calls it every cycle, where building the whole matrix cost ≈ 20 µs)."""
    x, y, z, w = np.asarray(q, dtype=float).tolist()
    r20 = 2 * (x * z - y * w)
    r21 = 2 * (y * z + x * w)
    r22 = 1 - 2 * (x * x + y * y)
    pitch = float(np.arcsin(-min(max(r20, -1.0), 1.0)))  # np.clip of one value (NaN stays NaN)
    return float(np.arctan2(r21, r22)), pitch


def rpy_matrix(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """``Rz(yaw)·Ry(pitch)·Rx(roll)`` for one orientation [rad]. Kept apart from the batched scipy
    :func:`shc_cli.analysis.metrics.rotation_rpy`: the controller stays numpy-only and calls this every cycle."""
    return np.asarray(rot_z(yaw) @ rot_y(pitch) @ rot_x(roll))


class ImuPoser:
    """OpenSHC IMU posing (study §7.4): ``c = −(k_d·D + k_p·e + k_i·∫e)`` on roll and pitch.

    ``e`` = roll/pitch of ``R_imu·R_manual⁻¹`` (yaw zeroed), ``D`` = low-passed negated body angular rate.

    Args:
        gains: (p, i, d).
        max_rotation: clamp of the roll/pitch correction (roll, pitch) [rad].
        time_delta: control period [s].
    """

    def __init__(self, gains: tuple[float, float, float], max_rotation: tuple[float, float], time_delta: float) -> None:
        self.kp, self.ki, self.kd = gains
        self.max_rotation = max_rotation
        self.dt = time_delta
        self.absement = np.zeros(3)
        self.derivative = np.zeros(3)
        self.error = np.zeros(3)

    def update(self, orientation: np.ndarray, angular_rate: np.ndarray, manual: Pose) -> Pose:
        """This cycle's IMU pose (absolute, replaces auto posing)."""
        relative = quaternion_matrix(orientation) @ manual.rotation.T
        roll, pitch, _ = euler_from_matrix(relative)
        self.error = np.array([roll, pitch, 0.0])
        self.absement = self.absement + self.error * self.dt
        self.derivative = IMU_DERIVATIVE_FILTER * (-np.asarray(angular_rate, dtype=float)) \
            + (1.0 - IMU_DERIVATIVE_FILTER) * self.derivative
        correction = -(self.kd * self.derivative + self.kp * self.error + self.ki * self.absement)
        c_roll = float(np.clip(correction[0], -self.max_rotation[0], self.max_rotation[0]))
        c_pitch = float(np.clip(correction[1], -self.max_rotation[1], self.max_rotation[1]))
        _, _, yaw = manual.euler()
        return Pose(np.zeros(3), rpy_matrix(c_roll, c_pitch, yaw))


def inclination_pose(orientation: np.ndarray, posing: Pose, body_clearance: float,
                     max_translation: tuple[float, float]) -> Pose:
    """OpenSHC inclination posing (study §7.5): ``(−h·tan(pitch), h·tan(roll), 0)``, clamped.

    Args:
        orientation: IMU quaternion (x, y, z, w).
        posing: the manual and auto pose composed (their tilt is intended, not measured).
        body_clearance: ``h`` [m].
        max_translation: clamp (x, y) [m].
    """
    relative = quaternion_matrix(orientation) @ posing.rotation.T
    roll, pitch, _ = euler_from_matrix(relative)
    x = float(np.clip(-body_clearance * math.tan(pitch), -max_translation[0], max_translation[0]))
    y = float(np.clip(body_clearance * math.tan(roll), -max_translation[1], max_translation[1]))
    return Pose(np.array([x, y, 0.0]), IDENTITY)


def support_centroid_pose(orientation: np.ndarray, stance_tips: np.ndarray, com: np.ndarray,
                          body_clearance: float, max_translation: tuple[float, float]) -> Pose:
    """The paper's intent of inclination posing: shift the body so the gravity projection of the centre of mass
    falls on the centroid of the stance feet (walk-plane frame), clamped.

    Args:
        orientation: IMU quaternion (x, y, z, w).
        stance_tips: feet on the ground, walk-plane frame ``(k, 3)`` [m].
        com: centre of mass in base_link [m] (the body's, as an estimate).
        body_clearance: body height above the walk plane [m].
        max_translation: clamp (x, y) [m].
    """
    if len(stance_tips) == 0:
        return Pose()
    roll, pitch, _ = euler_from_matrix(quaternion_matrix(orientation))
    height = body_clearance + float(com[2])
    # Where gravity carries the CoM down to the walk plane, relative to the body origin (walk-plane axes).
    projected = np.array([float(com[0]) + height * math.tan(pitch), float(com[1]) - height * math.tan(roll)])
    centroid = stance_tips[:, :2].mean(axis=0)
    shift = centroid - projected
    return Pose(np.array([float(np.clip(shift[0], -max_translation[0], max_translation[0])),
                          float(np.clip(shift[1], -max_translation[1], max_translation[1])), 0.0]), IDENTITY)


def plane_normal(points: np.ndarray) -> np.ndarray:
    """Upward unit normal of the plane through ``points`` ``(k ≥ 3, 3)``: exact for three, least squares
    (``z = a·x + b·y + c``) for more."""
    if len(points) == 3:
        normal = np.cross(points[1] - points[0], points[2] - points[0])
    else:
        design = np.column_stack([points[:, 0], points[:, 1], np.ones(len(points))])
        (a, b, _), *_ = np.linalg.lstsq(design, points[:, 2], rcond=None)
        normal = np.array([-a, -b, 1.0])
    length = float(np.linalg.norm(normal))
    if length < 1e-12:
        return np.array([0.0, 0.0, 1.0])
    normal = normal / length
    return normal if normal[2] >= 0.0 else -normal


@dataclass
class PostureEstimate:
    """One ATHENA estimate: ground-plane normal in the body frame and the displacements (eq. 25–27)."""

    normal: np.ndarray
    pitch: float
    """``δ_α`` (eq. 25) [rad]: tilt of the ground normal towards +x."""
    roll: float
    """``δ_β`` (eq. 26) [rad]: tilt of the ground normal towards +y."""
    height: float
    """``δ_z`` [m]: measured body height minus the reference (standing) height."""
    feet: int


class PostureController:
    """ATHENA posture control (seed 003 §4.2).

    Every gait cycle: the feet in contact (force sensors) give a ground plane in the body frame (eq. 24) —
    exactly three feet: their plane; more: a seeded random three (as the paper) or, with ``plane =
    "least_squares"``, all of them; fewer: no new estimate (the paper extends the other legs until they touch;
    that belongs with step depth). From its normal ``g`` the pitch and roll displacements ``δ_α = atan2(g_x,
    g_z)``, ``δ_β = atan2(g_y, g_z)`` (eq. 25–26), and from the body-height sensor ``δ_z = h − h_ref``. The
    feet's end positions move by ``k_z·δ_z`` (eq. 27, 30) and rotate by ``k_α·δ_α``, ``k_β·δ_β`` (eq. 29): as a
    body pose, the body rises by ``−k_z·δ_z`` and tilts towards the ground plane by the scaled angles. Each
    correction adds to the last (the feet start where the previous ones left them) and is taken in linearly
    over half a gait cycle (eq. 31).

    Args:
        kz, ka, kb: gains in [0, 1].
        reference_height: the height sensor's reading in the standing posture [m]; 0 = take the first reading
            once walking starts (the robot stands at its body clearance then).
        period: gait cycle [control cycles].
        plane: ``"random_three"`` or ``"least_squares"``.
        seed: seed of the random choice of three feet.
        max_z: clamp of the accumulated height correction [m].
        max_angle: clamp of the accumulated roll and pitch correction [rad].
    """

    def __init__(self, kz: float, ka: float, kb: float, reference_height: float, period: int,
                 plane: str = "random_three", seed: int = 0, max_z: float = 0.1, max_angle: float = 0.5) -> None:
        self.kz, self.ka, self.kb = kz, ka, kb
        self.reference_height = reference_height
        self.period = max(period, 2)
        self.plane = plane
        self.rng = np.random.default_rng(seed)
        self.max_z, self.max_angle = max_z, max_angle
        self.z = self.pitch = self.roll = 0.0  # accumulated targets
        self._from = (0.0, 0.0, 0.0)
        self._blend = 1.0
        self._count = 0
        self.last: PostureEstimate | None = None
        self.pose = Pose()

    def estimate(self, feet_body: np.ndarray, contact: np.ndarray, height: float | None) -> PostureEstimate | None:
        """Ground plane and displacements from the feet in contact (body frame) and the height sensor."""
        down = np.flatnonzero(contact)
        if len(down) < 3:
            return None
        if len(down) > 3 and self.plane == "random_three":
            down = np.sort(self.rng.choice(down, size=3, replace=False))
        normal = plane_normal(feet_body[down])
        dz = 0.0 if height is None or self.reference_height <= 0.0 else height - self.reference_height
        return PostureEstimate(normal, math.atan2(normal[0], normal[2]), math.atan2(normal[1], normal[2]), dz,
                               len(down))

    def update(self, walking: bool, feet_body: np.ndarray, contact: np.ndarray | None,
               height: float | None) -> Pose:
        """Advance one control cycle; returns the posture pose of this cycle."""
        if walking and self.reference_height <= 0.0 and height is not None:
            self.reference_height = height  # the standing posture's reading, as ATHENA's reference
        if walking:
            self._count += 1
            if self._count >= self.period and contact is not None:
                self._count = 0
                estimate = self.estimate(feet_body, contact, height)
                self.last = estimate
                if estimate is not None:
                    self._from = self._current()
                    self.z = float(np.clip(self.z - self.kz * estimate.height, -self.max_z, self.max_z))
                    self.pitch = float(np.clip(self.pitch + self.ka * estimate.pitch, -self.max_angle,
                                               self.max_angle))
                    self.roll = float(np.clip(self.roll + self.kb * estimate.roll, -self.max_angle, self.max_angle))
                    self._blend = 0.0
        if self._blend < 1.0:
            self._blend = min(1.0, self._blend + 2.0 / self.period)
        z, pitch, roll = self._current()
        rotation = IDENTITY if pitch == 0.0 and roll == 0.0 else rot_y(pitch) @ rot_x(-roll)
        self.pose = Pose(np.array([0.0, 0.0, z]), rotation)
        return self.pose

    def _current(self) -> tuple[float, float, float]:
        share = self._blend
        start = self._from
        return (start[0] + share * (self.z - start[0]), start[1] + share * (self.pitch - start[1]),
                start[2] + share * (self.roll - start[2]))
