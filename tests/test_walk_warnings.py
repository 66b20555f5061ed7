"""The summary line warns of a walk that went somewhere but badly (issue 42 point 13): the imported PhantomX of
docs/your-robot.md slid its feet over a quarter of the distance and said nothing; the servo model the guide sets is
the simulation's too."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import pytest

from shc_cli.analysis.run_line import SLIP_SHARE, walk_warnings
from shc_cli.record.summary import RunSummary

from .conftest import ROOT
from .test_cli import run

GUIDE = ROOT / "docs" / "your-robot.md"


def guide_command(start: str) -> str:
    """The guide's command that starts with ``start``, as written."""
    found = re.search(rf"^{re.escape(start)}.*$", GUIDE.read_text(encoding="utf-8"), re.M)
    assert found is not None, f"docs/your-robot.md has no command starting {start!r}"
    return found.group(0)


def summary_of(path: Path) -> RunSummary:
    return RunSummary.model_validate(json.loads((path / "summary.json").read_text(encoding="utf-8")))


def test_the_imported_phantomx_on_its_ax12a_servos_warns_that_its_feet_slip(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    urdf = ROOT / "tests" / "data" / "robots" / "phantomx_description" / "urdf" / "phantomx.urdf"
    code, _, err = run(["import", "urdf", str(urdf), "--out", "myrobot"], capsys, monkeypatch)
    assert code == 0, err
    subprocess.run(["bash", "-c", guide_command("sed -i 's/^model = ")], check=True, cwd=tmp_path, timeout=60)
    code, out, err = run(["simulate", "myrobot/robots/PhantomX.toml", "--duration", "10", "--out", "runs/px-sim",
                          "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    summary = summary_of(tmp_path / "runs" / "px-sim")
    assert summary.servo_model == "AX-12A"  # was "from the URDF's joint limits" after the guide's sed
    assert not summary.fell
    line = out.strip().splitlines()[-1]
    warning = next((part for part in line.split(", warning: ")[1:] if part.startswith("feet slip")), None)
    assert warning is not None, line
    slip, distance = (float(x) for x in re.findall(r"([0-9.]+) m", warning)[:2])
    assert distance == pytest.approx(summary.distance_m or 0.0, rel=0.02) and slip > SLIP_SHARE * distance
    # the guide quotes the warning as the run prints it
    quoted = warning.split(" → ")[0].split(", joint speed limited")[0].rstrip(")") + ")"
    assert f'"warning: {quoted}"' in re.sub(r"\s+", " ", GUIDE.read_text(encoding="utf-8")), \
        f"docs/your-robot.md should quote: warning: {quoted}"
    commands = re.sub(r"\s+", " ", (ROOT / "docs" / "commands.md").read_text(encoding="utf-8"))
    assert f"`warning: {quoted}` (`docs/your-robot.md`'s PhantomX)" in commands, \
        f"docs/commands.md should quote: warning: {quoted}"


def test_a_good_walk_has_no_warning(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                    monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "walk"
    code, stdout, err = run(["simulate", "--duration", "5", "--out", str(out), "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    assert "warning" not in stdout and walk_warnings(out, summary_of(out)) == []


def test_a_walk_whose_centre_of_mass_is_outside_the_feet_is_statically_unstable(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    """The bundled robot with its body's centre of mass moved 0.8 m ahead, beyond the front feet (a property of the
    robot, not of the controller): the walk's median static margin is negative, and the line says so."""
    robot = tmp_path / "nose_heavy.toml"
    robot.write_text('extends = "bullet"\nname = "nose_heavy"\n\n[body]\ncom = [0.8, 0.0, 0.0]\n', encoding="utf-8")
    out = tmp_path / "walk"
    code, stdout, err = run(["simulate", str(robot), "--duration", "3", "--out", str(out), "--no-plots"], capsys,
                            monkeypatch)
    assert code == 0, err
    summary = summary_of(out)
    if summary.fell:  # a fall is reported as FELL, not warned about
        assert "FELL" in stdout and "warning: statically unstable" not in stdout, stdout
        return
    assert "warning: statically unstable (median static margin -" in stdout, stdout


def test_a_closed_path_is_not_taken_for_slipping(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """The share is of the distance walked along the path, not of the straight line from start to end: a square
    walked back to its start is not "feet slip … over 0.1 m"."""
    out = tmp_path / "square"
    code, stdout, err = run(["simulate", "--path", str(ROOT / "paths" / "square_2m.csv"), "--duration", "60", "--out",
                             str(out), "--no-plots"], capsys, monkeypatch)
    assert code == 0, err
    assert "feet slip" not in stdout, stdout


def test_a_run_without_its_log_has_no_warning(tmp_path: Path) -> None:
    assert walk_warnings(tmp_path / "missing", RunSummary.model_validate({"distance_m": 1.0})) == []


@pytest.mark.slow  # a 10 s walk of every bundled robot
@pytest.mark.parametrize("robot", ["bullet", "bullet_openshc", "openshc_default", "athena", "quadruped", "octopod"])
def test_no_bundled_robot_slips_on_flat_ground(robot: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    """SLIP_SHARE is well above what the bundled robots slide in their default gaits (docs/commands.md: under 10 %).
    Not bullet_mammalian: its bipod (two feet down) slid 0.50 m each over 3.04 m (16 %), and its line warns."""
    out = tmp_path / "walk"
    code, stdout, err = run(["simulate", robot, "--duration", "10", "--out", str(out), "--no-plots"], capsys,
                            monkeypatch)
    assert code == 0, err
    from shc_cli.analysis.metrics import analyze_log
    from shc_cli.domain.stored_run import open_run

    result = analyze_log(open_run(out))
    assert result["foot_slip_m"] < 0.10 * result["distance_m"], result["foot_slip_m"] / result["distance_m"]
    assert "feet slip" not in stdout
