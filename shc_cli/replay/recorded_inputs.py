"""The controller's inputs for each cycle of a replay: the recorded velocity input and the inferred state requests.

A :class:`ReplayInputs` is a per-cycle command source: ``inputs.command(cycle)`` is what OpenSHC acted on in that
cycle, so any loop that steps a :class:`~shc_cli.control.controller.Controller` can replay a recording.

A recording says when each input *arrived* at the recorder, not in which cycle the controller consumed it: OpenSHC
reads its topics after publishing, so an input seen before a cycle's output is used one cycle later
(:data:`~shc_cli.replay.states.INPUT_LATENCY_CYCLES`), but a message that reaches the controller and a recorder
(two subscribers, e.g. ``rosbag record``) within a moment of a cycle's output can land on different sides of it in
each — and a recorder on a loaded machine stamps messages late, by tens of milliseconds. :func:`retime_changes`
settles each change of the velocity input from the data: of the cycle the latency gives and those up to
:data:`RETIME_RANGE` cycles either side (not past a neighbouring change), the one whose following cycles reproduce
the recorded joints; ties keep the nearest.
"""

from __future__ import annotations

import copy

import numpy as np

from shc_cli.control.controller import Command, Controller
from shc_cli.replay.source import Recorded, usable
from shc_cli.replay.states import INPUT_LATENCY_CYCLES, StatePlan

Velocity = tuple[float, float, float]
RETIME_WINDOW = 8
"""Cycles after a velocity change compared to settle its timing (the walker's response shows in the joints within
a few cycles)."""
RETIME_RANGE = 10
"""A velocity change is looked for up to this many cycles either side of where the latency puts it."""


class ReplayInputs:
    """Commands of a recorded run: the velocity input the recorder saw before cycle ``c − latency``'s output is used
    in cycle ``c``; unusable recorded inputs count as 0. ``retimed`` lists the changes moved by
    :func:`retime_changes` as (cycle, shift)."""

    def __init__(self, recorded: Recorded, plan: StatePlan, latency: int = INPUT_LATENCY_CYCLES) -> None:
        values = np.where(usable(recorded.command), recorded.command, 0.0)
        seen: list[Velocity] = [(float(x), float(y), float(w)) for x, y, w in values]
        self.requests = plan.requests
        self.latency = latency
        n = len(self.requests)
        self.applied: list[Velocity] = [seen[c - latency] if c - latency >= 0 else (0.0, 0.0, 0.0)
                                        for c in range(n)]
        self.retimed: list[tuple[int, int]] = []

    def __len__(self) -> int:
        return len(self.requests)

    def command(self, cycle: int) -> Command:
        return Command(velocity=self.applied[cycle], state_request=self.requests[cycle])

    def changes(self) -> list[int]:
        """Cycles in which the applied velocity differs from the previous cycle's."""
        return [c for c in range(1, len(self.applied)) if self.applied[c] != self.applied[c - 1]]

    def shifted(self, cycle: int, shift: int) -> list[Velocity]:
        """The applied velocities with the change at ``cycle`` moved by ``shift`` cycles (negative: earlier)."""
        applied = list(self.applied)
        if shift < 0:
            applied[cycle + shift:cycle] = [applied[cycle]] * -shift
        elif shift > 0:
            applied[cycle:cycle + shift] = [applied[cycle - 1]] * shift
        return applied


def retime_changes(inputs: ReplayInputs, controller: Controller, joints: np.ndarray,
                   window: int = RETIME_WINDOW, reach: int = RETIME_RANGE) -> None:
    """Move each velocity change of ``inputs`` by up to ``reach`` cycles to where the recorded ``joints`` ``(N, J)``
    [rad] show it (ties keep the nearest); steps ``controller`` (a copy of the replay's, not used after)."""
    ok = usable(joints)
    n = len(inputs)
    cycle = 0

    def run(trial: Controller, applied: list[Velocity], start: int, stop: int) -> float:
        worst = 0.0
        for c in range(start, min(stop, n)):
            out = trial.step(Command(velocity=applied[c], state_request=inputs.requests[c]), None)
            mask = ok[c]
            if mask.any():
                worst = max(worst, float(np.abs(out.joints.ravel()[mask] - joints[c][mask]).max()))
        return worst

    changes = inputs.changes()
    for i, change in enumerate(changes):
        before = changes[i - 1] if i > 0 else 0
        after = changes[i + 1] if i + 1 < len(changes) else n
        shifts = [s for s in range(-reach, reach + 1) if before < change + s < after and change + s >= 1]
        if len(shifts) < 2:
            continue
        start = change + min(shifts) - 1
        while cycle < start:
            controller.step(inputs.command(cycle), None)
            cycle += 1
        stop = change + max(shifts) + window
        errors = {s: run(copy.deepcopy(controller), inputs.shifted(change, s), cycle, stop) for s in shifts}
        best = min(errors, key=lambda s: (errors[s], abs(s)))
        if best != 0 and errors[best] < errors[0]:
            inputs.applied = inputs.shifted(change, best)
            inputs.retimed.append((change, best))
