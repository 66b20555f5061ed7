"""End-to-end tests of the ``shc`` command on the shipped files."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from shc_cli import __version__
from shc_cli.cli import main

from .conftest import ROOT


def run(argv: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> tuple[int, str, str]:
    """Run ``shc`` in-process; return (exit code, stdout, stderr)."""
    monkeypatch.setattr(sys, "argv", ["shc", *argv])
    code = 0
    try:
        main()
    except SystemExit as done:
        code = int(done.code or 0)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def test_help_lists_every_command_with_one_line(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = run(["--help"], capsys, monkeypatch)
    assert code == 0
    from shc_cli.cli import app

    names = [c.name or (c.callback.__name__ if c.callback else "") for c in app.registered_commands]
    names += [g.name or "" for g in app.registered_groups]
    assert {"validate", "workspace", "plan", "simulate", "run-hw", "analyze", "sweep", "schema", "export",
            "import"} <= set(names)
    for command in names:  # every registered command and group, with its one-line help
        line = next((row for row in out.splitlines() if row.strip().startswith(f"{command} ")), "")
        assert len(line.split()) > 1, f"{command} missing from --help"


def test_version(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = run(["--version"], capsys, monkeypatch)
    assert (code, out.strip()) == (0, f"shc {__version__}")


def test_a_command_runs_in_an_app_of_its_own_with_the_same_help_and_errors() -> None:
    """``shc COMMAND …`` builds that command alone (``shc_cli.cli._app_for``: typer builds every command's options
    first); its help, its errors and the options before it are the whole app's."""
    from typer.testing import CliRunner

    from shc_cli.cli import _app_for, app

    assert [c.callback.__name__ for c in _app_for(["--debug", "run-hw", "x"]).registered_commands
            if c.callback] == ["run_hw"]
    for args in (["--help"], ["export", "bag"], ["nothere"], []):
        assert _app_for(args) is app
    runner = CliRunner()
    for args in (["simulate", "--help"], ["simulate", "--bogus"], ["--debug", "workspace", "--help"],
                 ["run-hw", "--help"], ["plan", "--duration"]):
        whole, alone = runner.invoke(app, args), runner.invoke(_app_for(args), args)
        assert _app_for(args) is not app
        assert (alone.exit_code, alone.output) == (whole.exit_code, whole.output) and whole.output


def test_help_imports_nothing_heavy() -> None:
    """``shc --help`` must not import numpy, numba, pydantic, matplotlib, nor the viewer or renderer (viser, mujoco,
    imageio-ffmpeg, Pillow): that is what keeps it ≈ 0.1 s (measured by benchmarks/bench_startup.py, not here —
    a timed test fails on a loaded machine)."""
    code = ("import sys; sys.argv = ['shc', '--help']\n"
            "from shc_cli.cli import main\n"
            "try:\n    main()\nexcept SystemExit:\n    pass\n"
            "heavy = [m for m in ('numpy', 'numba', 'pydantic', 'matplotlib', 'scipy', 'viser', 'mujoco', "
            "'imageio_ffmpeg', 'PIL', 'playwright', 'shc_cli.view') if m in sys.modules]\n"
            "print(heavy, file=sys.stderr)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stderr.strip() == "[]"
    assert "Usage" in result.stdout


def test_validate_all_shipped_files(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    files = sorted(str(p) for p in (ROOT / "robots").glob("*.toml")) + sorted(
        str(p) for p in (ROOT / "gaits").glob("*.toml"))
    code, out, err = run(["validate", *files], capsys, monkeypatch)
    assert (code, err) == (0, "")
    assert "bullet_openshc: 6 legs, 5 DOF per leg, 30 joints, mass 13.37 kg" in out
    assert "bullet: 6 legs, 5 DOF per leg, 30 joints, mass 10.07 kg" in out  # the paper's Table I
    assert "tripod" in out and "0.500   184 cyc    1.84 s (default)" in out
    assert "quadruped: 4 legs" in out and "octopod: 8 legs" in out


def test_validate_show_prints_the_expanded_robot_as_toml(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import tomllib

    code, out, _ = run(["validate", "bullet_mammalian", "--show"], capsys, monkeypatch)
    assert code == 0
    text = out.split("\n", 1)[1].split("\nbullet_mammalian:")[0]
    data = tomllib.loads(text)
    assert list(data["legs"]) == ["AR", "BR", "CR", "CL", "BL", "AL"]
    assert data["legs"]["CL"]["joints"]["coxat"]["min"] == 0.0
    assert data["walker"]["gait"] == "bipod"


def test_validate_reports_every_problem_in_one_line_each(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "bad.toml"
    text = (ROOT / "robots" / "bullet_openshc.toml").read_text()
    bad.write_text(text.replace("time_delta = 0.01", "time_delta = 0.01\nbody_clearence = 0.2"))
    code, out, err = run(["validate", str(bad)], capsys, monkeypatch)
    lines = err.strip().splitlines()
    assert code == 2 and out == ""
    assert lines == [f"error: {bad}:10: body_clearence: unknown key 'body_clearence' (allowed: name, description, "
                     "time_delta, body, legs, walker, cruise, ik, pose, start_up, posture, manipulation, admittance, "
                     "servo, hardware, perception)"]


def test_missing_robot_is_one_line_with_the_bundled_names(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, err = run(["workspace", "bulet"], capsys, monkeypatch)
    assert code == 2 and out == ""
    assert err.strip().splitlines() == [
        "error: bulet: no such robot file or bundled robot (did you mean 'bullet'? bundled: athena, athena_paper, "
        "bullet, bullet_insectoid_a, bullet_insectoid_b, bullet_mammalian, bullet_mammalian_a, bullet_mammalian_b, "
        "bullet_openshc, bullet_verified, octopod, openshc_default, quadruped)"]


def test_workspace_json_has_the_documented_keys_and_nothing_else_on_stdout(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, err = run(["workspace", "bullet_openshc", "--json"], capsys, monkeypatch)
    assert code == 0 and err == ""
    document = json.loads(out)
    for key in ("legs", "walkspace", "max_linear_speed", "max_angular_speed", "step_period_cycles",
                "walkspace_area_m2", "walkspace_stride_m"):
        assert key in document
    assert document["step_period_cycles"] == 184
    assert document["legs"]["AR"]["45"] == pytest.approx(0.363383191, abs=1e-6)
    assert document["walkspace"]["0"] == pytest.approx(0.16, abs=1e-9)
    assert document["max_linear_speed"]["90"] == pytest.approx(0.299845481, rel=1e-6)
    assert document["max_angular_speed"]["0"] == pytest.approx(0.503027149, rel=1e-6)


def test_workspace_writes_csv_and_png(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    out_dir = tmp_path / "ws"
    code, out, _ = run(["workspace", "openshc_default", "--bearings", "72", "--out", str(out_dir)], capsys,
                       monkeypatch)
    assert code == 0
    assert "walkspace" in out and "max linear speed" in out
    rows = (out_dir / "workspace.csv").read_text().splitlines()
    assert rows[0] == "leg,height_m,bearing_deg,radius_m"
    assert len(rows) == 1 + 7 * 73
    limits = (out_dir / "limits.csv").read_text().splitlines()
    assert len(limits) == 1 + 73
    png = (out_dir / "workspace.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    assert not list(out_dir.glob("*.partial*"))


def test_workspace_other_gait_and_frequency_changes_the_limits(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    _, out, _ = run(["workspace", "bullet_openshc", "--gait", "wave", "--json"], capsys, monkeypatch)
    wave = json.loads(out)
    assert wave["step_period_cycles"] == 552
    _, out, _ = run(["workspace", "bullet_openshc", "--step-frequency", "2.0", "--json"], capsys, monkeypatch)
    fast = json.loads(out)
    assert fast["step_period_cycles"] < 184
    assert fast["max_linear_speed"]["0"] > 0.2318


def test_bad_option_values_are_one_line(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, _, err = run(["workspace", "bullet", "--bearings", "7"], capsys, monkeypatch)
    assert code == 2
    assert err.strip() == "error: --bearings: 7 does not divide 360 (use 8, 12, 24, 36 or 72)"
    code, _, err = run(["workspace", "bullet", "--gait", "trot"], capsys, monkeypatch)
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "gait 'trot' does not fit robot 'bullet'" in err


def test_schema_is_json_schema_for_both_formats(capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = run(["schema", "robot"], capsys, monkeypatch)
    robot = json.loads(out)
    assert code == 0 and robot["title"] == "shc robot file"
    assert {"legs", "templates", "extends", "mirror", "walker"} <= set(robot["properties"])
    code, out, _ = run(["schema", "gait"], capsys, monkeypatch)
    gait = json.loads(out)
    assert code == 0 and {"stance_phase", "offset_multiplier"} <= set(gait["properties"])
    code, _, err = run(["schema", "sweep"], capsys, monkeypatch)
    assert code == 2 and err.startswith("error: schema: unknown kind 'sweep'")


def test_unwritable_output_is_one_line(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, _, err = run(["workspace", "openshc_default", "--out", str(blocker / "sub")], capsys, monkeypatch)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and "cannot create output directory" in err
