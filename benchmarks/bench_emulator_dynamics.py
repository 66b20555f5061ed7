"""What the servo emulator's dynamics model (``dynamics=`` a ``[servo]`` table) costs the emulator per control cycle.

Run:  .venv/bin/python benchmarks/bench_emulator_dynamics.py [--cycles 2000]

18 emulated XM430-W350 with their torque on, on an injected clock that moves 10 ms per cycle (no waiting, no pty):
each cycle the emulator handles one SYNC READ of current, velocity and position of all 18 and one goal write each,
as run-hw's cycle makes it. Prints the median and 99th percentile of the handling time per cycle for the
first-order lag and for the dynamics model (10 firmware steps of 1 ms per servo and cycle), in the same run.
"""

from __future__ import annotations

import argparse
import statistics
import time


def main() -> None:
    from shc_cli.hardware import protocol2 as p2
    from shc_cli.hardware.emulator import BusEmulator, VirtualClock
    from shc_cli.spec.robot import Servo

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=2000)
    cycles = parser.parse_args().cycles
    ids = list(range(1, 19))
    read = p2.Packet(p2.BROADCAST, p2.SYNC_READ, (126).to_bytes(2, "little") + (10).to_bytes(2, "little") + bytes(ids))
    model = Servo(model="XM430-W350", control="dynamixel", armature=0.0045, coulomb_friction=0.15,  # type: ignore[arg-type]
                  viscous_friction=0.03)
    medians = {}
    for label, dynamics in (("first-order lag", None), ("dynamics model", model)):
        clock = VirtualClock(0.0, last=None)
        bus = BusEmulator({i: "XM430-W350" for i in ids}, clock=clock, dynamics=dynamics)
        for servo in bus.servos.values():
            servo.write(servo.model.torque_enable, bytes([1]))
        times = []
        for k in range(cycles):
            clock.now += 0.01
            started = time.perf_counter()
            bus._handle(read)
            for servo in bus.servos.values():
                servo.write(servo.model.goal_position, (2048 + k % 200).to_bytes(4, "little", signed=True))
            times.append(time.perf_counter() - started)
        times.sort()
        medians[label] = statistics.median(times)
        print(f"{label}: {statistics.median(times) * 1e3:.3f} ms median, {times[int(0.99 * len(times))] * 1e3:.3f} ms "
              f"p99 per cycle of 18 servos")
    print(f"ratio {medians['dynamics model'] / medians['first-order lag']:.2f}")


if __name__ == "__main__":
    main()
