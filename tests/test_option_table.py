"""The one option table of ``shc simulate`` (shc_cli/domain/options.py): the command line, the API's config and
keywords and the sweep/study options agree with it; every out-of-range value is one line and exit 2 wherever it is
given; friction 0 warns; a physics blow-up stops the run, named, exit 5."""

from __future__ import annotations

import math
import sys
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from shc_cli.domain.config import SimulationConfig, SimulationOptions
from shc_cli.domain.options import SIMULATE
from shc_cli.errors import SpecError


def _cli_params() -> dict[str, Any]:
    import typer.main

    from shc_cli.cli import app

    command = typer.main.get_command(app).commands["simulate"]  # type: ignore[attr-defined]
    return {param.name: param.default for param in command.params}


def test_the_command_line_has_the_tables_options_and_defaults() -> None:
    cli = _cli_params()
    # simulate's options that only choose outputs beside the run (not the simulation's): --bag, --video
    assert set(cli) - {"bag", "video"} == set(SIMULATE)
    assert {name: cli[name] for name in SIMULATE} == {name: option.default for name, option in SIMULATE.items()}


def test_the_command_lines_help_of_every_bounded_number_is_the_tables() -> None:
    import typer.main

    from shc_cli.cli import app

    command = typer.main.get_command(app).commands["simulate"]  # type: ignore[attr-defined]
    helps = {param.name: getattr(param, "help", None) for param in command.params}
    bounded = [name for name, option in SIMULATE.items() if option.low is not None and name != "live_port"]
    assert bounded == ["duration", "physics_rate", "friction", "restitution", "seed", "imu_noise", "imu_yaw_bias",
                       "watchdog"]
    assert {name: helps[name] for name in bounded} == {name: SIMULATE[name].cli_help for name in bounded}
    assert SIMULATE["restitution"].cli_help.endswith("Range: [0, 1].")
    assert SIMULATE["watchdog"].cli_help.endswith("Range: (0, 3600] s.")


def test_the_config_and_the_api_keywords_are_the_table() -> None:
    fields = SimulationConfig.model_fields
    assert list(fields) == list(SIMULATE)  # the same order too (sweep files list them so)
    assert {name: field.default for name, field in fields.items()} == {
        name: option.default for name, option in SIMULATE.items()}
    assert set(SimulationOptions.__annotations__) == set(SIMULATE) - {"robot"}


def test_sweep_and_study_options_are_the_table_but_the_per_run_ones() -> None:
    from shc_cli.domain.sweeps.options import OPTIONS, PER_RUN, option
    from shc_cli.spec.sweep import STRIDE

    assert set(SIMULATE) >= PER_RUN
    assert list(OPTIONS) == [name for name in SIMULATE if name not in PER_RUN] + [STRIDE]
    point = SimpleNamespace(options={})
    assert all(option(point, name) == SIMULATE[name].default for name in OPTIONS if name != STRIDE)  # type: ignore[arg-type]


BAD = [("friction", -1.0, "--friction: -1.0 is out of range: friction must be in [0, 10]"),
       ("friction", math.nan, "--friction: nan is not a finite number"),
       ("restitution", 5.0, "--restitution: 5.0 is out of range: restitution must be in [0, 1]"),
       ("restitution", -1.0, "--restitution: -1.0 is out of range"),
       ("imu_noise", -1.0, "--imu-noise: -1.0 is out of range: imu_noise must be in [0, 100]"),
       ("seed", -1, "--seed: -1 is out of range: seed must be in [0, 4294967295]"),
       ("duration", 0.0, "--duration: 0.0 is out of range: duration must be in (0, 1000000] s"),
       ("physics_rate", -400.0, "--physics-rate: -400.0 is out of range"),
       ("imu_yaw_bias", 91.0, "--imu-yaw-bias: 91.0 is out of range: imu_yaw_bias must be in [-90, 90] deg/s"),
       ("watchdog", math.inf, "--watchdog: inf is not a finite number"),
       ("live_port", 70000, "--live-port: 70000 is out of range: live_port must be in [0, 65535]")]


@pytest.mark.parametrize(("name", "value", "message"), BAD)
def test_an_out_of_range_value_is_one_line_in_the_config(name: str, value: object, message: str) -> None:
    with pytest.raises(SpecError) as raised:
        SimulationConfig(**{name: value})
    assert str(raised.value).startswith(message) and "\n" not in str(raised.value)
    assert f"give e.g. {SIMULATE[name].flag}" in str(raised.value)


@pytest.mark.parametrize(("name", "value", "message"), BAD[:6])
def test_an_out_of_range_value_on_the_command_line_is_exit_2(name: str, value: object, message: str,
                                                             capsys: pytest.CaptureFixture[str],
                                                             monkeypatch: pytest.MonkeyPatch,
                                                             tmp_path: Path) -> None:
    from shc_cli.cli import main

    monkeypatch.setattr(sys, "argv", ["shc", "simulate", "--out", str(tmp_path / "run"), SIMULATE[name].flag,
                                      str(value)])
    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 2 and err.startswith(f"error: {message}") and err.count("\n") == 1, err
    assert not (tmp_path / "run").exists()


def test_the_api_refuses_the_same_values_before_writing(tmp_path: Path) -> None:
    from shc_cli import api

    with pytest.raises(SpecError, match=r"--restitution: 5\.0 is out of range"):
        api.simulate(restitution=5.0, out=tmp_path / "run")
    with pytest.raises(SpecError, match="--seed: -1 is out of range"):
        api.simulate(seed=-1, out=tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_a_sweep_and_a_study_refuse_them_with_their_line(tmp_path: Path) -> None:
    from shc_cli.domain.sweeps.options import check_study, check_sweep
    from shc_cli.spec.study import load_study
    from shc_cli.spec.sweep import load_sweep

    sweep = tmp_path / "sweep.toml"
    sweep.write_text('name = "s"\n\n[[grid]]\nrobot = ["bullet"]\nfriction = [0.9, -1.0]\n')
    with pytest.raises(SpecError) as raised:
        check_sweep(load_sweep(sweep))
    assert "grid.friction: -1.0 is out of range: friction must be in [0, 10]" in str(raised.value)
    assert str(raised.value).startswith(str(sweep) + ":")
    study = tmp_path / "study.toml"
    study.write_text('name = "s"\nrobot = "bullet"\ntrials = 2\n\n[space]\nrestitution = { low = 0.0, high = 3.0 }\n'
                     '\n[objectives]\ncot = "minimize"\n')
    with pytest.raises(SpecError) as raised:
        check_study(load_study(study))
    assert "space.restitution.high: 3.0 is out of range: restitution must be in [0, 1]" in str(raised.value)


def test_friction_0_is_legal_but_warned() -> None:
    assert SimulationConfig(friction=0.9).warnings() == []
    (warning,) = SimulationConfig(friction=0.0).warnings()
    assert warning.startswith("friction 0: the feet slide freely")


def _reading(position: tuple[float, float, float], velocity: tuple[float, float, float]) -> Any:
    return SimpleNamespace(position=np.array(position), linear_velocity=np.array(velocity), rpy=np.zeros(3),
                           body_height=0.1)


@pytest.mark.parametrize(("position", "velocity", "diverged"), [
    ((0.0, 0.0, 0.1), (0.2, 0.0, 0.0), False),
    ((0.0, 0.0, 0.1), (19.0, 0.0, 0.0), False),
    ((0.0, 0.0, 0.1), (12.0, 12.0, 12.0), True),  # 20.8 m/s
    ((0.0, 0.0, 0.1), (math.nan, 0.0, 0.0), True),
    ((math.nan, 0.0, 0.1), (0.0, 0.0, 0.0), True),
    ((0.0, math.inf, 0.1), (0.0, 0.0, 0.0), True),
])
def test_the_fall_observer_names_a_physics_blow_up(position: tuple[float, float, float],
                                                   velocity: tuple[float, float, float], diverged: bool) -> None:
    from shc_cli.api import load_robot
    from shc_cli.control.controller import RobotState
    from shc_cli.loop.physics_summary import DIVERGED, PhysicsRecord

    record = PhysicsRecord(load_robot("bullet"), None, airborne=True)  # type: ignore[arg-type]
    out = SimpleNamespace(robot_state=RobotState.PACKED)
    stop = record(7, None, out, _reading(position, velocity))  # type: ignore[arg-type]
    assert (stop == DIVERGED) is diverged and (record.diverged is not None) is diverged
    if diverged:
        assert record.diverged is not None and record.diverged.startswith("the physics diverged at cycle 7: body speed")


def test_a_blow_up_stops_the_simulation_named_and_exits_6(capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """A physics step too coarse for the servo law (ATHENA's 22 g tibias at 20 Hz, docs/experiments/athena-posture.md)
    makes MuJoCo explode; before, such a run ended "FELL" with exit 0 and megawatts of mean power (restitution 5 did
    it too, when MuJoCo mapped restitution onto a bouncing contact); now the loop stops it at once."""
    import json

    from shc_cli.cli import main

    out = tmp_path / "run"
    monkeypatch.setattr(sys, "argv", ["shc", "simulate", "athena_paper", "--physics-rate", "20", "--duration", "5",
                                      "--no-plots", "--out", str(out)])
    with pytest.raises(SystemExit) as done:
        main()
    captured = capsys.readouterr()
    assert done.value.code == 6, captured.err
    assert "PHYSICS DIVERGED" in captured.out
    (line,) = [line for line in captured.err.splitlines() if line.startswith("error:")]
    assert line.startswith("error: the physics diverged at cycle ") and "directory is kept" in line
    summary = json.loads((out / "summary.json").read_text())
    assert summary["stop_reason"] == "diverged" and summary["fault"].startswith("the physics diverged")
    assert summary["sim_time_s"] < 3.0


def test_friction_0_warns_on_the_command_line(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
                                              tmp_path: Path) -> None:
    from shc_cli.cli import main

    monkeypatch.setattr(sys, "argv", ["shc", "simulate", "--friction", "0", "--duration", "0.5", "--no-plots",
                                      "--out", str(tmp_path / "ice")])
    with pytest.raises(SystemExit) as done:
        main()
    err = capsys.readouterr().err
    assert done.value.code == 0, err
    assert "warning: friction 0: the feet slide freely, so the run's distance and speed are sliding, not walking" in err


def test_a_sweep_point_whose_physics_diverged_is_a_failed_row(monkeypatch: pytest.MonkeyPatch,
                                                              tmp_path: Path) -> None:
    """No figure of a blown-up run is a result: its row fails (a study's trial then fails too) instead of ranking
    its megawatts and runaway speed."""
    from shc_cli import api

    sweep = tmp_path / "boom.toml"
    sweep.write_text('name = "boom"\nduration = 2.0\n\n[grid]\nrobot = ["athena_paper"]\n'
                     'physics_rate = [400.0, 20.0]\n')
    report = api.sweep(sweep, workers=1, out=tmp_path / "out")
    rows = {float(row["physics_rate"]): row for row in report.rows}
    assert rows[400.0]["status"] == "ok" and rows[400.0]["error"] == ""
    assert rows[20.0]["status"] == "failed"
    assert str(rows[20.0]["error"]).startswith("the physics diverged at cycle ")
