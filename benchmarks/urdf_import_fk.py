"""Accuracy of `shc import urdf` (not a timing): the largest tip difference between imported DH chains and
yourdfpy's forward kinematics of the URDF, over random URDFs drawn from the property test's generator.

Run:  .venv/bin/python -m benchmarks.urdf_import_fk [--urdfs 300] [--vectors 20]

Each URDF has 1–3 legs of 1–6 revolute joints with any axes and rpy offsets and 0–2 fixed joints before each;
each is compared at ``--vectors`` random joint vectors inside the limits.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.test_urdf_import import _fk_difference, _import_text, chains
from tests.urdf_robots import LegSpec, robot_urdf


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--urdfs", type=int, default=300)
    parser.add_argument("--vectors", type=int, default=20)
    options = parser.parse_args()
    worst, count = 0.0, 0

    @settings(max_examples=options.urdfs, deadline=None, suppress_health_check=list(HealthCheck), database=None)
    @given(legs=st.lists(st.sampled_from(["p", "q", "r"]), min_size=1, max_size=3, unique=True).flatmap(
        lambda names: st.tuples(*[chains(name) for name in names])), seed=st.integers(0, 2**31))
    def measure(legs: tuple[LegSpec, ...], seed: int) -> None:
        nonlocal worst, count
        with tempfile.TemporaryDirectory() as folder:
            model, imported = _import_text(robot_urdf(list(legs)), Path(folder))
            worst = max(worst, _fk_difference(model, imported, np.random.default_rng(seed), options.vectors))
            count += 1

    measure()
    print(f"{count} random URDFs, {options.vectors} joint vectors each: largest tip difference {worst:.2g} m")


if __name__ == "__main__":
    main()
