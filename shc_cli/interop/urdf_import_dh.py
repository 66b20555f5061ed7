"""A serial chain of revolute axes (lines in space) → shc's classical DH rows, exactly.

shc's leg is ``A(base) · A(θ₁ + q₁, d₁, r₁, α₁) ⋯ A(θₙ + qₙ, dₙ, rₙ, αₙ)`` with
``A = Rot_z(θ)·Trans_z(d)·Trans_x(r)·Rot_x(α)`` (docs/robot-files.md §2): frame ``k − 1``'s z axis is joint
``k``'s axis, frame 0 (the leg frame) is ``A(base)``. Any chain of revolute joints fits this form: each joint
is a line in space (a point and a direction at the zero pose), and the classical construction places frame
``k``'s x axis on the common normal of lines ``k`` and ``k + 1`` (Craig, *Introduction to Robotics*, §3.4).
The base row runs from ``base_link``'s z axis (the line through its origin) to joint 1's axis, so the
"non-DH" mounting of a URDF leg (any rpy, axes in any direction) needs nothing but the four base values. The
last row goes from joint ``n``'s axis to the tip point: ``d`` along the axis, ``r`` and ``θ`` to the point, α 0.

Each frame's z axis points along its joint's URDF axis, so a URDF joint angle equals the shc joint angle
(the servo map needs no offset or sign for it); the angle of the zero pose is held in ``θ``.

Choices where the construction is free: parallel axes take the common normal through the URDF joint's origin
(so ``d`` is that origin's height along the axis); coinciding axes keep the previous x axis; intersecting
axes take ``x = z_{k−1} × z_k``. Axes less than :data:`PARALLEL` rad from parallel are taken as parallel
(tip error below 1e-9 of the lever): nearly parallel axes put the common normal far away (``d`` grows as 1 /
angle), which :func:`chain_dh` reports instead of writing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

PARALLEL = 1e-9
"""Axes closer than this to parallel (sine of their angle) are treated as parallel [rad]."""
MAX_OFFSET = 10.0
"""Largest DH ``d`` or ``r`` written [m]: more means two axes are nearly, but not exactly, parallel."""


@dataclass(frozen=True)
class Row:
    """One DH row ``{d, theta, r, alpha}`` [m, rad, m, rad]."""

    d: float
    theta: float
    r: float
    alpha: float


@dataclass(frozen=True)
class Axis:
    """A revolute joint at the zero pose, in base_link: a point on its axis and the axis direction.

    Attributes:
        point: the URDF joint frame's origin [m], shape ``(3,)``.
        direction: unit vector of the URDF axis (positive angles turn right-handed about it), shape ``(3,)``.
    """

    point: FloatArray
    direction: FloatArray


class NearlyParallel(ValueError):
    """Two consecutive axes are so close to parallel that the DH offset would exceed :data:`MAX_OFFSET`."""

    def __init__(self, index: int, angle: float, offset: float) -> None:
        self.index, self.angle, self.offset = index, angle, offset
        super().__init__(f"axes {index} and {index + 1} are {angle:.2g} rad from parallel (DH offset {offset:.3g} m)")


def _angle(a: FloatArray, b: FloatArray, about: FloatArray) -> float:
    """Angle turning unit vector ``a`` onto ``b`` about the unit axis ``about`` (both perpendicular to it) [rad]."""
    return math.atan2(float(np.dot(np.cross(a, b), about)), float(np.dot(a, b)))


def _line_step(origin: FloatArray, x: FloatArray, z: FloatArray, axis: Axis,
               index: int) -> tuple[Row, FloatArray, FloatArray]:
    """The DH row from frame (origin, x, z) to the frame whose z is ``axis``; returns it and the new origin, x."""
    u = axis.direction
    normal = np.cross(z, u)
    sine = float(np.linalg.norm(normal))
    if sine < PARALLEL:
        offset = axis.point - origin
        d = float(np.dot(offset, z))
        across = offset - d * z
        r = float(np.linalg.norm(across))
        new_x = across / r if r > 0.0 else x
        new_origin = origin + d * z + r * new_x
    else:
        w0 = origin - axis.point
        b, dz, du = float(np.dot(z, u)), float(np.dot(z, w0)), float(np.dot(u, w0))
        denominator = 1.0 - b * b
        t = (b * du - dz) / denominator
        s = (du - b * dz) / denominator
        foot, new_origin = origin + t * z, axis.point + s * u
        new_x = normal / sine
        gap = float(np.dot(new_origin - foot, new_x))
        if gap < 0.0:
            new_x, gap = -new_x, -gap
        d, r = t, gap
        if max(abs(d), abs(r)) > MAX_OFFSET:
            raise NearlyParallel(index, math.asin(min(sine, 1.0)), max(abs(d), abs(r)))
        new_origin = foot + r * new_x
    theta = _angle(x, new_x, z)
    alpha = math.atan2(float(np.dot(np.cross(z, u), new_x)), float(np.dot(z, u)))
    return Row(d, theta, r, alpha), new_origin, new_x


def chain_dh(axes: list[Axis], tip: FloatArray) -> tuple[Row, list[Row]]:
    """The base row and one row per joint of a chain given at its zero pose in base_link.

    Args:
        axes: the revolute joints, body to tip (at least one).
        tip: the tip position at the zero pose in base_link [m], shape ``(3,)``.

    Returns:
        ``(base, joints)``: ``A(base)·A(θ₁ + q₁, …)⋯`` moves the tip exactly as the URDF chain does for the same
        joint angles.

    Raises:
        NearlyParallel: two consecutive axes (or base_link's z and the first axis) are nearly but not exactly
            parallel, which needs a DH offset beyond :data:`MAX_OFFSET`.
    """
    origin, x, z = np.zeros(3), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, 1.0])
    rows = []
    for index, axis in enumerate(axes):
        row, origin, x = _line_step(origin, x, z, axis, index)
        rows.append(row)
        z = axis.direction
    offset = tip - origin
    d = float(np.dot(offset, z))
    across = offset - d * z
    r = float(np.linalg.norm(across))
    theta = _angle(x, across / r, z) if r > 0.0 else 0.0
    rows.append(Row(d, theta, r, 0.0))
    return rows[0], rows[1:]
