"""The one "bad choice" refusal: one line naming the option, the value, what it should be and the choices."""

from __future__ import annotations

import pytest

from shc_cli.errors import SpecError, check_choice, spoken


def test_spoken_lists_choices_as_a_sentence() -> None:
    assert spoken(["mcap"]) == "mcap"
    assert spoken(["pybullet", "mujoco"]) == "pybullet or mujoco"
    assert spoken(["mcap", "sqlite3", "ros1"]) == "mcap, sqlite3 or ros1"


def test_a_bad_choice_is_one_line_with_the_choices() -> None:
    check_choice("--bag", "mcap", ("mcap", "sqlite3", "ros1"), "a bag format")  # a right value passes
    with pytest.raises(SpecError) as caught:
        check_choice("--bag", "zip", ("mcap", "sqlite3", "ros1"), "a bag format")
    assert str(caught.value) == "--bag: 'zip' is not a bag format (use mcap, sqlite3 or ros1)"
    with pytest.raises(SpecError, match=r"^--start: 'up' is not a start pose \(say unpacked\)$"):
        check_choice("--start", "up", ("unpacked", "packed"), "a start pose", "say unpacked")
