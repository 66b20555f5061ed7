"""The robot-state requests of a recorded run, inferred from the data so that stalls do not shift them.

OpenSHC counts cycles, not seconds: its start-up takes ``time_to_start / time_delta`` cycles however long they
last. But when it enters RUNNING depends on more than the start-up's length: the Bullet mammalian recording holds
the start-up's last pose for five cycles after a ~52 ms stall (the cycle that generates the workspaces) and starts
walking at cycle 507, not at 502. Requesting RUNNING five cycles early puts the 5-DOF legs into another redundant
posture (joints up to 32 mrad apart for ~15 s, tips still equal). So the requests follow what the data shows:

* the start-up (PACKED → READY) is requested in the cycle of the first joint motion (for the direct start-up,
  up to two cycles earlier when the fit of its cubic move shows that printed decimals hid its beginning);
* RUNNING is requested in the first cycle, at least a start-up's length later, that shows the robot RUNNING: its
  joints move again, or a leg reports a stance or swing progress (LegState; −1 outside RUNNING);
* later, the recorded ``/syropod_remote/robot_state`` requests (when the source holds them) with the input latency.

Until RUNNING the request is held at READY, so the controller waits however long the recording waited. With the
start-up *sequence* (``start_up.sequence``) RUNNING is requested at the first motion (its length depends on the
joints, so no plateau can be located from the data; see docs/migrating-from-openshc.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from shc_cli.control.controller import RobotState
from shc_cli.control.startup import iterations
from shc_cli.errors import ShcError
from shc_cli.replay.source import Recorded, usable
from shc_cli.spec.robot import Robot

INPUT_LATENCY_CYCLES = 1
"""Cycles between the recorder seeing an input and OpenSHC using it (OpenSHC reads its topics after publishing;
measured at all five velocity changes of the insectoid recording)."""


@dataclass(frozen=True)
class StatePlan:
    """Per-cycle state requests and where they came from.

    Attributes:
        requests: the request sent in each cycle (``None``: none), ``(N,)``.
        first_motion: cycle of the start-up's first joint motion, or ``None`` if the joints never move.
        running: cycle in which RUNNING is requested, or ``None`` if the data never shows RUNNING.
        evidence: what showed RUNNING (``"joints move"``, ``"leg progress"``) or ``""``.
        later: cycles of later requests taken from the recorded robot-state input.
    """

    requests: list[RobotState | None]
    first_motion: int | None
    running: int | None
    evidence: str
    later: list[tuple[int, RobotState]]

    def describe(self) -> str:
        """One line for the report."""
        if self.first_motion is None:
            return "states: the joints never move (no start-up requested)"
        text = f"states: start-up from cycle {self.first_motion} (first joint motion)"
        if self.running is None:
            text += ", RUNNING never shown"
        else:
            text += f", RUNNING from cycle {self.running} ({self.evidence})"
        for cycle, state in self.later:
            text += f", {state.name} requested at cycle {cycle}"
        return text


def moving(joints: np.ndarray) -> np.ndarray:
    """Per cycle: did any joint change since the previous cycle (``(N,)``, False for cycle 0)? Values that are not
    usable (non-finite, absurd) are ignored."""
    ok = usable(joints)
    out = np.zeros(len(joints), dtype=bool)
    if len(joints) > 1:
        both = ok[1:] & ok[:-1]
        out[1:] = (np.where(both, np.abs(joints[1:] - joints[:-1]), 0.0) > 0.0).any(axis=1)
    return out


def running_shown(recorded: Recorded) -> np.ndarray:
    """Per cycle: does a leg report a stance or swing progress (≥ 0; OpenSHC publishes −1 outside RUNNING)?"""
    if recorded.progress is None:
        return np.zeros(recorded.cycles, dtype=bool)
    progress = recorded.progress
    with np.errstate(invalid="ignore"):
        shown: np.ndarray = np.asarray((usable(progress) & (progress >= 0.0)).any(axis=(1, 2)))
    return shown


HIDDEN_START_CYCLES = 2
"""How many cycles the printed joints can hide the direct start-up's beginning (at 6 decimals a cubic move of less
than ~0.08 rad shows nothing in its first cycle, ~0.02 rad nothing in its first two)."""


def direct_start(joints: np.ndarray, first: int, steps: int) -> int:
    """The direct start-up's first cycle: the first visible motion, or up to :data:`HIDDEN_START_CYCLES` earlier when
    rounding hid the slow beginning of OpenSHC's cubic joint move ``q0 + Δ·(3u² − 2u³)``, ``u = k / steps`` in its
    ``k``-th cycle — whichever start fits the joint that moves most best (least squares)."""
    n = len(joints)
    q0 = joints[0]
    delta = np.where(usable(joints[min(first + steps - 1, n - 1)]) & usable(q0),
                     joints[min(first + steps - 1, n - 1)] - q0, 0.0)
    j = int(np.argmax(np.abs(delta)))
    if delta[j] == 0.0:
        return first

    def misfit(start: int) -> float:
        cycles = np.arange(start, min(start + steps, n))
        u = (cycles - start + 1) / steps
        predicted = q0[j] + delta[j] * (3.0 * u**2 - 2.0 * u**3)
        recorded = joints[cycles, j]
        ok = usable(recorded)
        return float(np.sum((recorded[ok] - predicted[ok]) ** 2))

    return min(range(max(1, first - HIDDEN_START_CYCLES), first + 1), key=lambda start: (misfit(start), -start))


def infer_states(recorded: Recorded, robot: Robot, latency: int = INPUT_LATENCY_CYCLES) -> StatePlan:
    """The state requests that reproduce the recorded run's state changes (module docstring)."""
    n = recorded.cycles
    requests: list[RobotState | None] = [None] * n
    if n == 0:
        return StatePlan(requests, None, None, "", [])
    shown = running_shown(recorded)
    if shown[0]:
        raise ShcError(f"{recorded.source}: the robot is already RUNNING in the first recorded cycle (its legs report "
                       "a stance or swing progress), so the replay cannot start where OpenSHC was (record from before "
                       "the controller starts up)")
    requests[0] = RobotState.RUNNING  # the remote's request: the controller estimates its state (UNKNOWN → PACKED)
    motion = moving(recorded.joints)
    first = int(np.argmax(motion)) if motion.any() else None
    if first is None:
        return StatePlan(requests, None, None, "", [])
    if robot.start_up.sequence:
        running: int | None = first
        evidence = "start-up sequence from the first motion"
        hold = RobotState.RUNNING
    else:
        steps = iterations(robot.start_up.time_to_start, robot.time_delta)
        first = direct_start(recorded.joints, first, steps)
        earliest = first + steps
        candidates = [(int(np.argmax(flags[earliest:])) + earliest, name)
                      for flags, name in ((motion, "joints move"), (shown, "leg progress"))
                      if flags[earliest:].any()]
        running, evidence = min(candidates) if candidates else (None, "")
        if len(candidates) == 2 and candidates[0][0] == candidates[1][0]:
            evidence = "joints move, leg progress"
        hold = RobotState.READY
    end = running if running is not None else n
    for cycle in range(first, end):
        requests[cycle] = hold
    later: list[tuple[int, RobotState]] = []
    if running is not None:
        current = RobotState.RUNNING
        for cycle in range(running, n):
            source = cycle - latency
            if recorded.robot_state is not None and source >= running:
                value = recorded.robot_state[source]
                if np.isfinite(value) and int(value) in (0, 1, 2) and int(value) != current:
                    current = RobotState(int(value))
                    later.append((cycle, current))
            requests[cycle] = current
    return StatePlan(requests, first, running, evidence, later)
