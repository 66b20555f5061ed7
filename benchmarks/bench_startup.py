"""Start-up time of ``shc --help``: the wall time of a fresh Python process that runs it, and the heavy modules the
process imported (none should be: typer alone; numpy, numba, pydantic and the viewer load inside the commands).

Run:  .venv/bin/python benchmarks/bench_startup.py [--repeats 15]

Prints the median, best and worst wall time [s] over ``--repeats`` processes and a bare ``python -c pass`` for the
same-run ratio (the interpreter's own start is most of it).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time

HEAVY = ("numpy", "numba", "pydantic", "matplotlib", "scipy", "viser", "mujoco", "imageio_ffmpeg", "PIL",
         "playwright", "shc_cli.view")
HELP = ("import sys; sys.argv = ['shc', '--help']\nfrom shc_cli.cli import main\n"
        "try:\n    main()\nexcept SystemExit:\n    pass\n"
        f"print([m for m in {HEAVY!r} if m in sys.modules], file=sys.stderr)")


def timed(code: str) -> tuple[float, str]:
    """Wall time [s] of a fresh interpreter running ``code``, and what it printed on stderr."""
    started = time.perf_counter()
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return time.perf_counter() - started, result.stderr.strip()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    repeats = parser.parse_args().repeats
    helps, bares, heavy = [], [], set()
    for _ in range(repeats):  # interleaved, so both see the same machine load
        wall, loaded = timed(HELP)
        helps.append(wall)
        heavy.add(loaded)
        bares.append(timed("pass")[0])
    for name, times in (("shc --help", helps), ("python -c pass", bares)):
        print(f"{name:15s} median {statistics.median(times):.3f} s  best {min(times):.3f} s  worst {max(times):.3f} s")
    print(f"ratio of medians {statistics.median(helps) / statistics.median(bares):.2f}; heavy modules imported: "
          f"{' '.join(sorted(heavy))}")


if __name__ == "__main__":
    main()
