"""DH chains of many legs at once: forward kinematics and position Jacobians (paper eq. 1–8).

All legs of a robot are held as arrays of shape ``(B, n)`` where ``B`` is the number of chains
(legs, or legs × search directions) and ``n`` the largest joint count. Shorter legs are padded
with fixed dummy joints (all DH values 0, range 0) placed after the tip: they add an identity
transform, a zero Jacobian column and nothing to the limit-avoidance sums, so padded results are
identical to unpadded ones. Frames follow OpenSHC (study §1.3): the leg frame is
``A(base)``, joint ``k`` rotates about the z axis of frame ``k − 1``, the tip is the last frame.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from shc_cli.spec.robot import DH, Robot

FloatArray = NDArray[np.float64]


def dh_matrix(d: FloatArray, theta: FloatArray, r: FloatArray, alpha: FloatArray) -> FloatArray:
    """Classical DH transforms ``Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)`` for arrays of links.

    Args:
        d: offsets along z [m], any shape ``S``.
        theta: angles about z [rad], shape ``S``.
        r: lengths along x [m], shape ``S``.
        alpha: twists about x [rad], shape ``S``.

    Returns:
        Homogeneous transforms, shape ``S + (4, 4)``.
    """
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    out = np.zeros((*np.shape(theta), 4, 4))
    out[..., 0, 0] = ct
    out[..., 0, 1] = -st * ca
    out[..., 0, 2] = st * sa
    out[..., 0, 3] = r * ct
    out[..., 1, 0] = st
    out[..., 1, 1] = ct * ca
    out[..., 1, 2] = -ct * sa
    out[..., 1, 3] = r * st
    out[..., 2, 1] = sa
    out[..., 2, 2] = ca
    out[..., 2, 3] = d
    out[..., 3, 3] = 1.0
    return out


def joint_slots(robot: Robot) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Rows (legs) and columns (joints) of every real joint in the padded ``(L, n)`` arrays, legs in id order and
    joints body to tip — the servo and ``log.csv`` column order: ``padded[rows, cols]`` lists the real joints."""
    pairs = [(i, k) for i, leg in enumerate(robot.legs.values()) for k in range(len(leg.joints))]
    return (np.array([i for i, _ in pairs], dtype=np.intp), np.array([k for _, k in pairs], dtype=np.intp))


@dataclass(frozen=True)
class JointSlots:
    """Where each real joint (servo order, :func:`joint_slots`) sits in the padded ``(L, n)`` arrays.

    Attributes:
        rows: each joint's leg.
        cols: each joint's index within its leg.
        legs: ``L``.
        width: ``n``, the most joints of a leg.
    """

    rows: NDArray[np.intp]
    cols: NDArray[np.intp]
    legs: int
    width: int

    @classmethod
    def of(cls, robot: Robot) -> JointSlots:
        rows, cols = joint_slots(robot)
        return cls(rows, cols, len(robot.legs), max(len(leg.joints) for leg in robot.legs.values()))

    def padded(self, values: NDArray[np.float64]) -> FloatArray:
        """Per-joint values (servo order) as a new padded ``(L, n)`` array, 0 where a leg has fewer joints."""
        if self.dense:
            return np.array(values, dtype=float).reshape(self.legs, self.width)
        out = np.zeros((self.legs, self.width))
        out[self.rows, self.cols] = values
        return out

    @property
    def dense(self) -> bool:
        """Every leg has ``n`` joints: the padded arrays hold no padding, servo order is their C order."""
        return len(self.rows) == self.legs * self.width

    def servo_order(self, values: NDArray[np.float64]) -> FloatArray:
        """The real joints of a padded ``(L, n)`` array in servo order ``(J,)``, as ``values[rows, cols]``: without
        padding (:attr:`dense`) a view of ``values`` (or a copy if it is not contiguous), else a new array."""
        if self.dense:
            return values.reshape(-1)
        flat: FloatArray = values[self.rows, self.cols]
        return flat


def _kernels() -> Any:
    """The numba kernels, imported on first use: numpy-only users of chains (run readers, exporters) stay light."""
    from shc_cli.model import kernels

    return kernels


def _base_matrix(base: DH) -> FloatArray:
    return dh_matrix(np.array(base.d), np.array(base.theta), np.array(base.r), np.array(base.alpha))


@dataclass(frozen=True)
class Chains:
    """DH parameters and joint limits of ``B`` legs, padded to ``n`` joints.

    Attributes:
        names: leg id of each chain.
        base: transform base_link → leg frame, ``(B, 4, 4)``.
        d, theta, r, alpha: DH values of the link each joint moves, ``(B, n)`` [m, rad].
        lower, upper: joint position limits, ``(B, n)`` [rad].
        max_vel: joint speed limits, ``(B, n)`` [rad/s].
        joint_count: real joints per chain, ``(B,)``.
    """

    names: tuple[str, ...]
    base: FloatArray
    d: FloatArray
    theta: FloatArray
    r: FloatArray
    alpha: FloatArray
    lower: FloatArray
    upper: FloatArray
    max_vel: FloatArray
    joint_count: NDArray[np.int64]

    @classmethod
    def from_robot(cls, robot: Robot) -> Chains:
        """Chains of every leg of ``robot`` in id order."""
        n = max(len(leg.joints) for leg in robot.legs.values())
        b = len(robot.legs)
        arrays = {key: np.zeros((b, n)) for key in ("d", "theta", "r", "alpha", "lower", "upper")}
        max_vel = np.ones((b, n))
        for i, leg in enumerate(robot.legs.values()):
            for k, joint in enumerate(leg.joints.values()):
                arrays["d"][i, k], arrays["theta"][i, k] = joint.d, joint.theta
                arrays["r"][i, k], arrays["alpha"][i, k] = joint.r, joint.alpha
                arrays["lower"][i, k], arrays["upper"][i, k] = joint.min, joint.max
                max_vel[i, k] = joint.max_vel
        base = np.stack([_base_matrix(leg.base) for leg in robot.legs.values()])
        counts = np.array([len(leg.joints) for leg in robot.legs.values()], dtype=np.int64)
        return cls(tuple(robot.legs), base, max_vel=max_vel, joint_count=counts, **arrays)

    @property
    def size(self) -> int:
        return len(self.names)

    @property
    def joints(self) -> int:
        return int(self.d.shape[1])

    def take(self, index: NDArray[np.int64]) -> Chains:
        """Chains selected (or repeated) by ``index``."""
        return replace(
            self,
            names=tuple(self.names[i] for i in index),
            **{k: getattr(self, k)[index] for k in
               ("base", "d", "theta", "r", "alpha", "lower", "upper", "max_vel", "joint_count")},
        )

    def default_joints(self) -> FloatArray:
        """OpenSHC's initial joint positions ``clamp(0, min, max)``, ``(B, n)`` [rad]."""
        return np.clip(np.zeros_like(self.lower), self.lower, self.upper)

    def frames(self, q: FloatArray) -> FloatArray:
        """Frames of every joint and the tip in the leg frame, ``(B, n + 1, 4, 4)``.

        Frame 0 is the leg frame itself (identity), frame ``k`` is ``A_1 ⋯ A_k``; frame ``n`` is the tip.
        """
        links = dh_matrix(self.d, self.theta + q, self.r, self.alpha)
        out = np.empty((self.size, self.joints + 1, 4, 4))
        out[:, 0] = np.eye(4)
        for k in range(self.joints):
            np.matmul(out[:, k], links[:, k], out=out[:, k + 1])
        return out

    def frames_in_base(self, q: FloatArray) -> FloatArray:
        """Frames of every joint and the tip in base_link for many configurations at once (numpy only):
        joints ``(N, B, n)`` → ``(N, B, n + 1, 4, 4)``."""
        count = q.shape[0]
        frames = self.take(np.tile(np.arange(self.size), count)).frames(q.reshape(count * self.size, -1))
        return np.asarray(np.matmul(self.base[None, :, None], frames.reshape(count, self.size, self.joints + 1, 4, 4)))

    def tips(self, q: FloatArray) -> FloatArray:
        """Tip positions in base_link, ``(B, 3)`` [m]."""
        out = np.empty((self.size, 3))
        _kernels().tips_kernel(self.base, self.d, self.theta, self.r, self.alpha,
                            np.ascontiguousarray(q, dtype=float), out)
        return out

    def jacobians(self, q: FloatArray) -> FloatArray:
        """Linear-velocity Jacobians in each leg frame, ``(B, 3, n)`` (paper eq. 7–8)."""
        frames = self.frames(q)
        out = np.empty((self.size, 3, self.joints))
        for b in range(self.size):
            _kernels().position_jacobian(frames[b], out[b])
        return out

    def tip_transforms(self, q: FloatArray) -> FloatArray:
        """Tip poses in base_link as homogeneous transforms, ``(B, 4, 4)``."""
        return np.asarray(np.matmul(self.base, self.frames(q)[:, -1]), dtype=np.float64)
