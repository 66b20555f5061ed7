"""What one cycle of leg odometry costs the controller (issue 26): ``Controller._update_odometry`` on bullet with
what MuJoCo measures — joints (forward kinematics), the IMU's orientation, foot contact and foot forces.

Run:  .venv/bin/python benchmarks/bench_odometry_cycle.py [--number 20000]
(with ``PYTHONPATH=OTHER_TREE`` to time another checkout the same way)
"""

from __future__ import annotations

import argparse
import timeit

import numpy as np

from shc_cli.api import load_gait, load_robot
from shc_cli.control.controller import Controller
from shc_cli.control.sensing import Sensors


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--number", type=int, default=20000)
    options = parser.parse_args()
    controller = Controller(load_robot("bullet"), load_gait("tripod"))
    q = np.array([0.01, 0.02, 0.03, 0.999])
    sensors = Sensors(joints=controller.model.joints.copy(), orientation=q / np.linalg.norm(q),
                      foot_forces=np.full(6, 20.0), foot_contact=np.ones(6, dtype=bool), angular_rate=np.zeros(3))
    stance = np.ones(6, dtype=bool)
    controller._update_odometry(sensors, stance)  # numba's cache loaded

    def cycle() -> None:
        controller._update_odometry(sensors, stance)

    best = min(timeit.repeat(cycle, number=options.number, repeat=5)) / options.number
    print(f"leg odometry: {best * 1e6:.1f} µs a cycle (best of 5 × {options.number})")


if __name__ == "__main__":
    main()
