"""The leg odometry's per-cycle arithmetic compiled with numba (:mod:`shc_cli.control.odometry`).

One call a control cycle does what :class:`~shc_cli.control.odometry.LegOdometry` describes: the feet levelled by
roll and pitch, the (weighted) 2-D Kabsch fit of the stance feet, the yaw filter (with its gyro-bias state) and the
composition
of the pose — the same formulas as :func:`~shc_cli.control.odometry.level` and
:func:`~shc_cli.control.odometry.rigid_increment`, summed element by element from the first foot (the order of
:func:`~shc_cli.control.odometry._increment_of_lists`). The levelling is written out instead of NumPy's matrix
product, so a levelled foot may differ from :func:`level`'s in its last bit (tests/test_odometry.py compares them to
1e-12 m); the Python and NumPy forms stay in :mod:`shc_cli.control.odometry` as the reference.
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.model.jit import njit

X, Y, YAW, LEG_YAW, IMU_YAW, CONTACT_BEFORE, LAST_DX, LAST_DY, LAST_TURN, HELD, REFERENCE, BIAS, RATE = range(13)
"""Indices of the odometry's state vector: pose x, y [m], yaw [rad], the legs' own heading [rad], the IMU's last
heading [rad] (NaN before the first orientation), whether the last cycle measured foot contact (1.0) or not, the
last increment measured by standing feet (dx, dy [m] in the level frame, the legs' turn [rad]) and the cycles it
has been held since; the yaw filter's reference heading [rad], its estimate of the IMU's yaw-rate bias [rad/s] and
the smoothed bias-corrected IMU yaw rate [rad/s] that tells turning from steady."""


@njit(cache=True)
def odometry_cycle(feet: np.ndarray, orientation: np.ndarray, has_orientation: bool, roll: float, pitch: float,
                   before: np.ndarray, after: np.ndarray, use: np.ndarray, contact: np.ndarray,
                   contact_before: np.ndarray, has_contact: bool, forces: np.ndarray, weighted: bool,
                   has_before: bool, turn: float, gain: float, hold: int, bias_gain: float, rate_gain: float,
                   steady_rate: float, dt: float, commanded_rate: float,
                   state: np.ndarray) -> int:  # pragma: no cover
    """Advance the odometry ``state`` one cycle; returns the stance feet used.

    Args:
        feet: every foot in base_link ``(L, 3)`` [m], now.
        orientation: the IMU's orientation quaternion (x, y, z, w), read when ``has_orientation``: it gives the
            roll and pitch (as :func:`shc_cli.control.sensing.quaternion_roll_pitch`) and the heading change since
            the last one (as :func:`shc_cli.control.odometry.quaternion_yaw`, wrapped to ±π).
        roll, pitch: the body's roll and pitch [rad] without an orientation (levels ``feet`` into ``after``:
            ``Ry(pitch)·Rx(roll)``).
        before: the levelled feet of the last cycle ``(L, 3)`` [m] (read when ``has_before``).
        after: out, the levelled feet ``(L, 3)`` [m].
        use: feet that stood on the ground since the last cycle ``(L,)``; with ``has_contact`` only those also
            touching now (``contact``) and at the last reading (``contact_before``, then set to ``contact``).
        forces: measured normal foot forces ``(L,)`` [N] (negative ones count as 0), read when ``weighted``.
        turn: the heading change over the cycle from the IMU's rates [rad] without an orientation, else NaN.
        gain: the yaw filter's heading gain ``dt/τ``.
        hold: cycles the last measured increment is repeated while feet stand by the gait (``use``) but none
            touches at both readings and no other foot touches now (a contact dropout), before the pose holds
            still.
        bias_gain: the yaw filter's bias gain ``dt/τ_b``.
        rate_gain: the smoothing gain ``dt/τ_r`` of the IMU's yaw rate that tells turning from steady.
        steady_rate: the smoothed yaw rate [rad/s] up to which the legs' turn is trusted (steady, not turning).
        dt: the control period [s].
        commanded_rate: the yaw rate the gait is walking at (the walker's desired one) [rad/s]; above
            ``steady_rate`` the body is turning.
        state: ``(13,)`` (:data:`X` … :data:`RATE`); updated in place.
    """
    if has_orientation:
        x, y, z, w = orientation[0], orientation[1], orientation[2], orientation[3]
        r20 = 2 * (x * z - y * w)
        roll = math.atan2(2 * (y * z + x * w), 1 - 2 * (x * x + y * y))
        pitch = math.asin(-min(max(r20, -1.0), 1.0)) if not math.isnan(r20) else r20
        yaw = math.atan2(2 * (x * y + z * w), 1 - 2 * (y * y + z * z))
        turn = math.nan
        if not math.isnan(state[IMU_YAW]):  # the IMU's own heading change (integrated at its rate, not ours)
            change = yaw - state[IMU_YAW]
            turn = change - 2.0 * math.pi * np.rint(change / (2.0 * math.pi))
        state[IMU_YAW] = yaw
    cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
    legs = feet.shape[0]
    for i in range(legs):
        fx, fy, fz = feet[i, 0], feet[i, 1], feet[i, 2]
        after[i, 0] = cp * fx + sp * sr * fy + sp * cr * fz
        after[i, 1] = cr * fy - sr * fz
        after[i, 2] = -sp * fx + cp * sr * fy + cp * cr * fz
    dx = dy = legs_turn = 0.0
    used = 0
    masked = has_contact and state[CONTACT_BEFORE] == 1.0
    chosen = np.empty(legs, dtype=np.bool_)
    for i in range(legs):
        chosen[i] = use[i] and (not masked or (contact[i] and contact_before[i]))
    if has_contact:
        for i in range(legs):
            contact_before[i] = contact[i]
        state[CONTACT_BEFORE] = 1.0
    if has_before:
        total = 0.0
        for i in range(legs):
            if chosen[i]:
                used += 1
                if weighted and forces[i] > 0.0:
                    total += forces[i]
        if used > 0:
            loaded = weighted and total > 0.0
            px = py = qx = qy = 0.0
            for i in range(legs):
                if chosen[i]:
                    w = (forces[i] / total if forces[i] > 0.0 else 0.0) if loaded else 1.0
                    px += w * before[i, 0]
                    py += w * before[i, 1]
                    qx += w * after[i, 0]
                    qy += w * after[i, 1]
            if not loaded:
                px, py, qx, qy = px / used, py / used, qx / used, qy / used
            if used > 1:
                cross = dot = 0.0
                for i in range(legs):
                    if chosen[i]:
                        w = (forces[i] / total if forces[i] > 0.0 else 0.0) if loaded else 1.0
                        bx, by = before[i, 0] - px, before[i, 1] - py
                        ax, ay = after[i, 0] - qx, after[i, 1] - qy
                        cross += w * (ax * by - ay * bx)
                        dot += w * (ax * bx + ay * by)
                legs_turn = math.atan2(cross, dot)
            c, s = math.cos(legs_turn), math.sin(legs_turn)
            dx, dy = px - (c * qx - s * qy), py - (s * qx + c * qy)
            state[LAST_DX], state[LAST_DY], state[LAST_TURN], state[HELD] = dx, dy, legs_turn, 0.0
        elif state[HELD] < hold:  # a contact dropout: the body keeps its last measured motion
            standing = dragging = False
            for i in range(legs):
                standing = standing or use[i]
                dragging = dragging or (has_contact and contact[i] and not use[i])
            if standing and not dragging:  # not when a swinging foot touches: the body may rest or drag on it
                # the turn only without an IMU: with one, the IMU measures the turn through the dropout, and the
                # legs' heading (the slow reference that bounds the IMU's drift) takes no turn it did not measure
                dx, dy = state[LAST_DX], state[LAST_DY]
                legs_turn = state[LAST_TURN] if math.isnan(turn) else 0.0
                state[HELD] += 1.0
    state[LEG_YAW] += legs_turn
    heading = state[YAW]
    if math.isnan(turn):
        state[YAW] += legs_turn
        state[REFERENCE] += legs_turn
    else:  # the yaw filter with a bias state: the legs' turn is trusted only while the body does not turn
        corrected = turn - state[BIAS] * dt
        state[RATE] += rate_gain * (corrected / dt - state[RATE])
        if abs(state[RATE]) <= steady_rate and abs(commanded_rate) <= steady_rate:
            # steady (neither the gait nor the gyro turns): the legs' turn (none when no foot is fitted)
            state[REFERENCE] += legs_turn
            if used > 1:
                state[BIAS] += bias_gain * ((turn - legs_turn) / dt - state[BIAS])
        else:  # turning: the gyro's
            state[REFERENCE] += corrected
        predicted = state[YAW] + corrected
        state[YAW] = predicted + gain * (state[REFERENCE] - predicted)
    c, s = math.cos(heading), math.sin(heading)  # the increment is in the level frame at the cycle's start
    state[X] += c * dx - s * dy
    state[Y] += s * dx + c * dy
    return used
