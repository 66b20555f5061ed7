"""The TOML key → line locator that puts line numbers on every error."""

from __future__ import annotations

from shc_cli.spec.source import key_lines, line_of

TEXT = '''# comment
name = "x"
[body]
size = [0.1, 0.2,
        0.3]
mass = 1.0   # kg

[legs.AR]
base = { d = 0.1, r = { x = 1 } }
joints.coxa = { min = -1, max = 1 }
"quoted key" = 3

[[runs]]
a = 1
[[runs]]
a = 2
'''


def test_keys_map_to_their_lines() -> None:
    lines = key_lines(TEXT)
    assert lines[("name",)] == 2
    assert lines[("body",)] == 3
    assert lines[("body", "size")] == 4
    assert lines[("body", "mass")] == 6
    assert lines[("legs", "AR")] == 8
    assert lines[("legs", "AR", "base", "d")] == 9
    assert lines[("legs", "AR", "base", "r", "x")] == 9
    assert lines[("legs", "AR", "joints", "coxa", "max")] == 10
    assert lines[("legs", "AR", "quoted key")] == 11
    assert lines[("runs", 0, "a")] == 14
    assert lines[("runs", 1, "a")] == 16


def test_missing_keys_fall_back_to_their_closest_ancestor() -> None:
    lines = key_lines(TEXT)
    assert line_of(lines, ("legs", "AR", "stance", "x")) == 8
    assert line_of(lines, ("nothing",)) is None
