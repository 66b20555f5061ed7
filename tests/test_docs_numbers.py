"""The figures the README quotes are the ones the commands print (issue 42 point 9): each test runs the command, reads
the figure from its output and checks that the README's text holds it as printed — so a change of the figure (a new
robot file, a controller fix) fails here until the README says the new one; the message names what to write."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest

from .conftest import ROOT
from .test_cli import run


def readme() -> str:
    """The README with its line breaks as spaces (a figure may sit at the end of a line)."""
    return re.sub(r"\s+", " ", (ROOT / "README.md").read_text(encoding="utf-8"))


def quoted(phrase: str) -> None:
    """Fail unless the README holds ``phrase`` (whitespace-insensitive)."""
    assert re.sub(r"\s+", " ", phrase) in readme(), f"README.md should say: {phrase!r}"


def workspace(name: str, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> dict[str, object]:
    code, out, err = run(["workspace", name, "--json"], capsys, monkeypatch)
    assert code == 0, err
    report: dict[str, object] = json.loads(out)
    return report


def plan(velocity: str, out: Path, capsys: pytest.CaptureFixture[str],
         monkeypatch: pytest.MonkeyPatch) -> dict[str, float]:
    code, _, err = run(["plan", "bullet", "--velocity", velocity, "--duration", "10", "--no-plots", "--out", str(out)],
                       capsys, monkeypatch)
    assert code == 0, err
    summary: dict[str, float] = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    return summary


def test_the_readme_quotes_bullets_walkspace_speed_limits(capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    """README, First five minutes: "0.23 m/s straight ahead" was bullet_openshc's 0.2319, not the default robot's."""
    document = workspace("bullet", capsys, monkeypatch)
    speeds, kept = document["max_linear_speed"], document["verified_max_linear_speed"]
    assert isinstance(speeds, dict) and isinstance(kept, dict)
    quoted(f"`shc workspace` prints them per bearing: {speeds['0']:.4f} m/s straight ahead for Bullet's tripod")
    quoted(f"{min(speeds['45'], speeds['315']):.4f} m/s at 45° off it")
    quoted(f"`shc workspace` prints them beside OpenSHC's): {kept['0']:.4f} m/s straight ahead, "
           f"{min(kept['45'], kept['315']):.4f} m/s at 45°")


def test_the_readme_explains_the_turning_share_with_the_plans_own_figures(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """"`0.5,0,0.2` is half speed ahead" — it walked 0.064 m/s against 0.094 for `0.5,0,0`: OpenSHC's throttle mode
    scales the linear throttle by 1 − |turn throttle| and reads each foot's limit at its stride's bearing (the least
    over the legs: turning takes the rear feet into the 315° sector)."""
    speeds = workspace("bullet", capsys, monkeypatch)["verified_max_linear_speed"]  # the limits the robot walks
    assert isinstance(speeds, dict)
    straight, turning = plan("0.5,0,0", tmp_path / "straight", capsys, monkeypatch), plan(
        "0.5,0,0.2", tmp_path / "arc", capsys, monkeypatch)
    # a left turn takes the front feet's strides into the 0° sector and the rear feet's into the 315° one
    off_axis = min(speeds["0"], speeds["315"])
    predicted = 0.5 * (1 - 0.2) * off_axis
    # the explanation holds: the stance feet move at the predicted speed (1 %: the acceleration-limited ramp)
    assert turning["achieved_mean_speed_mps"] == pytest.approx(predicted, rel=0.01)
    assert straight["achieved_mean_speed_mps"] == pytest.approx(0.5 * speeds["0"], rel=0.01)
    quoted(f"`0.5,0,0` walks at half speed (its plan's stance feet: {straight['achieved_mean_speed_mps']:.4f} m/s)")
    quoted(f"moves at 0.5 × 0.8 × {off_axis:.4f} = {predicted:.4f} m/s (its plan's stance feet: "
           f"{turning['achieved_mean_speed_mps']:.4f} m/s; path speed {turning['path_speed_mps']:.4f} m/s against "
           f"{straight['path_speed_mps']:.4f} m/s for `0.5,0,0`")


def test_the_readme_names_every_bundled_robot_and_gait() -> None:
    """`bullet_openshc` was missing from the README's list."""
    text = readme()
    listed = text[text.index("Robots are named"):]
    for kind in ("robots", "gaits"):
        for name in sorted(p.stem for p in (ROOT / kind).glob("*.toml")):
            assert f"`{name}`" in listed, f"README.md's list of named {kind} lacks `{name}`"


def test_the_workspace_line_does_not_call_another_robots_figure_the_papers(
        capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """`shc workspace athena` ended "(the OpenSHC paper's Table II figure)": Table II lists only Bullet's
    arrangements; for any robot the line gives the figure as Table II measures it."""
    code, out, err = run(["workspace", "athena"], capsys, monkeypatch)
    assert code == 0, err
    last = next(line for line in out.splitlines() if line.startswith("walkspace area"))
    assert "Table II figure" not in last and last.endswith("(measured as the OpenSHC paper's Table II does for Bullet)")


def test_a_piped_workspace_table_of_many_bearings_is_wrapped(capsys: pytest.CaptureFixture[str],
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 42 point 14: `shc workspace --bearings 72` in a pipe printed 770-character lines; it prints blocks of
    eight bearings (the default table, which stays whole)."""
    monkeypatch.delenv("COLUMNS", raising=False)
    monkeypatch.setattr("shutil.get_terminal_size", lambda fallback=(0, 0): os.terminal_size(fallback))  # a pipe
    code, out, err = run(["workspace", "athena", "--bearings", "72"], capsys, monkeypatch)
    assert code == 0, err
    lines = out.splitlines()
    assert max(len(line) for line in lines) <= 121 and sum(line.startswith("leg ") for line in lines) == 9
    code, out, err = run(["workspace", "athena"], capsys, monkeypatch)
    assert code == 0, err
    assert sum(line.startswith("leg ") for line in out.splitlines()) == 1
