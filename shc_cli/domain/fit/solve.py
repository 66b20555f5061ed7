"""The fit proper: weighted residuals of every recording, a bounded least squares over the parameters and the
uncertainty of each from the Jacobian at the solution.

**Residuals.** Per recording and channel — joint positions [rad], joint speeds [rad/s], motor currents [A] (a bus)
or output torques [N·m] (a simulated run), and total supply power [W] where it was measured — the simulated minus
the measured values, divided by the channel's RMS over the measured data and by √(its sample count), so each channel
weighs the same whatever its unit and length.

**Solver.** :func:`scipy.optimize.least_squares` (trust-region reflective, bounds) from the robot's values, with
this module's forward-difference Jacobian: a step of :data:`STEP` × the parameter's typical size; a parameter
that changes the motion needs one replay per step, the others (:data:`~shc_cli.domain.fit.params.ELECTRICAL_ONLY`)
only the electrical model on the cached replay. Each solver run is checked by probes of :data:`PROBE` of each
value up and down; one that lowers the cost restarts the solver from there (:func:`solve`).

**Uncertainty.** ``cov = s²·(JᵀJ)⁻¹`` with ``s² = Σr²/(m − n)`` (m residuals, n parameters), through the SVD of
the Jacobian in units of each parameter's typical size; a singular value below :data:`SINGULAR` × the largest is a
direction the data do not see, and every parameter with a share in it gets an infinite uncertainty. The residuals of
successive cycles are correlated (model error, not white noise), so ``s²/m`` underestimates the variance: the
uncertainty is multiplied by √(:data:`CORRELATION_CYCLES`), the number of control cycles over which a residual stays
correlated. That σ measures noise, not collinearity: two parameters whose effects on the readings the other can mimic
(a load-free joint's torque constant, armature and frictions scale together exactly) keep a small σ while the fit
slides along the valley between them.

**Independence.** So each parameter's sensitivity is also compared with the others': its *independent share*
``‖(I − P_others)·J_i‖ / ‖J_i‖`` (:func:`independence`; ``P_others`` the projection on the span of the other
fitted parameters' columns, through a QR of the column-normalised Jacobian) is the part of its effect no
combination of the others can reproduce — 1 for an effect of its own, 0 for one the others reproduce exactly.
Below :data:`INDEPENDENT` the parameter trades with the others whose columns make up that combination (a weight of
at least :data:`PARTNER` each: ``fit.json``'s ``correlated_with``).

Forward differences of open-loop replays are rough (Coulomb friction's stick and slip; a 1 % step sees it), and the
roughness can hide a valley: on the emulated bench the four columns of the exactly degenerate set reproduce each
other only to a few % of the largest, which leaves the small ones (viscous friction, armature) looking independent.
So the direction the Jacobian sees least (its last right singular vector with unit columns, turned into a relative
change of each value) is also walked
for real (:func:`flat_direction`): a move of :data:`PROBE` along it, against the same move of each parameter in it
(a weight of at least :data:`PARTNER` of the largest) alone; a parameter whose own move raises the cost more than
``1/INDEPENDENT²`` times the whole direction's does is compensated by the others there — not identifiable, and
they are its partners. This costs two or three replays per member.

A parameter is **identifiable** when (1) its uncertainty is below :data:`IDENTIFIABLE` of its value (of its typical
size when the value is smaller), (2) its independent share is at least :data:`INDEPENDENT`, and (3) the solver
converged, or did not but no probe of that parameter still lowered the cost (:func:`solve`).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.domain.fit.params import Parameter
from shc_cli.domain.fit.recording import Recording
from shc_cli.domain.fit.rollout import Trace, replay

if TYPE_CHECKING:
    from shc_cli.backends.engine_registry import EngineName
    from shc_cli.spec.robot import Servo

log = logging.getLogger(__name__)

STEP = 0.01
"""Forward-difference step [share of the parameter's typical size]."""
SINGULAR = 1e-6
"""Relative singular value below which a direction counts as unseen."""
CORRELATION_CYCLES = 25.0
"""Control cycles over which model error stays correlated (the uncertainty's inflation is its square root)."""
IDENTIFIABLE = 0.05
"""Relative uncertainty below which a parameter counts as identifiable."""
INDEPENDENT = 0.1
"""Independent share of a parameter's sensitivity below which it counts as not identifiable (module docstring): the
emulated bench's exactly degenerate torque constant, armature and frictions have shares of a few hundredths (the
forward differences' noise), the parameters of a well-excited fit several tenths."""
PARTNER = 0.1
"""Weight (in column-normalised units) from which another parameter counts as a partner of a degenerate one."""
WALKS = 3
"""Moves along the least-seen direction, each refined from the last (:func:`flat_direction`)."""
PROBE = 0.1
"""Probe step after each solver run [share of the parameter's value]."""
ROUNDS = 4
"""Solver runs at most (each but the first from a probe that lowered the cost)."""
CHANNELS = ("position", "velocity", "current", "torque", "power")


@dataclass
class Simulated:
    """One recording's replay with one parameter set, its electrical model applied.

    Attributes:
        position, velocity: ``(N, J)`` [rad, rad/s].
        current: motor current ``(N, J)`` [A].
        torque: output torque ``(N, J)`` [N·m].
        power: total supply power ``(N,)`` [W].
    """

    position: np.ndarray
    velocity: np.ndarray
    current: np.ndarray
    torque: np.ndarray
    power: np.ndarray

    def channel(self, name: str) -> np.ndarray:
        return np.asarray(getattr(self, name))


def electrical(trace: Trace, servo: Servo, dt: float) -> Simulated:
    """``trace`` through ``servo``'s electrical model."""
    from shc_cli.backends.servo import ServoModel

    speed = trace.speed(dt)
    state = ServoModel(servo).electrical(trace.torque, speed)
    current = state.current if trace.current is None else trace.current
    return Simulated(trace.position, speed, current, trace.torque, state.power.sum(axis=1))


def measured_channels(recording: Recording) -> dict[str, np.ndarray]:
    """The recording's measured channels by name (those it has)."""
    out = {"position": recording.position, "velocity": recording.velocity}
    for name in ("current", "torque", "power"):
        value = getattr(recording, name)
        if value is not None:
            out[name] = value
    return out


@dataclass
class Problem:
    """The least-squares problem of a fit.

    Args:
        recordings: the runs.
        base: the robot's servo (the fields not fitted keep its values).
        parameters: the fitted parameters.
        engine: the physics engine of the replays.
        joints: the servo indices whose residuals count (``None``: every joint).
    """

    recordings: list[Recording]
    base: Servo
    parameters: list[Parameter]
    engine: EngineName = "mujoco"
    joints: np.ndarray | None = None
    replays: int = 0
    _cache: dict[tuple[float, ...], list[Trace]] = field(default_factory=dict)
    _scales: dict[tuple[int, str], float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for index, recording in enumerate(self.recordings):
            for name, values in measured_channels(recording).items():
                chosen = values if values.ndim == 1 or self.joints is None else values[:, self.joints]
                rms = float(np.sqrt(np.mean(np.square(chosen))))
                self._scales[(index, name)] = max(rms, 1e-9) * np.sqrt(chosen.size)

    def servo(self, x: np.ndarray) -> Servo:
        """The servo with the parameters set to ``x``."""
        return self.base.model_copy(update={p.name: float(v) for p, v in zip(self.parameters, x, strict=True)})

    def traces(self, x: np.ndarray) -> list[Trace]:
        """The replays of every recording at ``x`` (cached by the values that change the motion)."""
        bench = any(recording.scenario == "BENCH" for recording in self.recordings)  # friction moves a bench's joints
        key = tuple(float(v) for p, v in zip(self.parameters, x, strict=True) if p.moves or bench)
        cached = self._cache.get(key)
        if cached is None:
            servo = self.servo(x)
            cached = [replay(recording, servo, self.engine) for recording in self.recordings]
            self.replays += 1
            if len(self._cache) > 8:
                self._cache.pop(next(iter(self._cache)))
            self._cache[key] = cached
        return cached

    def simulated(self, x: np.ndarray) -> list[Simulated]:
        servo = self.servo(x)
        return [electrical(trace, servo, recording.dt)
                for trace, recording in zip(self.traces(x), self.recordings, strict=True)]

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """Every weighted residual at ``x`` (module docstring)."""
        parts = []
        for index, (recording, sim) in enumerate(zip(self.recordings, self.simulated(x), strict=True)):
            for name, values in measured_channels(recording).items():
                difference = sim.channel(name) - values
                if difference.ndim == 2 and self.joints is not None:
                    difference = difference[:, self.joints]
                parts.append(difference.ravel() / self._scales[(index, name)])
        return np.concatenate(parts)

    def channel_errors(self, x: np.ndarray) -> dict[str, float]:
        """RMS of each channel's residual over every recording, in the channel's unit (``fit.json``)."""
        sums: dict[str, list[float]] = {}
        for recording, sim in zip(self.recordings, self.simulated(x), strict=True):
            for name, values in measured_channels(recording).items():
                difference = sim.channel(name) - values
                if difference.ndim == 2 and self.joints is not None:
                    difference = difference[:, self.joints]
                sums.setdefault(name, []).extend(np.square(difference).ravel().tolist())
        return {name: float(np.sqrt(np.mean(values))) for name, values in sums.items()}

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """Forward differences of :meth:`residuals` (steps of :data:`STEP` × typical size, turned back at an upper
        bound)."""
        base = self.residuals(x)
        columns = []
        for j, p in enumerate(self.parameters):
            step = STEP * p.scale
            if x[j] + step > p.upper:
                step = -step
            moved = x.copy()
            moved[j] += step
            columns.append((self.residuals(moved) - base) / step)
        return np.column_stack(columns)


@dataclass(frozen=True)
class Solution:
    """What the solver found.

    Attributes:
        x: the fitted values.
        uncertainty: one standard deviation of each (``inf``: not seen by the data).
        identifiable: each parameter's flag (module docstring).
        cost_before, cost_after: half the sum of squared weighted residuals at the start and the end.
        iterations: solver evaluations of the residuals.
        replays: engine replays of every recording.
        singular_values: of the Jacobian in typical-size units, largest first.
        converged: the solver met its tolerances (False: it stopped at its evaluation budget, and the values and
            uncertainties describe where it stopped, not a minimum).
        independence: each parameter's independent share (module docstring; 0 for one the data do not see).
        correlated: for each parameter whose share is below :data:`INDEPENDENT`, the indices of those it trades
            with (empty otherwise).
        unsettled: the parameters whose probes still lowered the cost when the solver stopped unconverged.
    """

    x: np.ndarray
    uncertainty: np.ndarray
    identifiable: np.ndarray
    cost_before: float
    cost_after: float
    iterations: int
    replays: int
    singular_values: np.ndarray
    converged: bool = True
    independence: np.ndarray = field(default_factory=lambda: np.zeros(0))
    correlated: tuple[tuple[int, ...], ...] = ()
    unsettled: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


def solve(problem: Problem, max_evaluations: int = 30) -> Solution:
    """Bounded least squares from the parameters' initial values, polished by probes; uncertainties at the solution.

    Open-loop replays make the cost slightly rough at small scales, and the trust region can shrink to nothing on a
    slope it cannot see (the Jacobian's model fails every small step): after each solver run every parameter is
    probed :data:`PROBE` of its value (of its typical size near 0) up and down, and the best probe that lowers the
    cost restarts the solver, at most :data:`ROUNDS` times; a solution whose probes still find a lower cost is
    reported as not converged.
    """
    from scipy.optimize import least_squares

    parameters = problem.parameters
    lower = np.array([p.lower for p in parameters])
    upper = np.array([p.upper for p in parameters])
    x = np.clip(np.array([p.initial for p in parameters]), lower, upper)
    scale = np.array([p.scale for p in parameters])
    start = problem.residuals(x)
    evaluations, converged = 0, False
    unsettled = np.zeros(len(parameters), dtype=bool)
    for _ in range(ROUNDS):
        budget = max_evaluations - evaluations
        if budget < 1:
            break
        result = least_squares(problem.residuals, x, jac=lambda x: problem.jacobian(x), bounds=(lower, upper),
                               x_scale=scale, method="trf", max_nfev=budget, xtol=1e-4, ftol=1e-6)
        x = np.asarray(result.x, dtype=float)
        evaluations += int(result.nfev)
        better, unsettled = _probe(problem, x, lower, upper)
        if better is None:
            converged = bool(result.status > 0)
            break
        x = better
    if converged:
        unsettled[:] = False
    residual = problem.residuals(x)
    jacobian = problem.jacobian(x)
    sigma, singular = uncertainty(residual, jacobian, scale)
    share, partners = independence(jacobian, scale)
    reference = np.maximum(np.abs(x), scale * IDENTIFIABLE)
    for k, (walked, others) in flat_direction(problem, x, jacobian * reference, reference, lower, upper).items():
        if walked < share[k]:
            share[k], partners = walked, (*partners[:k], others, *partners[k + 1:])
    identifiable = (np.isfinite(sigma) & (sigma <= IDENTIFIABLE * reference) & (share >= INDEPENDENT)
                    & ~unsettled)
    log.info("fit: %d evaluations, %d replays, cost %.4g → %.4g; independent shares %s", evaluations,
             problem.replays, 0.5 * float(start @ start), 0.5 * float(residual @ residual),
             ", ".join(f"{p.name} {v:.3g}" for p, v in zip(parameters, share, strict=True)))
    return Solution(x, sigma, identifiable, 0.5 * float(start @ start), 0.5 * float(residual @ residual),
                    evaluations, problem.replays, singular, converged, share, partners, unsettled)


def independence(jacobian: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, tuple[tuple[int, ...], ...]]:
    """Each parameter's independent share ``‖(I − P_others)·J_i‖ / ‖J_i‖`` and, for a share below
    :data:`INDEPENDENT`, the indices of the others whose least-squares weights (column-normalised) reach
    :data:`PARTNER` (module docstring). A column of zeros (a parameter the data do not see) has share 0 and no
    partners, and is no partner of the others.

    The shares need only the Gram matrix of the normalised columns, so the ``(m, n)`` Jacobian is reduced once to
    the ``n × n`` R of its QR and each column regressed on the others there.
    """
    n = jacobian.shape[1]
    scaled = jacobian * scale
    norms = np.linalg.norm(scaled, axis=0)
    seen = np.flatnonzero(norms > 1e-12 * max(float(norms.max(initial=0.0)), 1e-300))
    share = np.zeros(n)
    partners: list[tuple[int, ...]] = [() for _ in range(n)]
    if len(seen) == 0:
        return share, tuple(partners)
    r = np.asarray(np.linalg.qr(scaled[:, seen] / norms[seen], mode="r"))
    for k, i in enumerate(seen):
        others = [o for o in range(len(seen)) if o != k]
        if not others:
            share[i] = 1.0
            continue
        weights = np.linalg.lstsq(r[:, others], r[:, k], rcond=None)[0]
        share[i] = float(np.linalg.norm(r[:, k] - r[:, others] @ weights))
        if share[i] < INDEPENDENT:
            partners[i] = tuple(int(seen[o]) for o, w in zip(others, weights, strict=True) if abs(w) >= PARTNER)
    return np.clip(share, 0.0, 1.0), tuple(partners)


def flat_direction(problem: Problem, x: np.ndarray, relative: np.ndarray, reference: np.ndarray, lower: np.ndarray,
                   upper: np.ndarray) -> dict[int, tuple[float, tuple[int, ...]]]:
    """The direction ``relative`` (the Jacobian in units of each parameter's value) sees least, walked for real
    (module docstring): for each member whose own move raises the cost more than ``1/INDEPENDENT²`` times the
    direction's changes it (either way), its share ``√(|change of the direction| / rise of its own move)`` and the
    other members. Empty when
    the direction has one member, cannot be walked inside the bounds, or is seen.

    The direction from the rough Jacobian is only near the valley's floor, so it is refined :data:`WALKS` times by
    a Gauss-Newton step of its members but the largest, on the secants of their own moves."""
    norms = np.linalg.norm(relative, axis=0)
    seen = np.flatnonzero(norms > 0)
    if len(seen) < 2:
        return {}
    direction = np.zeros(len(x))  # least seen among unit columns (collinearity, not size), back in value units
    direction[seen] = np.linalg.svd(relative[:, seen] / norms[seen], full_matrices=False)[2][-1] / norms[seen]
    direction /= direction[np.argmax(np.abs(direction))]
    members = [int(k) for k in np.flatnonzero(np.abs(direction) >= PARTNER)]
    if len(members) < 2:
        return {}
    base = problem.residuals(x)
    cost = float(base @ base)
    secants, own = {}, {}
    for k in members:  # each member's own move of PROBE of its value, up (down at the upper bound)
        step = PROBE * reference[k] * (1.0 if x[k] + PROBE * reference[k] <= upper[k] else -1.0)
        if not lower[k] <= x[k] + step <= upper[k]:
            return {}
        moved = x.copy()
        moved[k] += step
        residual = problem.residuals(moved)
        own[k] = float(residual @ residual) - cost
        secants[k] = (residual - base) / (step / reference[k])  # per relative change
    anchor = members[int(np.argmax(norms[members]))]  # the largest effect held, the others follow it
    others = [k for k in members if k != anchor]
    walked = np.inf
    for _ in range(WALKS):
        moved = x + PROBE * direction * reference
        if np.any(moved < lower) or np.any(moved > upper):
            break
        residual = problem.residuals(moved)
        walked = min(walked, float(residual @ residual) - cost)
        correction = np.linalg.lstsq(np.column_stack([secants[k] for k in others]), -residual, rcond=None)[0]
        direction[others] += correction / PROBE
    if not np.isfinite(walked):
        return {}
    out = {}
    for k in members:
        # |rise|: a fit stopped short of the minimum may find the cost falling along the valley
        if own[k] > 0 and abs(walked) < INDEPENDENT**2 * own[k]:
            out[k] = (float(np.sqrt(abs(walked) / own[k])), tuple(m for m in members if m != k))
    log.info("fit: the least-seen direction %s raises Σr² by %.3g; compensated: %s",
             ", ".join(f"{problem.parameters[k].name} {direction[k]:+.2f}" for k in members), walked,
             ", ".join(problem.parameters[k].name for k in out) or "none")
    return out


def _probe(problem: Problem, x: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray | None,
                                                                                                np.ndarray]:
    """The best point ``PROBE`` up or down one parameter from ``x`` whose cost is lower than ``x``'s (or None), and
    which parameters have such a probe."""
    base = problem.residuals(x)
    best, best_cost = None, 0.5 * float(base @ base) * (1.0 - 1e-6)
    threshold = best_cost
    lowering = np.zeros(len(problem.parameters), dtype=bool)
    for j, p in enumerate(problem.parameters):
        step = PROBE * max(abs(x[j]), p.scale * IDENTIFIABLE)
        for sign in (1.0, -1.0):
            moved = x.copy()
            moved[j] = np.clip(x[j] + sign * step, lower[j], upper[j])
            if moved[j] == x[j]:
                continue
            residual = problem.residuals(moved)
            cost = 0.5 * float(residual @ residual)
            lowering[j] |= cost < threshold
            if cost < best_cost:
                best, best_cost = moved, cost
    return best, lowering


def uncertainty(residual: np.ndarray, jacobian: np.ndarray, scale: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One standard deviation of each parameter and the singular values (module docstring)."""
    m, n = jacobian.shape
    s2 = float(residual @ residual) / max(m - n, 1) * CORRELATION_CYCLES
    scaled = jacobian * scale  # columns per typical size
    _, singular, vt = np.linalg.svd(scaled, full_matrices=False)
    seen = singular > SINGULAR * (singular[0] if len(singular) else 1.0)
    sigma = np.zeros(n)
    for k in range(n):
        share = vt[:, k]
        if np.any(~seen & (np.abs(share) > 1e-6)):
            sigma[k] = np.inf
        else:
            sigma[k] = np.sqrt(s2 * np.sum((share[seen] / singular[seen]) ** 2)) * scale[k]
    return sigma, singular
