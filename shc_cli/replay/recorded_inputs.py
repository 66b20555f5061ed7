"""The controller's inputs for each cycle of a replay: the recorded velocity input and the inferred state requests.

A :class:`ReplayInputs` is a per-cycle command source: ``inputs.command(cycle)`` is what OpenSHC acted on in that
cycle, so any loop that steps a :class:`~shc_cli.control.controller.Controller` can replay a recording.
"""

from __future__ import annotations

import numpy as np

from shc_cli.control.controller import Command
from shc_cli.replay.source import Recorded, usable
from shc_cli.replay.states import INPUT_LATENCY_CYCLES, StatePlan


class ReplayInputs:
    """Commands of a recorded run: the velocity input the recorder saw before cycle ``c − latency``'s output is used
    in cycle ``c`` (OpenSHC reads its topics after publishing); unusable recorded inputs count as 0."""

    def __init__(self, recorded: Recorded, plan: StatePlan, latency: int = INPUT_LATENCY_CYCLES) -> None:
        values = np.where(usable(recorded.command), recorded.command, 0.0)
        self.velocity: list[tuple[float, float, float]] = [(float(x), float(y), float(w)) for x, y, w in values]
        self.requests = plan.requests
        self.latency = latency

    def __len__(self) -> int:
        return len(self.requests)

    def command(self, cycle: int) -> Command:
        source = cycle - self.latency
        velocity = self.velocity[source] if source >= 0 else (0.0, 0.0, 0.0)
        return Command(velocity=velocity, state_request=self.requests[cycle])
