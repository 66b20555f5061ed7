"""The public Python API: the worked example of docs/python-api.md runs as written, and its objects hold what the
CLI writes."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

from .conftest import ROOT


def _example() -> str:
    text = (ROOT / "docs" / "python-api.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.DOTALL)
    assert len(blocks) == 1
    return str(blocks[0])


def test_the_documented_example_runs(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                     capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    names: dict[str, object] = {}
    exec(compile(_example(), "docs/python-api.md", "exec"), names)
    run, planned, table = names["run"], names["planned"], names["table"]
    summary = json.loads((tmp_path / "runs" / "api-walk" / "summary.json").read_text())
    assert run.summary.model_dump(mode="json", exclude_unset=True) == summary  # type: ignore[attr-defined]
    assert run.complete and run.summary.fell is False and summary["fell"] is False  # type: ignore[attr-defined]
    assert run.log.position.shape == (round(summary["sim_time_s"] / 0.01), 3)  # type: ignore[attr-defined]
    assert names["result"]["cot"] == summary["cot"]  # type: ignore[index]  # the summary is the log's analysis
    assert planned.summary.achieved_mean_speed_mps == pytest.approx(  # type: ignore[attr-defined]
        planned.summary.eq16_speed_mps, rel=0.01)  # type: ignore[attr-defined]
    assert [row["status"] for row in table.rows] == ["ok", "ok"]  # type: ignore[attr-defined]
    out = capsys.readouterr().out
    assert "bullet has legs AR, BR, CR, CL, BL, AL" in out and "0.8 Hz: ok CoT" in out


def test_import_is_light_and_names_resolve() -> None:
    code = ("import sys, shc_cli\n"
            "heavy = [m for m in ('numpy', 'pydantic', 'matplotlib', 'pybullet') if m in sys.modules]\n"
            "names = [getattr(shc_cli, n) for n in shc_cli.__all__]\n"
            "print(heavy, len(names))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    from shc_cli import __all__ as exported

    assert result.stdout.split("]")[0] == "[" and result.stdout.strip().endswith(str(len(exported)))


def test_errors_are_exceptions_not_exits(tmp_path: Path) -> None:
    import shc_cli

    with pytest.raises(shc_cli.SpecError, match="--scenario"):
        shc_cli.simulate(scenario="XX", out=tmp_path / "x")
    with pytest.raises(shc_cli.ShcError):
        shc_cli.load_robot("no_such_robot")


def test_an_output_error_names_the_api_argument_not_the_cli_option(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 42 point 12: a second run into the same folder said "add --overwrite", an option the API does not
    have."""
    import shc_cli
    from shc_cli import api
    from shc_cli.errors import OutputError

    monkeypatch.chdir(tmp_path)
    (tmp_path / "runs" / "twice").mkdir(parents=True)
    with pytest.raises(OutputError) as refused:
        shc_cli.plan("bullet", duration=0.5, out="runs/twice", plots=False)
    message = str(refused.value)
    assert message == "runs/twice: already exists (pass overwrite=True to replace it, or choose another out)"
    assert "--" not in message
    with pytest.raises(OutputError, match=r"already exists \(pass overwrite=True"):
        api.fit_plan("bullet", out=tmp_path / "runs" / "twice")
