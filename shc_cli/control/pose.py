"""Body posing: walk-plane alignment and manual 6-DOF posing, composed as OpenSHC does (study §7).

The body pose (``walk_plane → base_link``) is ``walk_plane ∘ manual ∘ (posture) ∘ (inclination) ∘ (imu or
auto)``; the sensor-driven terms come from :mod:`shc_cli.control.sensing`. The tip
pose generator then expresses every walker tip in base_link under that pose (:meth:`PoseController.posed_tips`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np

from shc_cli.control.bezier import smooth_step

Vector = np.ndarray


def rot_x(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def euler_from_matrix(rotation: np.ndarray) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of ``R = Rz(yaw)·Ry(pitch)·Rx(roll)`` [rad]."""
    pitch = float(np.arcsin(-np.clip(rotation[2, 0], -1.0, 1.0)))
    roll = float(np.arctan2(rotation[2, 1], rotation[2, 2]))
    yaw = float(np.arctan2(rotation[1, 0], rotation[0, 0]))
    return roll, pitch, yaw


IDENTITY = np.eye(3)
IDENTITY.flags.writeable = False
"""The identity rotation; poses share this object so composition can skip exact no-op products."""


def rotation_between(a: Vector, b: Vector) -> np.ndarray:
    """Smallest rotation taking direction ``a`` to direction ``b`` (Eigen ``FromTwoVectors``)."""
    if a[0] == b[0] and a[1] == b[1] and a[2] == b[2]:
        return IDENTITY
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    axis = np.cross(a, b)
    sine = float(np.linalg.norm(axis))
    cosine = float(np.dot(a, b))
    if sine < 1e-12:
        return IDENTITY if cosine > 0 else np.diag([1.0, -1.0, -1.0])
    k = axis / sine
    skew = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.asarray(np.eye(3) + sine * skew + (1.0 - cosine) * (skew @ skew))


@dataclass
class Pose:
    """A rigid transform: ``x ↦ position + rotation·x``."""

    position: Vector = field(default_factory=lambda: np.zeros(3))
    rotation: np.ndarray = field(default_factory=lambda: IDENTITY)

    def add(self, other: Pose) -> Pose:
        """``self ∘ other`` (OpenSHC ``addPose``); products with the identity rotation are skipped (exact)."""
        if self.rotation is IDENTITY:
            return Pose(self.position + other.position, other.rotation)
        rotation = self.rotation if other.rotation is IDENTITY else self.rotation @ other.rotation
        return Pose(self.position + self.rotation @ other.position, rotation)

    def remove(self, other: Pose) -> Pose:
        """OpenSHC ``removePose``: ``(p + R·(−p_o), R·R_o⁻¹)``."""
        return Pose(self.position + self.rotation @ (-other.position), self.rotation @ other.rotation.T)

    def inverse_transform(self, vectors: np.ndarray) -> np.ndarray:
        """``R⁻¹(v − p)`` for vectors ``(..., 3)``, evaluated as OpenSHC does: ``R⁻¹(−p) + R⁻¹v``."""
        if self.rotation is IDENTITY:  # v − p is v + (−p) in IEEE arithmetic: the same bits, one array less
            return np.asarray(vectors - self.position)
        inverse = self.rotation.T
        return np.asarray(inverse @ (-self.position) + vectors @ self.rotation)

    def interpolate(self, share: float, target: Pose) -> Pose:
        """Positions blended linearly, rotations along the geodesic (slerp)."""
        if share == 0.0:
            return Pose(self.position, self.rotation)  # = 0·p_target + 1·p exactly
        position = share * target.position + (1.0 - share) * self.position
        if self.rotation is IDENTITY and target.rotation is IDENTITY:
            return Pose(position, IDENTITY)
        relative = self.rotation.T @ target.rotation
        angle = float(np.arccos(np.clip((np.trace(relative) - 1.0) / 2.0, -1.0, 1.0)))
        if angle < 1e-12:
            rotation = self.rotation if share < 1.0 else target.rotation
        else:
            axis = np.array([relative[2, 1] - relative[1, 2], relative[0, 2] - relative[2, 0],
                             relative[1, 0] - relative[0, 1]]) / (2.0 * np.sin(angle))
            rotation = self.rotation @ rotation_between_axis(axis, share * angle)
        return Pose(position, rotation)

    def euler(self) -> tuple[float, float, float]:
        """(roll, pitch, yaw) [rad] of the extrinsic ``Rz·Ry·Rx`` decomposition."""
        return (0.0, 0.0, 0.0) if self.rotation is IDENTITY else euler_from_matrix(self.rotation)


def rotation_between_axis(axis: Vector, angle: float) -> np.ndarray:
    """Rotation of ``angle`` [rad] about unit ``axis`` (Rodrigues)."""
    skew = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    return np.asarray(np.eye(3) + np.sin(angle) * skew + (1.0 - np.cos(angle)) * (skew @ skew))


class PoseReset(IntEnum):
    """Manual pose reset modes (OpenSHC ``PoseResetMode``)."""

    NO_RESET = 0
    Z_AND_YAW = 1
    X_AND_Y = 2
    PITCH_AND_ROLL = 3
    ALL = 4
    IMMEDIATE_ALL = 5


RESET_AXES = {
    PoseReset.NO_RESET: (),
    PoseReset.Z_AND_YAW: (2, 5),
    PoseReset.X_AND_Y: (0, 1),
    PoseReset.PITCH_AND_ROLL: (3, 4),
    PoseReset.ALL: (0, 1, 2, 3, 4, 5),
    PoseReset.IMMEDIATE_ALL: (0, 1, 2, 3, 4, 5),
}


class PoseController:
    """Body pose of every cycle (OpenSHC ``PoseController``, manual and walk-plane terms).

    Args:
        body_clearance: body height above the walk plane [m].
        max_translation: manual translation limits (x, y, z) [m].
        max_rotation: manual rotation limits (roll, pitch, yaw) [rad].
        max_translation_velocity: translation speed at input 1 [m/s].
        max_rotation_velocity: rotation speed at input 1 [rad/s].
        time_delta: control period [s].
        manual: whether manual posing is enabled.
    """

    def __init__(self, body_clearance: float, max_translation: Vector, max_rotation: Vector,
                 max_translation_velocity: float, max_rotation_velocity: float, time_delta: float,
                 manual: bool = True) -> None:
        self.body_clearance = body_clearance
        self.limits = np.concatenate([max_translation, max_rotation])
        self.speeds = np.array([max_translation_velocity] * 3 + [max_rotation_velocity] * 3)
        self.time_delta = time_delta
        self.manual_enabled = manual
        self.manual = np.zeros(6)  # x, y, z [m], roll, pitch, yaw [rad] (intrinsic order)
        self.walk_plane_origin = Pose(np.array([0.0, 0.0, body_clearance]), IDENTITY)
        self.walk_plane_pose = Pose(np.array([0.0, 0.0, body_clearance]), IDENTITY)
        self.current = Pose()

    def manual_pose(self) -> Pose:
        """The manual posing term: translation and intrinsic roll–pitch–yaw rotation."""
        x, y, z, roll, pitch, yaw = self.manual
        if roll == 0.0 and pitch == 0.0 and yaw == 0.0:
            return Pose(np.array([x, y, z]), IDENTITY)
        return Pose(np.array([x, y, z]), rot_x(roll) @ rot_y(pitch) @ rot_z(yaw))

    def update_manual(self, velocity_input: Vector | tuple[float, ...], reset: PoseReset) -> None:
        """Integrate manual posing inputs (−1..1 per axis), stopping exactly on the limits (study §7.2)."""
        if reset == 0 and not any(velocity_input):  # 0 = PoseReset.NO_RESET; nothing to integrate
            return
        inputs = np.clip(np.asarray(velocity_input, dtype=float), -1.0, 1.0)
        if reset == PoseReset.IMMEDIATE_ALL:
            self.manual = np.zeros(6)
            return
        for axis in RESET_AXES[reset]:
            inputs[axis] = 0.0 if self.manual[axis] == 0.0 else -np.sign(self.manual[axis])
        for axis in range(6):
            change = inputs[axis] * self.speeds[axis] * self.time_delta
            value = self.manual[axis] + change
            limit = self.limits[axis]
            if axis in RESET_AXES[reset] and self.manual[axis] != 0.0 and np.sign(value) != np.sign(self.manual[axis]):
                value = 0.0  # a reset stops exactly on the default pose
            self.manual[axis] = min(max(value, -limit), limit)

    def update_walk_plane_pose(self, swing_progress: np.ndarray, swing_phase: int, phase_offset: int,
                               planes: np.ndarray, normals: np.ndarray) -> None:
        """Align the body with the walk plane during swings (study §7.6); flat ground keeps it at rest."""
        scaler = max(1.0, swing_phase / phase_offset) if phase_offset else 1.0
        last, share = -1, 0.0
        progresses = np.asarray(swing_progress).tolist()
        for leg in range(len(progresses) - 1, -1, -1):  # the last swinging leg in id order wins, as in OpenSHC
            scaled = progresses[leg] * scaler
            if 0.0 <= scaled <= 1.0:
                last, share = leg, smooth_step(scaled)
                break
        if last < 0:  # no leg swinging: share 0 keeps the origin exactly
            self.walk_plane_pose = self.walk_plane_origin.interpolate(0.0, self.walk_plane_origin)
            return
        plane, normal = planes[last], normals[last]
        origin = self.walk_plane_origin
        if normal[0] == 0.0 and normal[1] == 0.0 and normal[2] == 1.0 and origin.rotation is IDENTITY:
            # Level plane: the same arithmetic as the general case, on floats (the common, hot case).
            target_z = (0.0 + self.body_clearance) + float(plane[2])
            ox, oy, oz = origin.position.tolist()
            rest = 1.0 - share
            position = np.array([share * 0.0 + rest * ox, share * 0.0 + rest * oy, share * target_z + rest * oz])
            self.walk_plane_pose = Pose(position, IDENTITY)
            if share == 1.0:
                self.walk_plane_origin = self.walk_plane_pose
            return
        rotation = rotation_between(np.array([0.0, 0.0, 1.0]), normal)
        height = np.array([0.0, 0.0, self.body_clearance])
        lift = rotation @ height if rotation is not IDENTITY else height
        target = Pose(lift + np.array([0.0, 0.0, plane[2]]), rotation)
        self.walk_plane_pose = self.walk_plane_origin.interpolate(share, target)
        if share == 1.0:
            self.walk_plane_origin = self.walk_plane_pose

    def update_current_pose(self, swing_progress: np.ndarray, swing_phase: int, phase_offset: int,
                            planes: np.ndarray, normals: np.ndarray, auto: Pose | None = None,
                            feedback: tuple[Pose | None, ...] = ()) -> Pose:
        """Compose this cycle's body pose: walk plane ∘ manual ∘ feedback terms ∘ auto (study §7.1).

        ``feedback``: the sensor-driven terms in order (ATHENA posture, inclination); ``auto`` is the IMU pose
        instead of the auto pose while IMU posing runs (OpenSHC ignores auto posing then).
        """
        self.update_walk_plane_pose(swing_progress, swing_phase, phase_offset, planes, normals)
        pose = self.walk_plane_pose  # = Identity ∘ walk-plane pose, exactly
        if self.manual_enabled and any(self.manual.tolist()):  # adding a zero manual pose changes nothing
            pose = pose.add(self.manual_pose())
        for term in feedback:
            if term is not None:
                pose = pose.add(term)
        if auto is not None:
            pose = pose.add(auto)
        self.current = pose
        return pose

    def posed_tips(self, walker_tips: np.ndarray, auto: Pose | None = None,
                   leg_autos: list[Pose] | None = None) -> np.ndarray:
        """Walker tips (walk-plane frame) in base_link under the current body pose (OpenSHC ``updateStance``).

        With auto posing, each leg sees ``body.remove(auto).add(leg_auto)`` so a negated leg ignores it.
        """
        if auto is None or leg_autos is None:
            return self.current.inverse_transform(walker_tips)
        body = self.current.remove(auto)
        return np.array([body.add(leg).inverse_transform(tip) for tip, leg in zip(walker_tips, leg_autos, strict=True)])
