"""Speed limits the legs can really walk: OpenSHC's walkspace limits checked by trial walks (an shc deviation).

OpenSHC derives its speed limits from the walkspace alone (:mod:`shc_cli.control.limits`). On a 5-DOF leg its one
DLS step per cycle with null-space limit avoidance lets the redundant joint drift during long walks, so a robot can
reach its walkspace at start and still walk onto a joint limit after some seconds at full speed (the default robot
``bullet`` above half throttle, issue 42). A robot file that sets ``walker.verify_speed_limits`` has its limits
checked here: per bearing (the walkspace's, 0°…315°: three directions from it to the next one, which OpenSHC
reads its limits for) and for turning, the controller alone walks
:data:`TRIAL_STEP_CYCLES` step cycles from its running stance at the limit; when a cycle of it commands a joint
within :data:`PROXIMITY_MARGIN` of a position limit (OpenSHC's limit proximity), misses an IK target, clamps a
joint or has its speed guarded, that bearing's limit is scaled down by bisection (:data:`BISECTION_STEPS` halvings)
until the trial is clean. The shares scale the linear (per bearing) and angular (all bearings) speed and
acceleration limits of the gait at the robot's default step frequency (a run-time step-frequency change keeps them).

The result is a pure function of the robot, the gait and this code: it is kept for the process and in a cache
file (``$SHC_CACHE_DIR`` or ``~/.cache/shc``, ``verified-limits/<key>.json``, the key a hash of both specs and the
control and model sources), so a run pays for it once per robot, gait and install.
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.control.speed_shares import UNCHANGED as UNCHANGED
from shc_cli.control.speed_shares import ShareSource
from shc_cli.control.speed_shares import SpeedShares as SpeedShares

if TYPE_CHECKING:
    from shc_cli.control.controller import Controller
    from shc_cli.control.limits import Limits
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

TRIAL_STEP_CYCLES = 25
"""Step cycles each trial walks at the limit (bullet's tripod drifts onto its roll limit after ≈ 15 at 0.6)."""
PROXIMITY_MARGIN = 0.05
"""Smallest limit proximity a trial may command (0 = a joint at a limit, 1 = every joint centred)."""
BISECTION_STEPS = 5
"""Halvings of a failed bearing's share (resolution 1/32)."""
START_UP_CYCLES = 20000
"""Give up bringing a trial robot to RUNNING after this many cycles."""
SECTOR_SAMPLES = 3
"""Directions tried per bearing b: b, b + step/3, b + 2·step/3 (OpenSHC reads b's limits up to the next bearing)."""
VERSION = 2
"""Bumped when the trial's rules change (part of the cache key)."""


_memo: dict[str, SpeedShares] = {}


def verified_shares(robot: Robot, gait: Gait) -> SpeedShares:
    """The verified shares of ``robot`` walking ``gait`` (from the process's memo, the cache file or trials)."""
    key = cache_key(robot, gait)
    if key in _memo:
        return _memo[key]
    path = _cache_dir() / f"{key}.json"
    shares = _read(path)
    if shares is None:
        log.info("verifying %s's speed limits in %s by trial walks (once per robot, gait and install)",
                 robot.name, gait.name)
        shares = trial_shares(robot, gait)
        _write(path, shares)
    _memo[key] = shares
    return shares


def cache_key(robot: Robot, gait: Gait) -> str:
    """Hash of both specs, the trial's rules and the control and model sources (their sizes and times)."""
    digest = hashlib.sha256()
    digest.update(f"v{VERSION} {TRIAL_STEP_CYCLES} {PROXIMITY_MARGIN} {BISECTION_STEPS} {SECTOR_SAMPLES}".encode())
    digest.update(robot.model_dump_json().encode())
    digest.update(gait.model_dump_json().encode())
    package = Path(__file__).resolve().parent.parent
    for folder in ("control", "model"):
        for source in sorted((package / folder).glob("*.py")):
            stat = source.stat()
            digest.update(f"{source.name} {stat.st_size} {stat.st_mtime_ns}".encode())
    return digest.hexdigest()[:32]


Velocity = tuple[float, float, float]
Clean = Callable[[Velocity, SpeedShares], bool]


def _trial(robot: Robot, gait: Gait) -> tuple[Clean, Limits, bool] | None:
    """The trial walk ``clean(velocity, shares)``, OpenSHC's limits and whether inputs are throttles; None when the
    robot never reaches RUNNING (nothing to verify: validate reports why)."""
    from shc_cli.control.controller import Command, Controller, RobotState

    unit = robot.walker.velocity_input_mode == "throttle"
    base = Controller(robot, gait, speed_shares=lambda _: UNCHANGED)
    for _ in range(START_UP_CYCLES):
        if base.state == RobotState.RUNNING:
            break
        base.step(Command(state_request=RobotState.RUNNING))
    else:
        return None
    assert base.walker is not None
    openshc = base.walker.limits
    period = base.cycle.period

    def clean(velocity: Velocity, shares: SpeedShares) -> bool:
        trial = copy.deepcopy(base)
        trial.speed_shares = lambda _: shares
        trial.walker.set_cycle(trial.cycle, shares.apply(openshc))  # type: ignore[union-attr]
        chains = trial.model.chains
        half = (chains.upper - chains.lower) / 2.0
        moving = half > 0.0
        for _ in range(TRIAL_STEP_CYCLES * period):
            out = trial.step(Command(velocity=velocity))
            if out.ik_deviations or out.ik_clamped or out.joint_speed_limited:
                return False
            near = np.minimum(out.joints - chains.lower, chains.upper - out.joints)
            if np.any(near[moving] < PROXIMITY_MARGIN * half[moving]):
                return False
        return True

    return clean, openshc, unit


def _directions(openshc: Limits, unit: bool) -> tuple[dict[int, list[Velocity]], list[Velocity]]:
    """The trial velocities of each bearing (three directions of its sector) and of turning (both ways)."""
    keys = sorted(openshc.bearings)
    step = keys[1] - keys[0]
    linear: dict[int, list[Velocity]] = {}
    for bearing, lim in sorted(openshc.bearings.items()):
        if bearing == 360 or lim.linear_speed <= 0.0:
            continue
        scale = 1.0 if unit else 2.0 * lim.linear_speed  # 'real' inputs: beyond the limit, which caps them
        # the walker reads bearing b's limits for every direction from b up to the next bearing: try three of them
        angles = [math.radians(bearing + step * k / SECTOR_SAMPLES) for k in range(SECTOR_SAMPLES)]
        linear[bearing] = [(scale * math.cos(a), scale * math.sin(a), 0.0) for a in angles]
    turn = 1.0 if unit else 2.0 * max(lim.angular_speed for lim in openshc.bearings.values())
    return linear, [(0.0, 0.0, turn), (0.0, 0.0, -turn)]


def failing_directions(robot: Robot, gait: Gait, shares: SpeedShares) -> list[Velocity]:
    """The trial velocities whose walk at ``shares`` is not clean (empty: every bearing and turning walks clean)."""
    trial = _trial(robot, gait)
    if trial is None:
        return []
    clean, openshc, unit = trial
    linear, turning = _directions(openshc, unit)
    return [v for velocities in linear.values() for v in velocities if not clean(v, shares)] + [
        v for v in turning if not clean(v, shares)]


def trial_shares(robot: Robot, gait: Gait) -> SpeedShares:
    """Bisect each bearing's (and turning's) share until its trial walk is clean."""
    trial = _trial(robot, gait)
    if trial is None:
        return UNCHANGED  # never runs: nothing to verify (validate reports why)
    clean, openshc, unit = trial

    def bisect(test: Callable[[float], bool]) -> float:
        if test(1.0):
            return 1.0
        low, high = 0.0, 1.0
        for _ in range(BISECTION_STEPS):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if test(middle) else (low, middle)
        return low

    directions, turning = _directions(openshc, unit)
    linear = {bearing: bisect(_partial_trial(clean, velocities, bearing)) for bearing, velocities in directions.items()}
    linear[360] = linear.get(0, 1.0)
    angular = bisect(lambda s: all(clean(v, SpeedShares({}, s)) for v in turning))
    return SpeedShares(linear, angular)


def _partial_trial(clean: Clean, velocities: list[Velocity], bearing: int) -> Callable[[float], bool]:
    """The trial of one bearing at a share: every one of its directions walks clean."""
    return lambda share: all(clean(v, SpeedShares({bearing: share}, 1.0)) for v in velocities)


def source_for(robot: Robot) -> ShareSource | None:
    """The controller's share source for ``robot``: verified by trials when its file asks for it, else the shares
    its file keeps (:func:`stored_shares`), else None (OpenSHC's limits)."""
    if robot.walker.verify_speed_limits:
        return lambda gait: verified_shares(robot, gait)
    if robot.walker.speed_shares:
        kept: dict[str, tuple[Gait, SpeedShares]] = {}

        def stored(gait: Gait) -> SpeedShares:
            known = kept.get(gait.name)
            if known is None or known[0] is not gait:
                known = kept[gait.name] = (gait, stored_shares(robot, gait))
            return known[1]
        return stored
    return None


def fingerprint(robot: Robot, gait: Gait) -> str:
    """What stored shares were verified for: a hash of the robot's name, control period, legs (geometry, joint
    limits and speeds, stance) and IK, of the gait and of the trial's rules. Not of the walker's parameters: like
    verified limits, stored shares are kept through a change of step frequency, heights or clearance (a sweep's
    or a study's); a robot file that extends this one (another name), new legs, another IK or another gait has
    other limits and walks OpenSHC's until its own shares are verified."""
    digest = hashlib.sha256()
    digest.update(f"v{VERSION} {TRIAL_STEP_CYCLES} {PROXIMITY_MARGIN} {BISECTION_STEPS} {SECTOR_SAMPLES}".encode())
    digest.update(robot.model_dump_json(include={"name", "time_delta", "legs", "ik"}).encode())
    digest.update(gait.model_dump_json().encode())
    return digest.hexdigest()[:16]


def stored_shares(robot: Robot, gait: Gait) -> SpeedShares:
    """The shares ``robot``'s file keeps for ``gait`` (``walker.speed_shares``), or OpenSHC's limits when it keeps
    none for that gait or they were verified for another robot or gait (their fingerprint differs: logged)."""
    entry = robot.walker.speed_shares.get(gait.name)
    if entry is None:
        return UNCHANGED
    if entry.fingerprint != fingerprint(robot, gait):
        log.info("%s's stored speed shares for %s were verified for another robot or gait (fingerprint %s, now %s):"
                 " OpenSHC's limits are used", robot.name, gait.name, entry.fingerprint, fingerprint(robot, gait))
        return UNCHANGED
    linear = {int(bearing): share for bearing, share in entry.linear.items()}
    linear[360] = linear.get(0, 1.0)
    return SpeedShares(linear, entry.turn)


def shares_table(robot: Robot, gait: Gait, shares: SpeedShares) -> str:
    """``shares`` as the robot file's ``[walker.speed_shares.<gait>]`` table (TOML)."""
    linear = ", ".join(f'"{b}" = {s:.5f}' for b, s in sorted(shares.linear.items()) if b != 360)
    return (f"[walker.speed_shares.{gait.name}]\nlinear = {{ {linear} }}\nturn = {shares.angular:.5f}\n"
            f'fingerprint = "{fingerprint(robot, gait)}"\n')


def _cache_dir() -> Path:
    root = os.environ.get("SHC_CACHE_DIR")
    return (Path(root) if root else Path.home() / ".cache" / "shc") / "verified-limits"


def _read(path: Path) -> SpeedShares | None:
    try:
        data = json.loads(path.read_text())
        return SpeedShares({int(b): float(s) for b, s in data["linear"].items()}, float(data["angular"]))
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _write(path: Path, shares: SpeedShares) -> None:
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_text(json.dumps({"linear": {str(b): s for b, s in shares.linear.items()},
                                         "angular": shares.angular}))
        temporary.replace(path)
    except OSError as error:  # a read-only home: verify again next time
        log.debug("could not cache the verified speed limits in %s: %s", path, error)


def controller_shares(controller: Controller) -> dict[str, float] | None:
    """What a run's summary records: the reduced shares of the controller's gait, or None when not verified."""
    if controller.speed_shares is None:
        return None
    return controller.speed_shares(controller.gait).reduced
