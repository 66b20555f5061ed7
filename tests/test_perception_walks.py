"""``shc simulate --perception rays`` end to end: the simulated depth sensor's map in the loop (issue 40)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from shc_cli.domain.config import SimulationConfig
from shc_cli.domain.simulate import simulate

from .test_cli import run


def test_an_unknown_perception_mode_is_one_line_and_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    code, _, err = run(["simulate", "--perception", "eyes", "--duration", "1", "--out", str(tmp_path / "run")],
                       capsys, monkeypatch)
    assert code == 2, err
    assert "--perception" in err and "'off' or 'rays'" in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert not (tmp_path / "run").exists()


@pytest.mark.slow
def test_seeing_flat_ground_changes_nothing(tmp_path: Path) -> None:
    """On flat ground the map shows no step: speed and CoT as blind (issue 40: within 1 %; measured equal)."""
    summaries = {}
    for mode in ("off", "rays"):
        summaries[mode] = simulate(SimulationConfig(duration=8.0, out=tmp_path / mode, plots=False,
                                                    perception=mode)).summary
    blind, seeing = summaries["off"], summaries["rays"]
    assert blind.mean_speed_mps and blind.cot and seeing.mean_speed_mps and seeing.cot
    assert seeing.mean_speed_mps == pytest.approx(blind.mean_speed_mps, rel=0.01)
    assert seeing.cot == pytest.approx(blind.cot, rel=0.01)
    assert json.loads((tmp_path / "rays" / "summary.json").read_text())["perception"] == "rays"


def test_sweeps_take_perception_as_a_key_and_refuse_an_unknown_mode(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str],
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """sweeps/perception.toml loads (blind against seeing per terrain); a bad mode is one line naming the file's
    line, exit 2."""
    from shc_cli.spec.sweep import load_sweep

    from .conftest import ROOT

    sweep = load_sweep(ROOT / "sweeps" / "perception.toml")
    assert {point.options.get("perception") for point in sweep.points} == {"off", "rays"}
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\nduration = 1.0\n[fixed]\nperception = "eyes"\n', encoding="utf-8")
    code, _, err = run(["sweep", str(bad), "--out", str(tmp_path / "out")], capsys, monkeypatch)
    assert code == 2 and "bad.toml:4: fixed.perception: 'eyes'" in err and len(err.strip().splitlines()) == 1, err
