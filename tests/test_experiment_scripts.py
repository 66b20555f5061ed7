"""The experiment scripts in docs/experiments: their physics against first principles, and their command line."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import vertical_load  # docs/experiments (on the path through conftest)

from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot

from .conftest import EXPERIMENTS, ROOT


@pytest.mark.parametrize("name", ["bullet_mammalian_a", "bullet_mammalian_b", "bullet_insectoid_b"])
def test_vertical_load_torque_is_the_virtual_work_of_the_foot_force(name: str) -> None:
    """τ_i = F · ∂tip/∂q_i with the tip and F in base_link (finite differences of the forward kinematics). The
    B legs' frames have their z axis along the coxa, not up: a torque taken in the leg frame fails this for them."""
    robot = load_robot(name).robot
    chains = Chains.from_robot(robot)
    rng = np.random.default_rng(3)
    force = np.array([0.0, 0.0, 18.2])
    for leg in range(chains.size):
        chain = chains.take(np.array([leg]))
        q = rng.uniform(chain.lower[0], chain.upper[0])
        step = 1e-6
        expected = [force @ (chain.tips((q + step * e)[None])[0] - chain.tips((q - step * e)[None])[0]) / (2 * step)
                    for e in np.eye(q.size)]
        np.testing.assert_allclose(vertical_load._leg_torque(chain, q, force), expected, atol=1e-5)


@pytest.mark.slow  # the experiment scripts as subprocesses
def test_scripts_answer_bad_arguments_with_one_line(tmp_path: object) -> None:
    script = str(EXPERIMENTS / "vertical_load.py")
    usage = subprocess.run([sys.executable, script], capture_output=True, text=True, check=False)
    assert usage.returncode != 0 and usage.stderr.startswith("usage: ")
    missing = subprocess.run([sys.executable, script, str(ROOT / "no-such-run")], capture_output=True, text=True,
                             check=False)
    assert missing.returncode == 2
    assert len(missing.stderr.strip().splitlines()) == 1 and missing.stderr.startswith("error: ")
