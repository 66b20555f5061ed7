"""A walk short of the distance asked says why (issue 37, point 8): which joint saturated, which foot slipped
(shc_cli/analysis/shortfall.py), from a log made here with known figures."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from shc_cli.analysis.shortfall import SATURATED_SHARE, saturation, worst_slip
from shc_cli.spec.loading import load_robot

ROWS = 200


def _log(**arrays: np.ndarray) -> SimpleNamespace:
    """bullet's robot, 200 cycles of 6 × 3 joints standing still at 0.1 rad, torques 0.1 N·m, unless given."""
    robot = load_robot("bullet").robot
    legs, width = len(robot.legs), max(len(leg.joints) for leg in robot.legs.values())
    base = {"efforts": np.full((ROWS, legs, width), 0.1), "commanded": np.full((ROWS, legs, width), 0.1)}
    return SimpleNamespace(robot=robot, **{**base, **arrays})


def test_a_joint_at_stall_torque_a_third_of_the_time_is_named() -> None:
    log = _log()
    stall = log.robot.servo.stall_torque
    log.efforts[:ROWS // 3, 2, 1] = -stall  # the third leg's second joint pulls its stall torque
    found = saturation(log, np.arange(ROWS))  # type: ignore[arg-type]
    assert found is not None
    second = list(log.robot.legs["CR"].joints)[1]
    assert found.joint == f"{list(log.robot.legs)[2]}_{second}" and found.how == "at stall torque"
    assert found.share == pytest.approx((ROWS // 3) / ROWS)


def test_a_joint_commanded_at_its_speed_limit_is_named() -> None:
    log = _log()
    joint = list(log.robot.legs["AR"].joints.values())[2]
    step = joint.max_vel * log.robot.time_delta
    log.commanded[:41, 0, 2] = 0.1 + step * (np.arange(41) % 2)  # 40 cycles at max_vel (to and fro), then held
    found = saturation(log, np.arange(ROWS))  # type: ignore[arg-type]
    assert found is not None and found.how == "at its speed limit"
    assert found.joint.startswith("AR_") and found.share == pytest.approx(40 / (ROWS - 1))


def test_a_joint_held_at_its_limit_is_named_and_a_short_spell_is_not() -> None:
    log = _log()
    joint = next(iter(log.robot.legs["AR"].joints.values()))
    log.commanded[:50, 0, 0] = joint.max
    found = saturation(log, np.arange(ROWS))  # type: ignore[arg-type]
    assert found is not None and found.how == "at its joint limit" and found.share == pytest.approx(0.25)
    log = _log()
    log.commanded[: int(SATURATED_SHARE * ROWS) - 1, 0, 0] = joint.max
    assert saturation(log, np.arange(ROWS)) is None  # type: ignore[arg-type]


def test_the_foot_that_slid_most_while_down_is_named() -> None:
    """Three feet: the second slides 1 mm a cycle while down for 100 cycles (0.099 m), the third 2 mm a cycle but
    only in the air; the first stands still."""
    feet = np.zeros((100, 3, 3))
    feet[:, 1, 0] = 0.001 * np.arange(100)
    feet[:, 2, 1] = 0.002 * np.arange(100)
    contact = np.ones((100, 3), dtype=bool)
    contact[:, 2] = False
    leg, slid = worst_slip(feet, contact, ["AR", "BR", "CR"])
    assert leg == "BR" and slid == pytest.approx(0.099)


def test_a_slipping_walk_says_it_fell_short_and_why(tmp_path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """quadruped on ice (friction 0.05) walks about a quarter of the distance asked in 5 s: the line says so, with
    the share summary.json gives, the saturated joint and the slipping foot."""
    import json
    import re

    from .test_cli import run

    code, out, err = run(["simulate", "quadruped", "--friction", "0.05", "--duration", "5", "--no-plots", "--out",
                          str(tmp_path / "ice")], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((tmp_path / "ice" / "summary.json").read_text())
    assert not summary["fell"] and summary["walked_share"] < 0.6
    found = re.search(r"warning: walked (\d+) % of the ([0-9.]+) m commanded \(under 60 %\): ([^,→]+)", out)
    assert found is not None, out
    assert int(found.group(1)) == round(100 * summary["walked_share"])
    assert float(found.group(2)) == pytest.approx(summary["commanded_distance_m"], abs=0.005)
    why = found.group(3)
    assert re.search(r"(AR|BR|BL|AL)_(coxa|femur|tibia) at (stall torque|its speed limit|its joint limit) in \d+ % "
                     r"of the cycles", why), why
    assert re.search(r"foot (AR|BR|BL|AL) slips most \([0-9.]+ m over [0-9.]+ m walked\)", why), why
