"""docs/your-robot.md ("Your robot: from URDF to first steps") end to end in a fresh clone: every command of the page
as written — import, validate, plan, simulate, then ``shc hw scan|check|jog`` and ``run-hw`` (dry run and first
power-on) — against emulated buses that this test serves (a process of its own, with the servo map the page's
import wrote), the page's ``/dev/ttyUSB0`` replaced by the emulator's port. The interactive jog gets its answers on
stdin. Runs are cut by ``SHC_MAX_DURATION`` as in tests/test_docs_examples.py."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from shc_cli.hardware.emulator_process import EmulatorProcess
from shc_cli.loop.run_inputs import MAX_DURATION_ENV
from shc_cli.spec.loading import load_robot

from . import test_docs_examples as docs
from .conftest import ROOT

PAGE = ROOT / "docs" / "your-robot.md"
PORT = "/dev/ttyUSB0"
ROBOT = "myrobot/robots/PhantomX.toml"


def _run(steps: list[docs.Step], where: Path, stdin: str = "") -> None:
    env = {**os.environ, MAX_DURATION_ENV: f"{docs.MAX_DURATION_S:g}", "MPLBACKEND": "Agg"}
    env.pop("VIRTUAL_ENV", None)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    done = subprocess.run(["bash", "-c", docs.script(steps)], cwd=where, env=env, capture_output=True, text=True,
                          input=stdin, timeout=1800)
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-5000:]}"


@docs.needs_git
@pytest.mark.slow
def test_the_how_to_runs_end_to_end_on_the_phantomx_against_emulated_servos(tmp_path: Path,
                                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    steps = docs.steps(PAGE)
    texts = [s.text for s in steps]
    for needed in ("shc import urdf", "shc validate", "shc simulate", "shc hw scan", "shc hw check", "shc hw jog",
                   "shc run-hw", "--dry-run"):
        assert any(needed in t for t in texts), f"the how-to has no {needed}"
    first_hw = next(i for i, s in enumerate(steps) if s.text.startswith(("shc hw", "shc run-hw")))
    where = docs.clone(tmp_path)
    # import, view, validate, plan, simulate: as the docs test runs them (shc view exempt)
    _run(steps[:first_hw], where)
    robot = load_robot(where / ROBOT).robot
    hardware = robot.hardware
    assert hardware.model == "AX-12A" and robot.time_delta == 0.04  # the page's sed
    # on a stand and after: against the servo map the import wrote, served by a process of its own
    monkeypatch.setattr(docs, "EXEMPT", {**{k: v for k, v in docs.EXEMPT.items() if k not in ("shc hw", "shc run-hw")},
                                         "shc hw emulate": "this test serves the buses"})
    with EmulatorProcess({s.id: s.model or hardware.model for s in hardware.servos.values()}, baud=hardware.baud,
                         check_baud=True) as bus:
        rest = [docs.Step(s.kind, s.text.replace(PORT, bus.port), s.where, s.name) for s in steps[first_hw:]]
        assert all(PORT not in s.text for s in rest)
        answers = "y\nk\n" * len(hardware.servos)  # the interactive jog: every joint as the file says
        _run(rest, where, stdin=answers)
        goals = [p for p in bus.packets() if p[1] == 0x83 and p[2][0] == 30]  # SYNC WRITE of Goal Position
        torque_on = [bus.torque_on(s.id) for s in hardware.servos.values()]
    assert goals, "the first power-on wrote no goal"
    assert not any(torque_on)  # every run ends with the torque off
    for run in ("px-plan", "px-sim", "px-dry", "px-stand", "px-walk"):
        assert (where / "runs" / run / "summary.json").is_file(), run
    after = load_robot(where / ROBOT).robot.hardware.servos
    assert {k: (s.direction, s.zero_ticks) for k, s in after.items()} == {
        k: (s.direction, s.zero_ticks) for k, s in hardware.servos.items()}  # every answer was "as the file says"
