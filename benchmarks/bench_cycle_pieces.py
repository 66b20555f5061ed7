"""The Python of one control cycle of the default MuJoCo walk, piece by piece (issue 26): the world's read, the
``log.csv`` row, its formatting and the controller's step.

A child process (the source tree of its ``PYTHONPATH``) runs ``shc simulate --duration 8 --no-plots`` into a
temporary directory, keeps the run loop's objects as the walk ends and times each piece on them, best of 5 blocks:

* **read** — ``MujocoWorld.read()`` (pose, twist, IMU, joints, efforts, power, contacts, height);
* **log row** — ``LogRecorder.record()`` of the last cycle without the formatting (the row gathered into the block);
* **formatting** — a block of 256 rows formatted and written (to ``/dev/null``), per row;
* **controller step** — ``Controller.step()`` with the last command and sensors (the walk goes on).

With ``--compare TREE`` (another checkout of shc) children of the two trees alternate ``--rounds`` times and the
medians and their ratios are printed: a change to one piece is seen on its own, which the loop's real-time factor
(``bench_loop.py``) mixes with every other piece and with MuJoCo.

Run:  .venv/bin/python benchmarks/bench_cycle_pieces.py [--compare TREE] [--rounds 3]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parents[1]
PIECES = ("read", "log row", "formatting", "controller step")


def best_of(piece: Callable[[], object], count: int, blocks: int = 5) -> float:
    """The fastest of ``blocks`` blocks of ``count`` calls, per call [µs]."""
    fastest = float("inf")
    for _ in range(blocks):
        started = time.perf_counter()
        for _ in range(count):
            piece()
        fastest = min(fastest, time.perf_counter() - started)
    return fastest / count * 1e6


def child(out: Path) -> None:
    """Walk, keep the loop's objects, time the pieces; print them as JSON."""
    from shc_cli.cli import main as shc
    from shc_cli.loop.run_loop import RunLoop
    from shc_cli.record.runlog import LogRecorder

    kept: dict[str, Any] = {}
    run, record = RunLoop.run, LogRecorder.record

    def keep_loop(self: Any) -> Any:
        kept["loop"] = self
        return run(self)

    def keep_row(self: Any, *arguments: Any) -> None:
        kept["recorder"], kept["row"] = self, arguments
        record(self, *arguments)

    RunLoop.run, LogRecorder.record = keep_loop, keep_row  # type: ignore[method-assign, assignment]
    sys.argv = ["shc", "simulate", "--duration", "8", "--out", str(out), "--no-plots"]
    try:
        shc()
    except SystemExit as exit_:
        if exit_.code:
            raise
    loop, recorder, (cycle, command, output, applied, reading) = kept["loop"], kept["recorder"], kept["row"]
    recorder.handle = open(os.devnull, "w")  # noqa: SIM115 (the benchmark's own sink)
    block, world, controller = recorder.block, loop.backend.world, loop.controller
    sensors = loop.backend.sensors(True)

    def row() -> None:
        record(recorder, cycle, command, output, applied, reading)
        block.rows = 0

    def formatting() -> None:
        block.rows = 256
        recorder.write_rows()

    print(json.dumps({"read": best_of(world.read, 5000), "log row": best_of(row, 5000),
                      "formatting": best_of(formatting, 40) / 256,
                      "controller step": best_of(lambda: controller.step(command, sensors), 5000)}))


def measure(tree: Path, folder: Path) -> dict[str, float]:
    """One child of ``tree``."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = str(tree)
    out = folder / f"walk-{time.monotonic_ns()}"
    done = subprocess.run([sys.executable, str(Path(__file__).resolve()), "--child", str(out)], env=env,
                          cwd=folder, capture_output=True, text=True, check=True)
    result: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--compare", type=Path, default=None, help="another shc source tree, run alternately")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--child", type=Path, default=None, help=argparse.SUPPRESS)
    options = parser.parse_args()
    if options.child is not None:
        child(options.child)
        return
    trees = [options.compare.resolve(), HERE] if options.compare else [HERE]
    runs: dict[Path, list[dict[str, float]]] = {tree: [] for tree in trees}
    with tempfile.TemporaryDirectory() as folder:
        for tree in trees:  # untimed: bytecode and numba caches
            measure(tree, Path(folder))
        for _ in range(options.rounds):
            for tree in trees:
                runs[tree].append(measure(tree, Path(folder)))
    print(f"load average {os.getloadavg()[0]:.1f} at the end; {options.rounds} runs per tree; µs per cycle "
          "(formatting: per row), median (runs)")
    medians = {tree: {piece: statistics.median(run[piece] for run in runs[tree]) for piece in PIECES}
               for tree in trees}
    for tree in trees:
        print(f"{tree}:")
        for piece in PIECES:
            values = ", ".join(f"{run[piece]:.2f}" for run in runs[tree])
            print(f"  {piece}: {medians[tree][piece]:.2f} ({values})")
    if len(trees) == 2:
        before, after = trees
        print("this tree over the compared one (ratio of medians, < 1 is faster):")
        for piece in PIECES:
            print(f"  {piece}: {medians[after][piece] / medians[before][piece]:.2f}")


if __name__ == "__main__":
    main()
