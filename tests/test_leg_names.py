"""``shc validate`` warns (not errs) when a leg named in OpenSHC's scheme (AR front right … AL front left) stands
where its name says it does not: a mirrored robot whose AR is on the left and whose legs run anticlockwise."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

from shc_cli.spec.loading import bundled, load_robot
from shc_cli.validation import leg_position_warnings


def _swapped_sides(tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Path:
    """Bullet expanded (``validate --show``), each leg's R and L swapped in its name: AR on the left, and so on."""
    from shc_cli.cli import main

    monkeypatch.setattr(sys, "argv", ["shc", "validate", "bullet", "--show"])
    with pytest.raises(SystemExit) as done:
        main()
    assert done.value.code == 0
    text = capsys.readouterr().out
    swapped = re.sub(r"\b([A-C])([RL])(?=[\]._])", lambda m: m[1] + ("L" if m[2] == "R" else "R"), text)
    path = tmp_path / "mirrored.toml"
    path.write_text(swapped)
    return path


@pytest.mark.parametrize("name", bundled("robots"))
def test_every_bundled_robot_stands_where_its_leg_names_say(name: str) -> None:
    assert leg_position_warnings(load_robot(name).robot) == []


def test_a_robot_whose_legs_stand_opposite_their_names_is_warned_but_valid(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    from shc_cli.cli import main

    path = _swapped_sides(tmp_path, capsys, monkeypatch)
    robot = load_robot(str(path)).robot
    assert list(robot.legs) == ["AL", "BL", "CL", "CR", "BR", "AR"]  # the file's order: anticlockwise from AL
    assert robot.legs["AR"].stance.y > 0  # AR (OpenSHC's front right) on the left
    monkeypatch.setattr(sys, "argv", ["shc", "validate", str(path)])
    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 0, err  # valid: a warning only
    warnings = [line for line in err.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 6, err
    assert any(line.startswith(f"warning: {path}: leg AR: OpenSHC's name says right side, but it stands on the left "
                               "(stance x +0.300, y +0.350 m)") for line in warnings), warnings


def test_legs_of_one_side_out_of_front_to_rear_order_are_named() -> None:
    robot = load_robot("bullet").robot
    legs = dict(robot.legs)
    legs["AR"], legs["CR"] = legs["CR"], legs["AR"]  # AR at the rear, CR at the front
    (first, second) = leg_position_warnings(robot.model_copy(update={"legs": legs}))
    assert first.startswith("leg AR: OpenSHC's name says it is in front of BR, but it stands behind or beside it "
                            "(stance x -0.300 m against +0.000 m)")
    assert second.startswith("leg BR: OpenSHC's name says it is in front of CR")


def test_legs_named_otherwise_are_not_checked() -> None:
    robot = load_robot("bullet").robot
    legs = {f"leg{i}": leg for i, leg in enumerate(reversed(robot.legs.values()))}
    assert leg_position_warnings(robot.model_copy(update={"legs": legs})) == []
