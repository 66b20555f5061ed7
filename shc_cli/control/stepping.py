"""Compiled per-leg stepping: phase, step state and the Bézier tip trajectory of every leg (study §4–§5).

The state of all legs lives in four arrays (see :class:`LegArrays`): vectors ``(L, V, 3)``, Bézier nodes
``(L, 3, 5, 3)``, floats ``(L, F)`` and integers ``(L, I)``, indexed by the constants below. The walk
controller calls :func:`walk_legs` once per cycle; it runs OpenSHC's per-leg block of ``updateWalk``
(walk-state bookkeeping, ``updateTipPosition``, ``iteratePhase``) for all legs in id order. Swing and
stance *integrate* the derivative of a quartic Bézier curve, as OpenSHC does; expressions keep its
operation order so recordings match to their printed precision. Compiled with numba
(``NUMBA_DISABLE_JIT=1`` runs it as plain Python for debugging).
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.control.states import WalkState
from shc_cli.model.jit import njit

# Step states (OpenSHC StepState) and walk states (WalkState).
SWING, STANCE, FORCE_STANCE, FORCE_STOP = 0, 1, 2, 3
STARTING, MOVING, STOPPING, STOPPED = (int(state) for state in WalkState)  # plain ints for the kernels

# Vector slots, (L, V, 3), walk-plane frame [m, m/s].
CURRENT, DEFAULT, TARGET, VELOCITY, STRIDE, SWING_ORIGIN, SWING_ORIGIN_VELOCITY, STANCE_ORIGIN, IDENTITY, \
    CLEARANCE, PLANE, NORMAL = range(12)
VECTORS = 12
# Node sets, (L, 3, 5, 3).
PRIMARY, SECONDARY, STANCE_NODES = range(3)
# Float slots, (L, F).
SWING_PROGRESS, STANCE_PROGRESS, STEP_PROGRESS, SWING_DELTA_T, STANCE_DELTA_T, SPAN_CHANGE = range(6)
FLOATS = 6
# Integer slots, (L, I).
PHASE, OFFSET, STATE, AT_CORRECT_PHASE, COMPLETED_FIRST_STEP, IS_LEFT = range(6)
INTEGERS = 6
# Walk counters, (3,).
LEGS_AT_CORRECT_PHASE, LEGS_COMPLETED_FIRST_STEP, RETURN_TO_DEFAULT_ATTEMPTED = range(3)

TIP_TOLERANCE = 0.01
"""Tip-to-target distance [m] within which a stopping leg counts as back at its default."""


class LegArrays:
    """The stepping state of ``L`` legs (OpenSHC ``LegStepper`` × L) as arrays.

    Args:
        identity_tips: default tip positions ``(L, 3)`` in the walk plane [m].
        offsets: phase offsets [iterations], legs in id order.
        swing_height: initial swing clearance [m].
    """

    def __init__(self, identity_tips: np.ndarray, offsets: list[int], swing_height: float) -> None:
        legs = len(identity_tips)
        self.vectors = np.zeros((legs, VECTORS, 3))
        for slot in (CURRENT, DEFAULT, TARGET, SWING_ORIGIN, STANCE_ORIGIN, IDENTITY):
            self.vectors[:, slot] = identity_tips
        self.vectors[:, CLEARANCE, 2] = swing_height
        self.vectors[:, NORMAL, 2] = 1.0
        self.nodes = np.zeros((legs, 3, 5, 3))
        self.floats = np.zeros((legs, FLOATS))
        self.floats[:, SWING_PROGRESS] = -1.0
        self.floats[:, STANCE_PROGRESS] = -1.0
        self.integers = np.zeros((legs, INTEGERS), dtype=np.int64)
        self.integers[:, OFFSET] = offsets
        self.integers[:, STATE] = STANCE
        self.integers[:, IS_LEFT] = identity_tips[:, 1] > 0.0

    def tips(self) -> np.ndarray:
        """Current walker tips ``(L, 3)`` (a copy)."""
        return np.array(self.vectors[:, CURRENT])


@njit(cache=True)
def update_step_state(integers, leg, swing_start, swing_end, stance_start, stance_end):  # type: ignore[no-untyped-def]
    """Step state from the phase; FORCE_STOP is sticky, FORCE_STANCE lasts until the swing window ends."""
    state = integers[leg, STATE]
    if state == FORCE_STOP:
        return
    phase = integers[leg, PHASE]
    if swing_start <= phase < swing_end and state != FORCE_STANCE:
        integers[leg, STATE] = SWING
    elif phase < stance_end or phase >= stance_start:
        integers[leg, STATE] = STANCE


@njit(cache=True)
def iterate_phase(integers, floats, leg, period, swing_start, swing_end, stance_start, stance_end):  # type: ignore[no-untyped-def]
    """Advance one iteration; the progress values then describe the next cycle (FORCE_STANCE keeps them)."""
    integers[leg, PHASE] = (integers[leg, PHASE] + 1) % period
    update_step_state(integers, leg, swing_start, swing_end, stance_start, stance_end)
    phase = integers[leg, PHASE]
    floats[leg, STEP_PROGRESS] = phase / period
    state = integers[leg, STATE]
    if state == SWING:
        progress = (phase - swing_start + 1) / (swing_end - swing_start)
        floats[leg, SWING_PROGRESS] = min(max(progress, 0.0), 1.0)
        floats[leg, STANCE_PROGRESS] = -1.0
    elif state == STANCE:
        progress = (((phase + period - stance_start) % period) + 1) / ((stance_end - stance_start) % period)
        floats[leg, STANCE_PROGRESS] = min(max(progress, 0.0), 1.0)
        floats[leg, SWING_PROGRESS] = -1.0
    elif state == FORCE_STOP:
        floats[leg, STANCE_PROGRESS] = 0.0
        floats[leg, SWING_PROGRESS] = -1.0


@njit(cache=True)
def _projection(vx, vy, vz, nx, ny, nz):  # type: ignore[no-untyped-def]
    """Projection of v on n; zero if either is zero (OpenSHC ``getProjection``)."""
    if (vx == 0.0 and vy == 0.0 and vz == 0.0) or (nx == 0.0 and ny == 0.0 and nz == 0.0):
        return 0.0, 0.0, 0.0
    scale = (vx * nx + vy * ny + vz * nz) / (nx * nx + ny * ny + nz * nz)
    return scale * nx, scale * ny, scale * nz


@njit(cache=True)
def _quartic_dot(nodes, t, out):  # type: ignore[no-untyped-def]
    """``dB/dt`` of the quartic Bézier ``nodes`` (5, 3) at ``t`` into ``out`` (3,)."""
    s = 1.0 - t
    a = 4.0 * s * s * s
    b = 12.0 * s * s * t
    c = 12.0 * s * t * t
    d = 4.0 * t * t * t
    for i in range(3):
        out[i] = (a * (nodes[1, i] - nodes[0, i]) + b * (nodes[2, i] - nodes[1, i])
                  + c * (nodes[3, i] - nodes[2, i]) + d * (nodes[4, i] - nodes[3, i]))


@njit(cache=True)
def _update_stride(vectors, leg, vx, vy, omega, scale, swing_height, plane, normal):  # type: ignore[no-untyped-def]
    """Stride = (v + ω ẑ × tip_xy)·β/f and the swing clearance along the walk-plane normal (study §5.1)."""
    for i in range(3):
        vectors[leg, PLANE, i] = plane[i]
        vectors[leg, NORMAL, i] = normal[i]
    x = vectors[leg, CURRENT, 0]
    y = vectors[leg, CURRENT, 1]
    vectors[leg, STRIDE, 0] = (vx + (0.0 * 0.0 - omega * y)) * scale
    vectors[leg, STRIDE, 1] = (vy + (omega * x - 0.0 * 0.0)) * scale
    vectors[leg, STRIDE, 2] = (0.0 + (0.0 * y - 0.0 * x)) * scale
    size = math.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
    for i in range(3):
        vectors[leg, CLEARANCE, i] = swing_height * (normal[i] / size)


@njit(cache=True)
def update_tip_position(  # type: ignore[no-untyped-def]
    vectors, nodes, floats, integers, leg, period, swing_start, swing_end, stance_start, stance_end,
    swing_period, stance_period_full, frequency, dt, vx, vy, omega, swing_height, swing_width, plane, normal,
    rough, step_depth, sensing, contact, body_position, perceive, offsets, clearances,
):
    """Move one leg's walker tip one control cycle along its swing or stance curve (study §5).

    Rough-terrain mode (study §5.5, §5.7): the default tip is updated at every swing and stance start (its height
    through where the foot last landed); with foot sensing, the swing target is lowered by ``step_depth`` along
    the walk-plane normal (reactive) and, once the foot touches down in the second half of the swing, the tip
    stops moving towards the ground. Returns whether the default tip moved.

    With ``perceive`` (a height map, :mod:`shc_cli.control.step_plane`) the target is shifted by the leg's
    ``offsets`` (OpenSHC's proactive step-plane shift, walk-plane frame) and the swing clearance is the leg's
    ``clearances`` instead of ``swing_height``.
    """
    moved = False
    state = integers[leg, STATE]
    standard = state == SWING or integers[leg, COMPLETED_FIRST_STEP] != 0
    this_stance_start = stance_start if standard else integers[leg, OFFSET]
    stance_period = (stance_end - this_stance_start) % period
    if stance_end == this_stance_start:
        stance_period = period
    swing_iterations = int((swing_period / period) / (frequency * dt))
    if swing_iterations % 2 != 0:
        swing_iterations += 1
    swing_dt = 1.0 / (swing_iterations / 2.0)
    stance_iterations = int((stance_period / period) / (frequency * dt))
    stance_dt = 1.0 / stance_iterations
    floats[leg, SWING_DELTA_T] = swing_dt
    floats[leg, STANCE_DELTA_T] = stance_dt
    for i in range(3):  # the target uses the previous cycle's stride, as in OpenSHC
        vectors[leg, TARGET, i] = vectors[leg, DEFAULT, i] + 0.5 * vectors[leg, STRIDE, i]
    if rough and sensing and step_depth != 0.0:
        size = math.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
        for i in range(3):
            vectors[leg, TARGET, i] -= step_depth * (normal[i] / size)
    if perceive:
        for i in range(3):
            vectors[leg, TARGET, i] += offsets[leg, i]
        swing_height = clearances[leg]
    scale = (stance_period_full / period) / frequency
    delta = np.empty(3)
    if state == SWING:
        _update_stride(vectors, leg, vx, vy, omega, scale, swing_height, plane, normal)
        iteration = integers[leg, PHASE] - swing_start + 1
        if iteration == 1:
            for i in range(3):
                vectors[leg, SWING_ORIGIN, i] = vectors[leg, CURRENT, i]
                vectors[leg, SWING_ORIGIN_VELOCITY, i] = vectors[leg, VELOCITY, i]
            if rough:
                update_default_tip(vectors, floats, leg, body_position)
                moved = True
        _swing_nodes(vectors, nodes, leg, swing_dt, stance_dt, dt, swing_width, integers[leg, IS_LEFT] != 0)
        half = swing_iterations // 2
        if iteration <= half:
            _quartic_dot(nodes[leg, PRIMARY], swing_dt * iteration, delta)
        else:
            _quartic_dot(nodes[leg, SECONDARY], swing_dt * (iteration - half), delta)
            if rough and sensing and contact:  # touched down: no further motion towards the ground
                size = math.sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])
                down = (delta[0] * normal[0] + delta[1] * normal[1] + delta[2] * normal[2]) / size
                if down < 0.0:
                    for i in range(3):
                        delta[i] -= down * (normal[i] / size)
        for i in range(3):
            step = swing_dt * delta[i]
            vectors[leg, CURRENT, i] = vectors[leg, CURRENT, i] + step
            vectors[leg, VELOCITY, i] = step / dt
    elif state == STANCE or state == FORCE_STANCE:  # noqa: SIM109 (plain comparisons compile simply in numba)
        _update_stride(vectors, leg, vx, vy, omega, scale, swing_height, plane, normal)
        iteration = (integers[leg, PHASE] + (period - this_stance_start)) % period + 1
        if iteration == 1:
            for i in range(3):
                vectors[leg, STANCE_ORIGIN, i] = vectors[leg, CURRENT, i]
            if rough:
                update_default_tip(vectors, floats, leg, body_position)
                moved = True
        scaler = stance_period / ((stance_end - stance_start) % period)
        for i in range(3):
            step = ((-vectors[leg, STRIDE, i]) * scaler) * 0.25
            for k in range(5):
                nodes[leg, STANCE_NODES, k, i] = vectors[leg, STANCE_ORIGIN, i] + k * step
        _quartic_dot(nodes[leg, STANCE_NODES], iteration * stance_dt, delta)
        for i in range(3):
            step = stance_dt * delta[i]
            vectors[leg, CURRENT, i] = vectors[leg, CURRENT, i] + step
            vectors[leg, VELOCITY, i] = step / dt
    return moved


@njit(cache=True)
def _swing_nodes(vectors, nodes, leg, swing_dt, stance_dt, dt, swing_width, is_left):  # type: ignore[no-untyped-def]
    """Primary (lift-off → apex) and secondary (apex → touchdown) swing control nodes (study §5.2–§5.3)."""
    primary = nodes[leg, PRIMARY]
    secondary = nodes[leg, SECONDARY]
    mid = np.empty(3)
    for i in range(3):
        mid[i] = (vectors[leg, SWING_ORIGIN, i] + vectors[leg, TARGET, i]) / 2.0
    mid[2] = max(vectors[leg, SWING_ORIGIN, 2], vectors[leg, TARGET, 2])
    for i in range(3):
        mid[i] = mid[i] + vectors[leg, CLEARANCE, i]
    mid[1] += swing_width if is_left else -swing_width
    for i in range(3):
        origin = vectors[leg, SWING_ORIGIN, i]
        scale = (0.25 * vectors[leg, SWING_ORIGIN_VELOCITY, i]) * (dt / swing_dt)
        primary[0, i] = origin
        primary[1, i] = origin + scale
        primary[2, i] = origin + 2.0 * scale
        primary[3, i] = (mid[i] + primary[2, i]) / 2.0
        primary[4, i] = mid[i]
    primary[3, 2] = mid[2]
    for i in range(3):
        final_velocity = (-vectors[leg, STRIDE, i]) * (stance_dt / dt)
        scale = (0.25 * final_velocity) * (dt / swing_dt)
        target = vectors[leg, TARGET, i]
        secondary[0, i] = primary[4, i]
        secondary[1, i] = primary[4, i] - (primary[3, i] - primary[4, i])
        secondary[2, i] = target - 2.0 * scale
        secondary[3, i] = target - scale
        secondary[4, i] = target


@njit(cache=True)
def _at_target(vectors, leg):  # type: ignore[no-untyped-def]
    """In-plane tip-to-target distance below :data:`TIP_TOLERANCE`."""
    ex = vectors[leg, CURRENT, 0] - vectors[leg, TARGET, 0]
    ey = vectors[leg, CURRENT, 1] - vectors[leg, TARGET, 1]
    ez = vectors[leg, CURRENT, 2] - vectors[leg, TARGET, 2]
    px, py, pz = _projection(ex, ey, ez, vectors[leg, NORMAL, 0], vectors[leg, NORMAL, 1], vectors[leg, NORMAL, 2])
    rx, ry, rz = ex - px, ey - py, ez - pz
    return math.sqrt(rx * rx + ry * ry + rz * rz) < TIP_TOLERANCE


@njit(cache=True)
def update_default_tip(vectors, floats, leg, body_position):  # type: ignore[no-untyped-def]
    """New default after a stop: identity x, y plus the stance-span change (y); height through the last
    stance origin (study §5.5)."""
    point = np.empty(3)
    span = (0.0, floats[leg, SPAN_CHANGE], 0.0)
    for i in range(3):
        point[i] = body_position[i] + (vectors[leg, IDENTITY, i] + span[i])
    px, py, pz = _projection(vectors[leg, STANCE_ORIGIN, 0] - point[0], vectors[leg, STANCE_ORIGIN, 1] - point[1],
                             vectors[leg, STANCE_ORIGIN, 2] - point[2], vectors[leg, NORMAL, 0],
                             vectors[leg, NORMAL, 1], vectors[leg, NORMAL, 2])
    vectors[leg, DEFAULT, 0] = point[0] + px
    vectors[leg, DEFAULT, 1] = point[1] + py
    vectors[leg, DEFAULT, 2] = point[2] + pz


@njit(cache=True)
def walk_legs(  # type: ignore[no-untyped-def]
    vectors, nodes, floats, integers, counters, walk_state, period, swing_start, swing_end, stance_start,
    stance_end, swing_period, stance_period, frequency, dt, vx, vy, omega, swing_height, swing_width, plane,
    normal, body_position, rough, step_depth, sensing, contacts, perceive, offsets, clearances,
):
    """OpenSHC's per-leg block of ``updateWalk`` for every leg in id order (counters change during the loop).

    Returns the number of legs whose default tip was updated (they stopped), so the caller knows when the
    walk plane needs re-estimating.
    """
    legs = vectors.shape[0]
    moved = 0
    for leg in range(legs):
        phase = integers[leg, PHASE]
        if walk_state == STARTING:
            if (counters[LEGS_AT_CORRECT_PHASE] == legs and phase == swing_end
                    and integers[leg, COMPLETED_FIRST_STEP] == 0):
                integers[leg, COMPLETED_FIRST_STEP] = 1
                counters[LEGS_COMPLETED_FIRST_STEP] += 1
            if integers[leg, AT_CORRECT_PHASE] == 0:
                offset = integers[leg, OFFSET]
                if swing_start < offset < swing_end and phase != swing_end:
                    integers[leg, STATE] = FORCE_STANCE
                else:
                    counters[LEGS_AT_CORRECT_PHASE] += 1
                    integers[leg, AT_CORRECT_PHASE] = 1
        elif walk_state == MOVING:
            integers[leg, AT_CORRECT_PHASE] = 0
        elif walk_state == STOPPING:
            zero_stride = (vectors[leg, STRIDE, 0] == 0.0 and vectors[leg, STRIDE, 1] == 0.0
                           and vectors[leg, STRIDE, 2] == 0.0)
            if zero_stride and integers[leg, AT_CORRECT_PHASE] == 0 and phase == swing_end:
                if _at_target(vectors, leg) or counters[RETURN_TO_DEFAULT_ATTEMPTED] != 0:
                    counters[RETURN_TO_DEFAULT_ATTEMPTED] = 0
                    update_default_tip(vectors, floats, leg, body_position)
                    moved += 1
                    integers[leg, STATE] = FORCE_STOP
                    integers[leg, AT_CORRECT_PHASE] = 1
                    counters[LEGS_AT_CORRECT_PHASE] += 1
                else:
                    counters[RETURN_TO_DEFAULT_ATTEMPTED] = 1
        elif walk_state == STOPPED:
            integers[leg, STATE] = FORCE_STOP
            integers[leg, PHASE] = 0
        if update_tip_position(vectors, nodes, floats, integers, leg, period, swing_start, swing_end, stance_start,
                               stance_end, swing_period, stance_period, frequency, dt, vx, vy, omega, swing_height,
                               swing_width, plane, normal, rough, step_depth, sensing, contacts[leg],
                               body_position, perceive, offsets, clearances):
            moved += 1
        iterate_phase(integers, floats, leg, period, swing_start, swing_end, stance_start, stance_end)
    return moved


@njit(cache=True)
def round_half_away(value):  # type: ignore[no-untyped-def]
    """OpenSHC ``roundToInt``: halves round away from zero."""
    return int(value + 0.5) if value >= 0.0 else -int(0.5 - value)


@njit(cache=True)
def walk_limits(tips, linear_x, linear_y, angular, table, bearing_step, out):  # type: ignore[no-untyped-def]
    """Smallest limit of each column of ``table`` over the legs (OpenSHC ``getLimit``), into ``out``.

    ``table`` is ``(K, C)``: row ``k`` holds the limits at bearing ``k·bearing_step`` (k = 0 … 360/step).
    Each leg's stride direction at its walker tip gives a bearing; the table is read at the sector
    *below* it, because OpenSHC's interpolation weight is an integer division.
    """
    columns = table.shape[1]
    for c in range(columns):
        out[c] = np.inf
    for leg in range(tips.shape[0]):
        dx = linear_x + angular * -tips[leg, 1]
        dy = linear_y + angular * tips[leg, 0]
        bearing = round_half_away((math.atan2(dy, dx) / (2.0 * math.pi)) * 360.0) % 360
        upper = ((bearing + bearing_step - 1) // bearing_step) * bearing_step  # first key ≥ bearing
        lower = (upper - bearing_step) % 360
        if bearing < lower:
            bearing += 360
        if upper < lower:
            upper += 360
        share = (bearing - lower) // (upper - lower)
        low_row = lower // bearing_step
        high_row = (upper % 360) // bearing_step
        for c in range(columns):
            value = (1.0 - share) * table[low_row, c] + share * table[high_row, c]
            if value < out[c]:
                out[c] = value


# Slots of the walk-level state array (7,): desired velocity and ideal odometry.
DESIRED_X, DESIRED_Y, DESIRED_YAW_RATE, ODOMETRY_X, ODOMETRY_Y, ODOMETRY_Z, ODOMETRY_YAW = range(7)
WALK_SLOTS = 7


@njit(cache=True)
def clamped_norm(x, y, limit):  # type: ignore[no-untyped-def]
    """2-D vector ``(x, y)`` scaled down to norm ``limit`` if longer (OpenSHC ``clamped(vector, limit)``; Eigen's
    ``sqrt(x² + y²)`` norm). The one velocity clamp: compiled for :func:`walk_update`, called from Python by
    :meth:`WalkController.within_limits_for` so both see the same target to the bit."""
    norm = math.sqrt(x * x + y * y)
    if norm > limit:
        scale = limit / norm
        return x * scale, y * scale
    return x, y


@njit(cache=True)
def walk_update(  # type: ignore[no-untyped-def]
    vectors, nodes, floats, integers, counters, walk, walk_state, table, bearing_step, period, swing_start,
    swing_end, stance_start, stance_end, swing_period, stance_period, frequency, dt, linear_x, linear_y, angular,
    throttle, swing_height, swing_width, plane, normal, body_position, legs_walking, posing_complete, limits_out,
    rough, step_depth, sensing, contacts, perceive, offsets, clearances,
):
    """One cycle of OpenSHC's ``updateWalk`` (study §4.4, §6; exact notes §2): limits for the input at the
    current tips, new target velocity, acceleration ramp, walk-state transition, the legs, ideal odometry.

    ``walk`` holds the desired velocity and odometry (slots above) and is updated in place. Returns
    ``(walk_state, legs_whose_default_tip_moved)``.
    """
    walk_limits(vectors[:, CURRENT], linear_x, linear_y, angular, table, bearing_step, limits_out)
    max_speed, max_angular = limits_out[0], limits_out[1]
    max_acceleration, max_angular_acceleration = limits_out[2], limits_out[3]
    new_x, new_y, new_angular = 0.0, 0.0, 0.0
    if walk_state != STOPPING:
        if throttle:
            new_x, new_y = clamped_norm(linear_x, linear_y, 1.0)
            new_x, new_y = new_x * max_speed, new_y * max_speed
            new_angular = min(max(angular, -1.0), 1.0) * max_angular
            scale = 1.0 - abs(angular)
        else:
            new_angular = min(max(angular, -max_angular), max_angular)
            new_x, new_y = clamped_norm(linear_x, linear_y, max_speed)
            scale = 1.0 - abs(new_angular / max_angular) if max_angular != 0.0 else 0.0
        new_x, new_y = new_x * scale, new_y * scale
    has_command = linear_x != 0.0 or linear_y != 0.0 or angular != 0.0
    if not legs_walking:
        return walk_state, 0
    # Acceleration-limited ramp (Eigen: norm = sqrt(x² + y²), normalized = division by it; sign(0) = −1).
    vx, vy = walk[DESIRED_X], walk[DESIRED_Y]
    cx, cy = new_x - vx, new_y - vy
    size = math.sqrt(cx * cx + cy * cy)
    if size < max_acceleration * dt:
        walk[DESIRED_X], walk[DESIRED_Y] = vx + cx, vy + cy
    else:
        walk[DESIRED_X] = vx + ((cx / size) * max_acceleration) * dt
        walk[DESIRED_Y] = vy + ((cy / size) * max_acceleration) * dt
    change = new_angular - walk[DESIRED_YAW_RATE]
    if abs(change) < max_angular_acceleration * dt:
        walk[DESIRED_YAW_RATE] += change
    else:
        walk[DESIRED_YAW_RATE] += ((1.0 if change > 0.0 else -1.0) * max_angular_acceleration) * dt
    # Walk-state transitions.
    legs = vectors.shape[0]
    if walk_state == STOPPED and has_command:
        for leg in range(legs):  # the STARTING cycle moves no tip
            integers[leg, AT_CORRECT_PHASE] = 0
            integers[leg, COMPLETED_FIRST_STEP] = 0
            integers[leg, STATE] = STANCE
            integers[leg, PHASE] = integers[leg, OFFSET]
            update_step_state(integers, leg, swing_start, swing_end, stance_start, stance_end)
        return STARTING, 0
    if (walk_state == STARTING and counters[LEGS_AT_CORRECT_PHASE] == legs
            and counters[LEGS_COMPLETED_FIRST_STEP] == legs):
        counters[LEGS_AT_CORRECT_PHASE] = 0
        counters[LEGS_COMPLETED_FIRST_STEP] = 0
        walk_state = MOVING
    elif walk_state == MOVING and not has_command:
        walk_state = STOPPING
    elif walk_state == STOPPING and counters[LEGS_AT_CORRECT_PHASE] == legs and posing_complete:
        counters[LEGS_AT_CORRECT_PHASE] = 0
        walk_state = STOPPED
    moved = walk_legs(vectors, nodes, floats, integers, counters, walk_state, period, swing_start, swing_end,
                      stance_start, stance_end, swing_period, stance_period, frequency, dt, walk[DESIRED_X],
                      walk[DESIRED_Y], walk[DESIRED_YAW_RATE], swing_height, swing_width, plane, normal,
                      body_position, rough, step_depth, sensing, contacts, perceive, offsets, clearances)
    # Ideal odometry: compose this cycle's commanded motion.
    sx, sy = walk[DESIRED_X] * dt, walk[DESIRED_Y] * dt
    c, s = math.cos(walk[ODOMETRY_YAW]), math.sin(walk[ODOMETRY_YAW])
    walk[ODOMETRY_X] = walk[ODOMETRY_X] + (c * sx - s * sy)
    walk[ODOMETRY_Y] = walk[ODOMETRY_Y] + (s * sx + c * sy)
    walk[ODOMETRY_YAW] += walk[DESIRED_YAW_RATE] * dt
    return walk_state, moved
