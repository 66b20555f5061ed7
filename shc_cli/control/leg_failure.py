"""Walking on when legs have failed (issue 39): declared failures, from the start of a run or mid-walk.

A failure is declared per leg, ``LEG[:MODE][@T]`` (:func:`parse_failures`; ``@T``: ``T`` seconds after walking
starts, when the controller changes to the re-planned gait as it changes gaits):

* ``retracted`` (default): the leg is folded clear of the ground and held there (the set-up of Mailer et al.,
  GECCO 2021: coxa 0°, femur up, tibia folded). In shc's joint convention the pose is the first joint at 0
  (clamped into its limits) and the others at the values, within their limits, that lift the tip highest in
  base_link (:func:`retracted_pose`: a grid search, the same rule for any leg geometry). It is held from the
  first cycle, so the robot starts up on the legs that are left.
* ``locked``: the joints are held where they are when walking begins (after the start-up, which the leg still
  takes part in); its foot may stay on the ground and drag.

:func:`adapt` re-plans the robot for the legs left, with no trials: the walkspace of the walking legs gives the
stride, :func:`~shc_cli.control.gait_planner.plan_gait` the fastest phase table that keeps a static margin over
the cycle with one constant body shift, else with the body swaying through the cycle
(:func:`~shc_cli.control.gait_planner.sway_path`); where no table holds on the robot's own stance the planner
moves the stance positions of the legs left. :class:`LegFailure` is the controller's collaborator: it drops the
failed legs from the walkspace (so the speed limits are those of the walking legs), holds their joints at the held
pose at the end of every cycle (:meth:`LegFailure.hold`) and shifts the posed tips by the sway at the walker's
phase (:meth:`LegFailure.posed`, :func:`walk_phase`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial import ConvexHull, QhullError

from shc_cli.control import stepping
from shc_cli.control.gait import step_cycle
from shc_cli.control.gait_planner import GaitPlanningError, PlannedGait, plan_gait, stance_tips, sway_at, sway_path
from shc_cli.control.limits import generate_limits
from shc_cli.control.states import WalkState
from shc_cli.control.walk import WalkController
from shc_cli.errors import Issue, SpecError
from shc_cli.model.chains import Chains, FloatArray
from shc_cli.model.ik import solve
from shc_cli.model.workspace import Workplane, search_workspaces, walkspace
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import Robot

MODES = ("retracted", "locked")
"""The failure modes so far (``limp``, ``missing`` and ``short`` are not done)."""
GRID_POINTS = 20000
"""Grid points of the retracted-pose search (per joint: the ``(n − 1)``-th root, at least 5)."""
STRIDE_SHARES = (1.0, 0.75, 0.5, 0.35, 0.25)
"""Shares of the walking legs' walkspace stride tried in turn until a generated table holds."""
MIN_MARGIN_M = 0.02
"""The static margin the re-planned gait keeps at every instant [m]."""
SWAY_STRIDE_SHARES = (0.0, 0.5, 1.0)
"""Shares of the planned stride the body sway must hold the margin for at once (the walker ramps its stride)."""
SWAY_RATE_SHARE = 2.0
"""Fastest the body sways, relative to a stance foot's speed at the planned stride."""
SHIFT_RATE_MPS = 0.05
"""Fastest the body shift moves towards the sway when the sway itself moves slower (walker stopped) [m/s]."""


@dataclass(frozen=True)
class FailedLeg:
    """One declared failure: the leg id, its mode (one of :data:`MODES`) and when it is declared (seconds after
    walking starts; ``None``: from the start of the run)."""

    leg: str
    mode: str = "retracted"
    at_s: float | None = None

    def __str__(self) -> str:
        return f"{self.leg}:{self.mode}" + ("" if self.at_s is None else f"@{self.at_s:g}")


def _bad(spec: str, problem: str, fix: str) -> SpecError:
    return SpecError([Issue(None, None, "--fail-leg", f"{spec!r}: {problem}", fix)])


def parse_failures(specs: Sequence[str], legs: Sequence[str]) -> tuple[FailedLeg, ...]:
    """``LEG[:MODE][@T]`` specs (each may also be a comma-separated list) → failures, checked against ``legs``.

    Raises:
        SpecError: an unknown leg or mode, a leg given twice, or fewer than three legs left (one line each).
    """
    failed: list[FailedLeg] = []
    for spec in (part.strip() for text in specs for part in text.split(",") if part.strip()):
        body, at, when = spec.partition("@")
        leg, _, mode = body.partition(":")
        mode = mode or "retracted"
        at_s: float | None = None
        if at:
            try:
                at_s = float(when)
            except ValueError:
                at_s = math.nan
            if not math.isfinite(at_s) or at_s < 0.0:
                raise _bad(spec, f"@{when!r} is not a time", "give seconds after walking starts, e.g. BR@5")
        if leg not in legs:
            raise _bad(spec, f"no leg {leg!r} on this robot", f"give one of {', '.join(legs)}")
        if mode not in MODES:
            raise _bad(spec, f"unknown mode {mode!r}", f"give {' or '.join(f'{leg}:{m}' for m in MODES)}")
        if any(f.leg == leg for f in failed):
            raise _bad(spec, f"leg {leg} is failed twice", "give each leg once")
        failed.append(FailedLeg(leg, mode, at_s))
    if len({f.at_s for f in failed}) > 1:
        raise _bad(",".join(map(str, failed)), "legs failed at different times",
                   "give every leg the same @T (or none)")
    if len(legs) - len(failed) < 3:
        raise _bad(",".join(map(str, failed)), f"{len(legs) - len(failed)} leg(s) left",
                   "a statically stable gait needs at least three: fail fewer legs")
    return tuple(failed)


def retracted_pose(chains: Chains, index: int) -> FloatArray:
    """The retracted pose of leg ``index``: joint 0 at 0 (clamped into its limits), the other joints the grid point
    within their limits that puts the tip highest in base_link, ``(n,)`` [rad] (padding joints stay 0)."""
    count = int(chains.joint_count[index])
    lower, upper = chains.lower[index], chains.upper[index]
    axes = [np.array([min(max(0.0, lower[0]), upper[0])])]
    per_joint = max(5, int(GRID_POINTS ** (1.0 / max(count - 1, 1))))
    axes += [np.linspace(lower[j], upper[j], per_joint) for j in range(1, count)]
    grid = np.array(list(itertools.product(*axes)))
    q = np.zeros((len(grid), chains.d.shape[1]))
    q[:, :count] = grid
    tips = chains.take(np.full(len(grid), index, dtype=np.int64)).tips(q)
    return np.asarray(q[int(np.argmax(tips[:, 2]))], dtype=float)


class LegFailure:
    """The controller's collaborator for failed legs (pure: no I/O).

    Args:
        failed: the failures.
        chains: the robot's legs (:class:`~shc_cli.model.chains.Chains`, legs in id order).
    """

    def __init__(self, failed: Sequence[FailedLeg], chains: Chains) -> None:
        self.failed = tuple(failed)
        self.chains = chains
        names = list(chains.names)
        self.index = np.array([names.index(f.leg) for f in self.failed], dtype=np.int64)
        self.poses: dict[int, FloatArray] = {
            i: retracted_pose(chains, i) for i, f in zip(self.index, self.failed, strict=True) if f.mode == "retracted"}
        self._locked = [int(i) for i, f in zip(self.index, self.failed, strict=True) if f.mode == "locked"]
        self._held = chains.take(self.index)
        self.stride_share = 1.0
        """The share of the walking legs' walkspace the re-planned gait holds for (the speed limits' share)."""
        self.at_s = self.failed[0].at_s if self.failed else None
        """When the failures are declared, seconds after walking starts (``None``: from the start of the run)."""
        self.gait: Gait | None = None
        """The re-planned gait the controller changes to when the failures are declared mid-walk."""
        self.sway = np.zeros((1, 2))
        """The body's sway over the legs left through one gait cycle, ``(K, 2)`` [m] (samples evenly over the
        cycle from the first group's lift-off: :func:`~shc_cli.control.gait_planner.sway_path`)."""
        self.shift = np.zeros(2)
        """The body's current shift (x, y) in the walk plane [m]: the sway at the walker's phase, reached at no more
        than the sway's own speed (or :data:`SHIFT_RATE_MPS`) from where it is."""
        self.max_step_m = 0.0
        """Largest move of :attr:`shift` in one control cycle [m] (set with the sway)."""

    @property
    def legs(self) -> tuple[str, ...]:
        """The failed legs' ids."""
        return tuple(f.leg for f in self.failed)

    def walking(self, planes: Mapping[str, Workplane]) -> dict[str, Workplane]:
        """The workplanes of the legs that walk (the walkspace, hence the speed limits, is theirs alone)."""
        share = self.stride_share
        return {leg: {bearing: radius * share for bearing, radius in plane.items()}
                for leg, plane in planes.items() if leg not in self.legs}

    def hold(self, joints: FloatArray, running: bool) -> FloatArray | None:
        """The joints ``(L, n)`` with every failed leg at its held pose (``None``: nothing held yet). A ``locked``
        leg is captured from ``joints`` the first cycle walking runs (``running``)."""
        if running:
            for i in self._locked:
                if i not in self.poses:
                    self.poses[i] = np.array(joints[i], dtype=float)
        if not self.poses:
            return None
        held = np.array(joints, dtype=float)
        for i, pose in self.poses.items():
            held[i] = pose
        return held

    def set_sway(self, sway: FloatArray, period: int, time_delta: float) -> None:
        """Use ``sway`` (``(K, 2)`` [m] over a cycle of ``period`` control cycles of ``time_delta`` [s]); the shift
        may move per cycle 1.5 × as far as the sway does between two samples spread over their cycles, and at
        least :data:`SHIFT_RATE_MPS`."""
        self.sway = np.asarray(sway, dtype=float)
        steps = np.abs(np.roll(self.sway, -1, axis=0) - self.sway).max() if len(self.sway) > 1 else 0.0
        self.max_step_m = max(1.5 * float(steps) * len(self.sway) / max(period, 1), SHIFT_RATE_MPS * time_delta)

    def posed(self, tips: FloatArray, phase: float | None) -> FloatArray:
        """Posed tips ``(L, 3)`` (base_link) with the body shifted by :attr:`shift` (the tips move by its
        opposite): the shift moves towards the sway at ``phase`` of the gait cycle (the walker's; ``None``: not
        walking, the sway where walking starts), by at most :attr:`max_step_m`."""
        target = sway_at(self.sway, 0.0 if phase is None else phase)
        step = target - self.shift
        distance = float(np.abs(step).max())
        if distance > self.max_step_m:
            step *= self.max_step_m / distance
        self.shift = self.shift + step
        moved = np.array(tips, dtype=float)
        moved[:, :2] -= self.shift
        return moved

    def active(self) -> np.ndarray | None:
        """The legs the IK steps, ``(L,)`` bool: all but the held ones (``None``: all)."""
        if not self.poses:
            return None
        mask = np.ones(self.chains.size, dtype=bool)
        mask[list(self.poses)] = False
        return mask

    def tips(self, joints: FloatArray) -> FloatArray:
        """The failed legs' tips at ``joints`` ``(L, n)``, ``(F, 3)`` (base_link) [m]."""
        return self._held.tips(joints[self.index])


def walk_phase(walker: WalkController | None) -> float | None:
    """The walker's place in its gait cycle ∈ [0, 1) (0: the phase every leg starts walking from, when the first
    group of a generated table lifts off), ``None`` when it is stopped: every leg's phase less its offset is the
    same once walking starts (they all start at their offset and advance together)."""
    if walker is None or walker.state == WalkState.STOPPED:
        return None
    integers = walker.legs.integers
    period = walker.cycle.period
    return float((int(integers[0, stepping.PHASE]) - int(integers[0, stepping.OFFSET])) % period) / period


def margin_at(planned: PlannedGait, shift: FloatArray, stride_m: float, heading_rad: float = 0.0) -> float:
    """The worst static margin over ``planned``'s cycle with the centre of mass at ``shift`` (x, y) [m] (the
    planner's margin is this at its own shift; ``-inf`` with fewer than three stance feet)."""
    swing = planned.gait.swing_phase * len(planned.groups) / planned.gait.base_length
    worst = math.inf
    for feet in stance_tips(planned.stance, planned.groups, swing, stride_m, heading_rad):
        if len(feet) < 3:
            return -math.inf
        try:
            equations = ConvexHull(feet).equations  # outward normal·x + offset ≤ 0 inside
        except QhullError:  # collinear feet: no area
            return -math.inf
        worst = min(worst, float(np.min(-(equations[:, :2] @ shift + equations[:, 2]))))
    return worst


@dataclass(frozen=True)
class Adapted:
    """A robot re-planned for its failed legs.

    Attributes:
        robot: the robot with the walking legs' stance positions moved (body shift and redistribution).
        gait: the generated gait (the failed legs carry multiplier 0; their joints are held anyway).
        failure: the controller's collaborator.
        planned: what the planner chose (margin, shift, duty factor).
        stride_m: the stride the plan holds for (the walkspace of the walking legs along the heading) [m].
    """

    robot: Robot
    gait: Gait
    failure: LegFailure
    planned: PlannedGait
    stride_m: float


def _plan(stance: Mapping[str, tuple[float, float]], legs: Sequence[str], stride_m: float, heading_rad: float,
          reach_m: float, failed: Sequence[FailedLeg]) -> tuple[PlannedGait, float, FloatArray]:
    """The gait for the longest share of ``stride_m`` (:data:`STRIDE_SHARES`) a generated table and a body sway
    (:func:`~shc_cli.control.gait_planner.sway_path`) hold for; the stance positions are only moved (``reach_m``,
    a slow greedy search) at the shortest share."""
    for share in STRIDE_SHARES:
        for sway in (False, True):  # one constant shift where it holds (a steadier walk), else a sway
            try:
                planned = plan_gait(stance, legs, stride_m * share, heading_rad, MIN_MARGIN_M, name="planned",
                                    sway=sway, reach_m=reach_m if share == STRIDE_SHARES[-1] else 0.0)
            except GaitPlanningError:
                continue
            path = sway_path(planned, stride_m * share, heading_rad, MIN_MARGIN_M, SWAY_STRIDE_SHARES,
                             SWAY_RATE_SHARE if sway else 0.0, reach_m)
            if path is not None:
                return planned, share, path
    raise _bad(",".join(map(str, failed)), f"no generated gait and body sway keep a {MIN_MARGIN_M:g} m static "
               f"margin on legs {', '.join(legs)}, down to {STRIDE_SHARES[-1]:g} of their stride",
               "fail fewer legs")


def adapt(robot: Robot, failed: Sequence[FailedLeg], heading_rad: float = 0.0) -> Adapted:
    """Re-plan ``robot`` for the legs left after ``failed`` (see the module).

    Raises:
        SpecError: no generated gait keeps the margin for these legs (one line).
    """
    chains = Chains.from_robot(robot)
    stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}
    clearance = robot.walker.body_clearance
    identity = np.array([[x, y, -clearance] for x, y in stance.values()])
    standing, _ = solve(chains, chains.default_joints(), identity)  # the walkspace is searched from the stance
    planes = search_workspaces(chains, standing, identity, robot.time_delta).planes
    failure = LegFailure(failed, chains)
    legs = [leg for leg in robot.legs if leg not in failure.legs]
    space = walkspace(failure.walking(planes), stance, robot.walker.overlapping_walkspaces)
    bearing = round(math.degrees(heading_rad) / 45.0) * 45 % 360
    reach = min(min(plane.values()) for plane in failure.walking(planes).values())
    stride = 2.0 * space[bearing]  # OpenSHC's largest stride; the limits scale it down for the gait's timing
    for _ in range(3):  # the stride the walker will take with the gait chosen for it (a fixed point)
        planned, share, sway = _plan(stance, legs, stride, heading_rad, reach, failed)
        gait = planned.gait.model_copy(update={"offset_multiplier": {
            leg: planned.gait.offset_multiplier.get(leg, 0) for leg in robot.legs}})
        cycle = step_cycle(gait, robot.walker.step_frequency.default, robot.time_delta)
        first = next(iter(stance.values()))
        limits = generate_limits({b: r * share for b, r in space.items()}, cycle, robot.time_delta,
                                 math.hypot(*first))
        walked = 2.0 * limits.bearings[bearing].scaled_radius
        failure.stride_share = share
        if abs(walked - stride * share) < 1e-3:
            break
        stride = walked / share
    stride *= share
    swaying = bool(np.ptp(sway, axis=0).max() > 0.0)
    failure.gait = gait
    relocated = any(planned.stance[leg] != stance[leg] for leg in legs)
    if failure.at_s is not None and relocated:
        raise _bad(",".join(map(str, failed)), "the legs left only walk with their stance positions moved",
                   "fail these legs from the start (drop @T)")
    walked_sway = sway_path(planned, stride, heading_rad, MIN_MARGIN_M, SWAY_STRIDE_SHARES,
                            SWAY_RATE_SHARE if swaying else 0.0, reach)  # at the stride walked
    failure.set_sway(sway if walked_sway is None else walked_sway, cycle.period, robot.time_delta)
    legs_spec = {}
    for leg, spec in robot.legs.items():
        x, y = planned.stance.get(leg, stance[leg])
        moved = spec.stance.model_copy(update={"x": float(x), "y": float(y)})
        legs_spec[leg] = spec.model_copy(update={"stance": moved})
    return Adapted(robot.model_copy(update={"legs": legs_spec}), gait, failure, planned, stride)
