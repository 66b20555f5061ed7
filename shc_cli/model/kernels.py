"""Compiled inner loops of the kinematics: FK and one OpenSHC IK step, per chain.

These are plain Python loops compiled by numba (``cache=True``: compiled once per machine, then
loaded in milliseconds). They run every control cycle and thousands of times in a workspace
search, where NumPy's per-call overhead on small arrays would dominate. Set ``NUMBA_DISABLE_JIT=1``
to step through them as ordinary Python. Arrays are ``(B, n)`` over chains ``B`` and joints ``n``.
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.model.jit import njit

DLS_COEFFICIENT = 0.02
JOINT_LIMIT_COST_WEIGHT = 0.1
POSITION_LIMIT_SHARE = 0.25
CAPPED_TIP_SPEED = 0.05
"""Tip speed [m/s] at and above which ``avoidance_cap`` leaves OpenSHC's velocity term whole (below, it blends
to the capped term of a still tip)."""
IK_TOLERANCE = 0.005


@njit(cache=True)
def chain_frames(base, d, theta, r, alpha, q, out):  # type: ignore[no-untyped-def]
    """Fill ``out[k]`` (``(n+1, 4, 4)``) with the frame of joint k+1 in the leg frame; ``out[n]`` = tip.

    ``base`` is unused here (frames are in the leg frame) but kept for a uniform signature.
    """
    n = d.shape[0]
    for i in range(4):
        for j in range(4):
            out[0, i, j] = 1.0 if i == j else 0.0
    for k in range(n):
        # The DH transform of :func:`shc_cli.model.chains.dh_matrix`, written out: a compiled kernel cannot call the
        # batched numpy function, and this is the controller's hot path (test_compiled_tips_equal_numpy_frames
        # checks the two equal). Its top three rows are held in locals (a 4×4 array allocated per call cost a
        # third of the time); its bottom row is (0, 0, 0, 1).
        ct = math.cos(theta[k] + q[k])
        st = math.sin(theta[k] + q[k])
        ca = math.cos(alpha[k])
        sa = math.sin(alpha[k])
        l00, l01, l02, l03 = ct, -st * ca, st * sa, r[k] * ct
        l10, l11, l12, l13 = st, ct * ca, -ct * sa, r[k] * st
        l20, l21, l22, l23 = 0.0, sa, ca, d[k]
        # Homogeneous product; the bottom rows are (0, 0, 0, 1), so only the top 3 rows are computed and the
        # summation stops where the remaining factors are exact zeros (same values as the full product).
        for i in range(3):
            a0, a1, a2 = out[k, i, 0], out[k, i, 1], out[k, i, 2]
            out[k + 1, i, 0] = a0 * l00 + a1 * l10 + a2 * l20
            out[k + 1, i, 1] = a0 * l01 + a1 * l11 + a2 * l21
            out[k + 1, i, 2] = a0 * l02 + a1 * l12 + a2 * l22
            out[k + 1, i, 3] = a0 * l03 + a1 * l13 + a2 * l23 + out[k, i, 3]
        out[k + 1, 3, 0] = 0.0
        out[k + 1, 3, 1] = 0.0
        out[k + 1, 3, 2] = 0.0
        out[k + 1, 3, 3] = 1.0
    return out


@njit(cache=True)
def position_jacobian(frames, jac):  # type: ignore[no-untyped-def]
    """Linear Jacobian in the leg frame (``(3, n)``): column k = z_k × (p_tip − o_k) (paper eq. 7–8)."""
    n = jac.shape[1]
    px, py, pz = frames[n, 0, 3], frames[n, 1, 3], frames[n, 2, 3]
    for k in range(n):
        zx, zy, zz = frames[k, 0, 2], frames[k, 1, 2], frames[k, 2, 2]
        ex = px - frames[k, 0, 3]
        ey = py - frames[k, 1, 3]
        ez = pz - frames[k, 2, 3]
        jac[0, k] = zy * ez - zz * ey
        jac[1, k] = zz * ex - zx * ez
        jac[2, k] = zx * ey - zy * ex
    return jac


@njit(cache=True)
def tip_kernel_one(base, d, theta, r, alpha, q, frames, tip):  # type: ignore[no-untyped-def]
    """Tip position of one chain in base_link into ``tip`` (3,), using ``frames`` as scratch."""
    n = d.shape[0]
    chain_frames(base, d, theta, r, alpha, q, frames)
    for i in range(3):
        acc = 0.0
        for m in range(3):
            acc += base[i, m] * frames[n, m, 3]
        tip[i] = acc + base[i, 3]
    return tip


@njit(cache=True)
def tips_kernel(base, d, theta, r, alpha, q, tips):  # type: ignore[no-untyped-def]
    """Tip positions in base_link for every chain, written into ``tips`` ``(B, 3)``."""
    chains, n = d.shape
    frames = np.empty((n + 1, 4, 4))
    for b in range(chains):
        chain_frames(base[b], d[b], theta[b], r[b], alpha[b], q[b], frames)
        for i in range(3):
            acc = 0.0
            for m in range(3):
                acc += base[b, i, m] * frames[n, m, 3]
            tips[b, i] = acc + base[b, i, 3]
    return tips


@njit(cache=True)
def ik_step_one(  # type: ignore[no-untyped-def]
    base, d, theta, r, alpha, lower, upper, max_vel,
    q, qd, current_tip, desired_tip, dt, clamp_positions, clamp_velocities,
    q_out, qd_out, tip_out, frames, jac, z, v, delta, null_space=1.0, frames_ready=False, avoidance_cap=0.0,
    target_motion=0.0,
):
    """One DLS step with joint-limit avoidance for one chain (study §2.1–§2.2).

    Returns ``(flags, proximity)``: flags bit 0 = tip within tolerance, bit 1 = a position was clamped,
    bit 2 = a velocity was clamped; proximity ρ ∈ [0, 1] as OpenSHC's ``updateJointPositions``.
    ``frames`` ``(n + 1, 4, 4)``, ``jac`` ``(3, n)``, ``z`` ``(n, 3)``, ``v`` ``(n,)`` and ``delta`` ``(3,)`` are
    scratch space (allocated once per batch by the callers). ``null_space`` scales the limit-avoidance
    motion: 1 is OpenSHC; 0 gives a plain damped-least-squares step (used to polish planning solutions).
    ``frames_ready``: ``frames`` already holds the frames of ``q`` (:func:`ik_step_frames_kernel`). On return
    ``frames`` holds the frames of ``q_out``. ``avoidance_cap``: 0 is OpenSHC; c > 0 shortens the two limit-avoidance
    terms to at most c times what they correct (see below); ``target_motion`` is how far the tip's target moved since
    the last step [m] (0: a still target, as the planning callers pass).
    """
    n = d.shape[0]
    w = JOINT_LIMIT_COST_WEIGHT
    lam2 = DLS_COEFFICIENT * DLS_COEFFICIENT
    if not frames_ready:
        chain_frames(base, d, theta, r, alpha, q, frames)
    # Tip displacement in the leg frame: T_leg⁻¹·p_des − T_leg⁻¹·p_cur.
    for i in range(3):
        des = 0.0
        cur = 0.0
        for m in range(3):
            des += base[m, i] * (desired_tip[m] - base[m, 3])
            cur += base[m, i] * (current_tip[m] - base[m, 3])
        delta[i] = des - cur
    position_jacobian(frames, jac)
    # Z = Jᵀ (J Jᵀ + λ² I)⁻¹ through the 3×3 position block (the rotation rows of J are zero).
    m00 = lam2
    m01 = 0.0
    m02 = 0.0
    m11 = lam2
    m12 = 0.0
    m22 = lam2
    for k in range(n):
        m00 += jac[0, k] * jac[0, k]
        m01 += jac[0, k] * jac[1, k]
        m02 += jac[0, k] * jac[2, k]
        m11 += jac[1, k] * jac[1, k]
        m12 += jac[1, k] * jac[2, k]
        m22 += jac[2, k] * jac[2, k]
    c00 = m11 * m22 - m12 * m12
    c01 = m02 * m12 - m01 * m22
    c02 = m01 * m12 - m02 * m11
    c11 = m00 * m22 - m02 * m02
    c12 = m01 * m02 - m00 * m12
    c22 = m00 * m11 - m01 * m01
    det = m00 * c00 + m01 * c01 + m02 * c02
    for k in range(n):
        z[k, 0] = (jac[0, k] * c00 + jac[1, k] * c01 + jac[2, k] * c02) / det
        z[k, 1] = (jac[0, k] * c01 + jac[1, k] * c11 + jac[2, k] * c12) / det
        z[k, 2] = (jac[0, k] * c02 + jac[1, k] * c12 + jac[2, k] * c22) / det
    # Joint-limit avoidance: normalised gradients of the position and velocity costs.
    cost_p = 0.0
    cost_v = 0.0
    for k in range(n):
        span = upper[k] - lower[k]
        if span != 0.0:
            centre = lower[k] + span / 2.0
            t = w * (q[k] - centre) / span
            cost_p += t * t
        tv = w * qd[k] / (2.0 * max_vel[k])
        cost_v += tv * tv
    norm_p = math.sqrt(cost_p)
    norm_v = math.sqrt(cost_v)
    # Both terms are normalised gradients: OpenSHC gives them a length that does not shrink as what they correct
    # does. The velocity term keeps (1 − share)·w/(2·max_vel) however slowly the joints move (√Φ_v vanishes with
    # q̇), so joints moving less than that per cycle (a robot standing) are pushed back further than they came, every
    # cycle: a two-cycle chatter. The position term's step on a joint of range Δq has the gain share·w²/(Δq²·√Φ_p),
    # above 2 (the same overshoot) on a narrow range (a "locked" ±0.1 rad joint). ``avoidance_cap`` c > 0 shortens
    # each to at most c times what it corrects: the velocity term to c·|q̇|·dt, the position term (scaled as a whole,
    # so where the leg settles is unchanged) to a gain of c (docs/deviations.md).
    vel_scale = 1.0
    pos_scale = 1.0
    if avoidance_cap > 0.0:
        moved = 0.0
        pushed = 0.0
        narrowest = math.inf
        for k in range(n):
            vspan = 2.0 * max_vel[k]
            moved += qd[k] * qd[k]
            if norm_v > 0.0:
                g = (w * w) * qd[k] / (vspan * vspan) / norm_v
                pushed += g * g
            span = upper[k] - lower[k]
            if span != 0.0:
                narrowest = min(narrowest, span)
        reach = avoidance_cap * math.sqrt(moved) * dt
        length = (1.0 - POSITION_LIMIT_SHARE) * math.sqrt(pushed)
        if length > reach:
            vel_scale = reach / length
        # a tip whose target moves (walking, posing) keeps OpenSHC's velocity term: shortened, it let a walking
        # stance leg's redundant joints move undamped and its foot slip in yaw (the leg odometry then misread a
        # walk as a turn); it blends in from a still target to one moving CAPPED_TIP_SPEED
        moving = target_motion / (CAPPED_TIP_SPEED * dt)
        if moving >= 1.0:
            vel_scale = 1.0
        elif moving > vel_scale:
            vel_scale = moving
        gain = POSITION_LIMIT_SHARE * (w * w) / (narrowest * narrowest * norm_p) if norm_p > 0.0 else 0.0
        if gain > avoidance_cap:
            pos_scale = avoidance_cap / gain
    for k in range(n):
        span = upper[k] - lower[k]
        gp = 0.0
        if span != 0.0 and norm_p > 0.0:
            centre = lower[k] + span / 2.0
            gp = -(w * w) * (q[k] - centre) / (span * span) / norm_p * pos_scale
        gv = 0.0
        if norm_v > 0.0:
            vspan = 2.0 * max_vel[k]
            gv = -(w * w) * qd[k] / (vspan * vspan) / norm_v * vel_scale
        v[k] = (POSITION_LIMIT_SHARE * gp + (1.0 - POSITION_LIMIT_SHARE) * gv) * null_space
    # Δq = Z Δs + (I − Z J) v, then velocity and position clamping.
    jv0 = 0.0
    jv1 = 0.0
    jv2 = 0.0
    for k in range(n):
        jv0 += jac[0, k] * v[k]
        jv1 += jac[1, k] * v[k]
        jv2 += jac[2, k] * v[k]
    flags = 0
    for k in range(n):
        step = z[k, 0] * delta[0] + z[k, 1] * delta[1] + z[k, 2] * delta[2]
        step += v[k] - (z[k, 0] * jv0 + z[k, 1] * jv1 + z[k, 2] * jv2)
        rate = step / dt
        if clamp_velocities:
            if rate > max_vel[k]:
                rate = max_vel[k]
                flags |= 4
            elif rate < -max_vel[k]:
                rate = -max_vel[k]
                flags |= 4
        value = q[k] + rate * dt
        if clamp_positions:
            if value > upper[k]:
                value = upper[k]
                flags |= 2
            elif value < lower[k]:
                value = lower[k]
                flags |= 2
        qd_out[k] = rate
        q_out[k] = value
    prox = 1.0
    for k in range(n):
        half = (upper[k] - lower[k]) / 2.0
        if half != 0.0:
            near = min(abs(q_out[k] - lower[k]), abs(q_out[k] - upper[k])) / half
            prox = min(prox, near)
    # Forward kinematics of the result and the 5 mm deviation check.
    chain_frames(base, d, theta, r, alpha, q_out, frames)
    ok = True
    for i in range(3):
        acc = 0.0
        for m in range(3):
            acc += base[i, m] * frames[n, m, 3]
        acc += base[i, 3]
        tip_out[i] = acc
        if abs(acc - desired_tip[i]) > IK_TOLERANCE:
            ok = False
    if ok:
        flags |= 1
    return flags, prox


@njit(cache=True)
def ik_step_kernel(  # type: ignore[no-untyped-def]
    base, d, theta, r, alpha, lower, upper, max_vel,
    q, qd, current_tip, desired_tip, dt, clamp_positions, clamp_velocities,
    q_out, qd_out, tip_out, flags_out, proximity_out, null_space=1.0, avoidance_cap=0.0,
):
    """:func:`ik_step_one` for every chain ``b`` of ``(B, n)`` arrays."""
    chains, n = d.shape
    frames, jac, z, v, delta = np.empty((n + 1, 4, 4)), np.empty((3, n)), np.empty((n, 3)), np.empty(n), np.empty(3)
    for b in range(chains):
        flags_out[b], proximity_out[b] = ik_step_one(
            base[b], d[b], theta[b], r[b], alpha[b], lower[b], upper[b], max_vel[b],
            q[b], qd[b], current_tip[b], desired_tip[b], dt, clamp_positions, clamp_velocities,
            q_out[b], qd_out[b], tip_out[b], frames, jac, z, v, delta, null_space, False, avoidance_cap,
        )


@njit(cache=True)
def ik_step_frames_kernel(  # type: ignore[no-untyped-def]
    base, d, theta, r, alpha, lower, upper, max_vel,
    q, qd, current_tip, desired_tip, dt, clamp_positions, clamp_velocities,
    q_out, qd_out, tip_out, flags_out, proximity_out, frames, frames_q, target_motion, null_space=1.0,
    avoidance_cap=0.0,
):
    """:func:`ik_step_kernel` keeping each chain's frames: ``frames[b]`` ``(n + 1, 4, 4)`` holds the frames of the
    joints ``frames_q[b]`` (NaN: none yet). A chain whose joints ``q[b]`` are those, bit for bit, starts from them
    instead of computing them again — the frames of one step's result are where the controller's next step starts
    (the same function of the same values: the same bits). Both are updated to ``q_out``. ``target_motion[b]``: how
    far chain b's target moved since its last step [m] (:func:`ik_step_one`)."""
    chains, n = d.shape
    jac, z, v, delta = np.empty((3, n)), np.empty((n, 3)), np.empty(n), np.empty(3)
    for b in range(chains):
        ready = True
        for k in range(n):
            now = q[b, k]
            kept = frames_q[b, k]
            if not (now == kept and math.copysign(1.0, now) == math.copysign(1.0, kept)):  # (NaN: never equal)
                ready = False
                break
        flags_out[b], proximity_out[b] = ik_step_one(
            base[b], d[b], theta[b], r[b], alpha[b], lower[b], upper[b], max_vel[b],
            q[b], qd[b], current_tip[b], desired_tip[b], dt, clamp_positions, clamp_velocities,
            q_out[b], qd_out[b], tip_out[b], frames[b], jac, z, v, delta, null_space, ready, avoidance_cap,
            target_motion[b],
        )
        for k in range(n):
            frames_q[b, k] = q_out[b, k]


@njit(cache=True)
def linear_search_kernel(  # type: ignore[no-untyped-def]
    base, d, theta, r, alpha, lower, upper, max_vel,
    q, start_tip, end_tip, origin, steps, dt, stop_on_failure, distance_out,
):
    """Move each chain's tip target from ``start_tip`` to ``end_tip`` in ``steps`` equal IK steps.

    Simulation steps as in OpenSHC's workspace search: positions clamped, velocities not. With
    ``stop_on_failure`` a chain stops at the first step whose result is 0 (tip error > 5 mm or a joint at a
    limit). ``q`` is updated in place; ``distance_out[b]`` receives |tip − origin| at the last step taken.
    """
    chains, n = d.shape
    frames, jac, z, v, delta = np.empty((n + 1, 4, 4)), np.empty((3, n)), np.empty((n, 3)), np.empty(n), np.empty(3)
    qd = np.zeros(n)
    q_new = np.empty(n)
    qd_new = np.empty(n)
    tip = np.empty(3)
    tip_new = np.empty(3)
    target = np.empty(3)
    for b in range(chains):
        qd[:] = 0.0
        tip_kernel_one(base[b], d[b], theta[b], r[b], alpha[b], q[b], frames, tip)
        distance_out[b] = 0.0
        for i in range(1, steps + 1):
            share = i / steps
            for a in range(3):
                target[a] = start_tip[b, a] * (1.0 - share) + end_tip[b, a] * share
            flags, prox = ik_step_one(
                base[b], d[b], theta[b], r[b], alpha[b], lower[b], upper[b], max_vel[b],
                q[b], qd, tip, target, dt, True, False, q_new, qd_new, tip_new, frames, jac, z, v, delta,
            )
            q[b, :] = q_new
            qd[:] = qd_new
            tip[:] = tip_new
            dist = 0.0
            for a in range(3):
                dist += (tip[a] - origin[b, a]) ** 2
            distance_out[b] = math.sqrt(dist)
            if stop_on_failure and ((flags & 1) == 0 or prox == 0.0):
                break


SPEED_TOLERANCE = 1e-12
"""Joint motion beyond ``max_vel·dt`` [rad] that :func:`limit_joint_speed_kernel` lets pass: the rounding of
``q + max_vel·dt − q`` after an IK step clamped to ``max_vel``, never a real excess."""


@njit(cache=True)
def limit_joint_speed_kernel(before, joints, bound, joints_out, velocities, velocities_out, dt, limited_out):  # type: ignore[no-untyped-def]
    """The per-cycle joint speed guard (docs/deviations.md): each joint moves at most ``bound`` (``max_vel·dt``)
    from ``before`` (the joints the cycle started from), ``(B, n)`` arrays.

    A joint that moved further is put at ``before ± bound`` in ``joints_out`` and its velocity in
    ``velocities_out`` becomes ``± bound / dt``; every other value is copied. ``limited_out[b]`` is 1 where a joint of
    chain ``b`` was limited, else 0. Returns the number of chains limited.
    """
    chains, n = joints.shape
    count = 0
    for b in range(chains):
        limited_out[b] = 0
        for k in range(n):
            step = joints[b, k] - before[b, k]
            limit = bound[b, k]
            value = joints[b, k]
            rate = velocities[b, k]
            if step > limit + SPEED_TOLERANCE:
                value = before[b, k] + limit
                rate = limit / dt
                limited_out[b] = 1
            elif step < -limit - SPEED_TOLERANCE:
                value = before[b, k] - limit
                rate = -limit / dt
                limited_out[b] = 1
            joints_out[b, k] = value
            velocities_out[b, k] = rate
        count += limited_out[b]
    return count


@njit(cache=True)
def joint_speed_exceeded(before, joints, limit):  # type: ignore[no-untyped-def]
    """Whether any joint of ``joints`` is further than ``limit`` (``max_vel·dt`` + :data:`SPEED_TOLERANCE`) from
    ``before``, ``(B, n)``: the guard's check, cheaper than limiting (the common case is nothing to limit)."""
    chains, n = joints.shape
    for b in range(chains):
        for k in range(n):
            if abs(joints[b, k] - before[b, k]) > limit[b, k]:
                return True
    return False
