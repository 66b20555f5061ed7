"""What the path follower costs per control cycle (docs/path-following.md, docs/performance.md).

    .venv/bin/python benchmarks/bench_path.py [--pairs 5]

The bundled square (``paths/square_2m.csv``) walked by ``bullet`` on the kinematic backend without logging, once
with the follower as the input (:class:`~shc_cli.loop.path_input.PathInput`) and once replaying the very commands it
gave (a plain sequence input): the controller does the same work in both, so the difference is the follower's
(its geometry, the walker's limits it asks for, the conversion to the velocity input). Alternating pairs; prints the
median loop time per cycle of each, their per-pair ratios and the median time of one ``PathInput.next``.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from shc_cli.backends.kinematic import KinematicBackend
from shc_cli.control.controller import Command, Controller, CycleOutput
from shc_cli.loop.path_input import PathInput
from shc_cli.loop.run_inputs import load_inputs
from shc_cli.loop.run_loop import NullRecorder, RunLoop, SequenceInput, StartUp
from shc_cli.spec.path import load_path

SQUARE = Path(__file__).parents[1] / "paths" / "square_2m.csv"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--pairs", type=int, default=5)
    pairs = parser.parse_args().pairs
    inputs = load_inputs("bullet", None, "0,0,0", None, None, default_s=10.0, path=SQUARE)
    path = load_path(SQUARE)

    def follow() -> tuple[float, list[Command], list[float]]:
        controller = Controller(inputs.robot, inputs.gait, pose_sets=inputs.pose_sets)
        source = PathInput(path, controller, inputs.cycles)
        commands: list[Command] = []
        spent: list[float] = []
        real = source.next

        def timed() -> Command | None:
            started = time.perf_counter()
            command = real()
            spent.append(time.perf_counter() - started)
            return command

        source.next = timed  # type: ignore[method-assign]

        def record(cycle: int, command: Command, out: CycleOutput, reading: object) -> None:
            if command.state_request is None:
                commands.append(command)

        loop = RunLoop(controller, KinematicBackend(), source, NullRecorder(), StartUp.of(inputs.robot),
                       observers=[record])
        started = time.perf_counter()
        result = loop.run()
        return (time.perf_counter() - started) / result.cycles, commands, spent

    def replay(commands: list[Command]) -> float:
        controller = Controller(inputs.robot, inputs.gait, pose_sets=inputs.pose_sets)
        loop = RunLoop(controller, KinematicBackend(), SequenceInput(commands), NullRecorder(),
                       StartUp.of(inputs.robot))
        started = time.perf_counter()
        result = loop.run()
        return (time.perf_counter() - started) / result.cycles

    _, commands, _ = follow()  # warm-up (compiled kernels loaded)
    replay(commands)
    results = []
    for _ in range(pairs):
        followed, commands, spent = follow()
        results.append((followed, replay(commands), statistics.median(spent)))
    follower = statistics.median(r[0] for r in results) * 1e6
    plain = statistics.median(r[1] for r in results) * 1e6
    ratios = ", ".join(f"{r[0] / r[1]:.3f}" for r in results)
    print(f"{len(commands)} walking cycles: follower {follower:.1f} µs/cycle, the same commands replayed "
          f"{plain:.1f} µs/cycle (median of {pairs}); per-pair ratios {ratios}; PathInput.next median "
          f"{statistics.median(r[2] for r in results) * 1e6:.1f} µs")


if __name__ == "__main__":
    main()
