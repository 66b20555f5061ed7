"""Failures declared mid-walk (``--fail-leg LEG[:MODE]@T``, issue 39): the controller changes to the re-planned gait
as OpenSHC changes gaits (the walker stops with every foot down), then holds the failed legs and walks on."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from shc_cli.control.leg_failure import FailedLeg, parse_failures
from shc_cli.errors import SpecError
from shc_cli.spec.loading import load_robot

LEGS = list(load_robot("bullet").robot.legs)


def test_a_time_declares_the_failure_that_many_seconds_after_walking_starts() -> None:
    assert parse_failures(["BR:retracted@5"], LEGS) == (FailedLeg("BR", "retracted", 5.0),)
    assert parse_failures(["BR@2.5,AL@2.5"], LEGS) == (FailedLeg("BR", at_s=2.5), FailedLeg("AL", at_s=2.5))
    assert str(FailedLeg("BR", "locked", 5.0)) == "BR:locked@5"


@pytest.mark.parametrize(("spec", "message"), [
    ("BR@soon", "--fail-leg: 'BR@soon': @'soon' is not a time (give seconds after walking starts, e.g. BR@5)"),
    ("BR@-1", "--fail-leg: 'BR@-1': @'-1' is not a time (give seconds after walking starts, e.g. BR@5)"),
    ("BR@5,AL@6", "--fail-leg: 'BR:retracted@5,AL:retracted@6': legs failed at different times (give every "
                  "leg the same @T (or none))"),
])
def test_a_bad_time_is_one_line(spec: str, message: str) -> None:
    with pytest.raises(SpecError) as raised:
        parse_failures([spec], LEGS)
    assert str(raised.value) == message


def _rows(run: Path, name: str) -> list[dict[str, str]]:
    with (run / name).open() as file:
        return list(csv.DictReader(file))


def test_a_leg_failed_mid_walk_is_walked_on_the_intact_gait_then_held_on_the_re_planned_one(tmp_path: Path) -> None:
    """plan, BR@2: the tripod walks 2 s, the walker stops, the generated five-leg gait starts; BR's commanded
    joints move before and are constant from the re-planned walk on, the others keep walking."""
    from shc_cli import api

    run = api.plan("bullet", duration=12.0, out=tmp_path / "run", plots=False, fail_leg="BR@2").path
    summary = json.loads((run / "summary.json").read_text())
    assert summary["gait"] == "planned"  # the gait at the end of the run
    events = [json.loads(line) for line in (run / "events.log").read_text().splitlines()]
    walk = [(e["cycle"], e["message"]) for e in events if e["event"] == "walk_state"]
    started = next(c for c, m in walk if m.endswith("STOPPED → STARTING"))
    stopping = next(c for c, m in walk if m.endswith("→ STOPPING"))
    restarted = [c for c, m in walk if m.endswith("STOPPED → STARTING")][1]
    assert 200 <= stopping - started <= 200 + 250  # requested 2 s (200 cycles) in, the walker stops in a step cycle
    failures = [(e["cycle"], e["message"]) for e in events if e["event"] == "leg_failure"]  # at the 200th walking cycle
    assert [m.split(":")[0] for _, m in failures] == ["leg failure declared (BR", "walking on without BR"]
    assert failures[0][0] == started + 199 and failures[1][0] in range(stopping, restarted + 1)
    joints = _rows(run, "joints.csv")
    names = [n for n in joints[0] if n.startswith("BR_")]
    br = np.array([[float(r[n]) for n in names] for r in joints])
    cycles = np.array([int(r["cycle"]) for r in joints])
    assert np.ptp(br[(cycles > started) & (cycles < stopping)], axis=0).max() > 0.1  # BR walked the tripod
    assert np.ptp(br[cycles > restarted + 100], axis=0).max() == 0.0  # then held
    ar = np.array([[float(r[n]) for n in joints[0] if n.startswith("AR_")] for r in joints])
    assert np.ptp(ar[cycles > restarted + 100], axis=0).max() > 0.1  # the others walk on


@pytest.mark.slow
def test_a_leg_retracted_five_seconds_into_the_walk_is_absorbed_without_a_fall_in_mujoco(tmp_path: Path) -> None:
    from shc_cli import api

    run = api.simulate("bullet", duration=20.0, out=tmp_path / "run", plots=False, fail_leg="BR:retracted@5").path
    summary = json.loads((run / "summary.json").read_text())
    assert not summary["fell"] and summary["max_tilt_rad"] < 0.6
    assert summary["forward_distance_m"] > 1.0


@pytest.mark.parametrize(("option", "message"), [
    ("--on-fault", "error: --on-fault: 'bogus' is not hold, torque-off or adapt (use hold, torque-off or adapt)\n"),
    ("--on-stop", "error: --on-stop: 'bogus' is not hold or torque-off (use hold or torque-off)\n"),
])
def test_run_hws_fault_choices_include_adapt_and_a_bad_one_is_one_line(
        option: str, message: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """``--on-fault adapt`` is a choice (``--on-stop`` has none such); anything else exits 2 before a bus opens."""
    import sys

    from shc_cli.cli import main
    from shc_cli.domain.hardware import HardwareConfig

    assert HardwareConfig(robot="bullet", ports=["/dev/null"], on_fault="adapt").on_fault == "adapt"
    monkeypatch.setattr(sys, "argv", ["shc", "run-hw", "bullet", "--port", "/dev/nonexistent", option, "bogus"])
    with pytest.raises(SystemExit) as done:
        main()
    assert done.value.code == 2 and capsys.readouterr().err == message
