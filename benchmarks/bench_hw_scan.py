"""How long ``shc hw scan`` takes on an empty bus (nothing answers: the worst case), per protocol.

    .venv/bin/python benchmarks/bench_hw_scan.py

An emulated bus with no servo (``shc_cli/hardware/emulator_process.py``, its own process) at 1 Mbaud; the scan
itself timed (``shc_cli.hardware.scan.scan``, no interpreter start-up): Protocol 2.0's broadcast ping for ids 0-252
and 1-18, and Protocol 1.0's unicast pings of ids 0-252 at the default timeout (a pty has no latency timer: 6 ms),
then the same pings at dynamixel-sdk's own timeout (2 × 16 ms + 2 ms per ping) for comparison.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from shc_cli.hardware.emulator_process import EmulatorProcess
from shc_cli.hardware.scan import scan


def main() -> None:
    with EmulatorProcess({}, baud=1_000_000, check_baud=True) as bus:
        for protocol, ids, timeout in (("2.0", range(253), None), ("2.0", range(1, 19), None),
                                       ("1.0", range(253), None), ("1.0", range(253), 0.034)):
            began = time.perf_counter()
            found = scan([bus.port], [1_000_000], [protocol], ids, timeout)  # type: ignore[list-item]
            took = time.perf_counter() - began
            wait = "default" if timeout is None else f"{timeout * 1e3:.0f} ms"
            print(f"Protocol {protocol}, ids {ids.start}-{ids.stop - 1}, timeout {wait}: {took:.2f} s, "
                  f"{len(found)} found")


if __name__ == "__main__":
    main()
