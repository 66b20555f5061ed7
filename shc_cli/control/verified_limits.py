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


def trial_shares(robot: Robot, gait: Gait) -> SpeedShares:
    """Bisect each bearing's (and turning's) share until its trial walk is clean."""
    from shc_cli.control.controller import Command, Controller, RobotState

    unit = robot.walker.velocity_input_mode == "throttle"
    base = Controller(robot, gait, speed_shares=lambda _: UNCHANGED)
    for _ in range(START_UP_CYCLES):
        if base.state == RobotState.RUNNING:
            break
        base.step(Command(state_request=RobotState.RUNNING))
    else:
        return UNCHANGED  # never runs: nothing to verify (validate reports why)
    assert base.walker is not None
    openshc = base.walker.limits
    period = base.cycle.period

    def clean(velocity: tuple[float, float, float], shares: SpeedShares) -> bool:
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

    def bisect(test: Callable[[float], bool]) -> float:
        if test(1.0):
            return 1.0
        low, high = 0.0, 1.0
        for _ in range(BISECTION_STEPS):
            middle = 0.5 * (low + high)
            low, high = (middle, high) if test(middle) else (low, middle)
        return low

    linear: dict[int, float] = {}
    keys = sorted(openshc.bearings)
    step = keys[1] - keys[0]
    for bearing, lim in sorted(openshc.bearings.items()):
        if bearing == 360 or lim.linear_speed <= 0.0:
            continue
        scale = 1.0 if unit else 2.0 * lim.linear_speed  # 'real' inputs: beyond the limit, which caps them
        # the walker reads bearing b's limits for every direction from b up to the next bearing: try three of them
        angles = [math.radians(bearing + step * k / SECTOR_SAMPLES) for k in range(SECTOR_SAMPLES)]
        velocities = [(scale * math.cos(a), scale * math.sin(a), 0.0) for a in angles]
        linear[bearing] = bisect(_partial_trial(clean, velocities, bearing))
    linear[360] = linear.get(0, 1.0)
    turn = 1.0 if unit else 2.0 * max(lim.angular_speed for lim in openshc.bearings.values())
    angular = bisect(lambda s: all(clean((0.0, 0.0, sign * turn), SpeedShares({}, s)) for sign in (1.0, -1.0)))
    return SpeedShares(linear, angular)


def _partial_trial(clean: Callable[[tuple[float, float, float], SpeedShares], bool],
                   velocities: list[tuple[float, float, float]], bearing: int) -> Callable[[float], bool]:
    """The trial of one bearing at a share: every one of its directions walks clean."""
    return lambda share: all(clean(v, SpeedShares({bearing: share}, 1.0)) for v in velocities)


def source_for(robot: Robot) -> ShareSource | None:
    """The controller's share source for ``robot``: verified when its file asks for it, else None (OpenSHC's)."""
    if not robot.walker.verify_speed_limits:
        return None
    return lambda gait: verified_shares(robot, gait)


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
