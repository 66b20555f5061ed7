"""``summary.json`` has one schema (:class:`shc_cli.record.summary.RunSummary`, ``shc schema summary``): what plan
writes follows it, a bad field is caught by the check the whole test session runs (conftest), and a run whose
summary has a field of the wrong type is refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

from shc_cli.cli import app
from shc_cli.record.summary import RunSummary, summary_schema

from .conftest import summary_problems


def test_schema_command_prints_the_summary_schema() -> None:
    result = CliRunner().invoke(app, ["schema", "summary"])
    assert result.exit_code == 0
    schema = json.loads(result.stdout)
    assert schema == summary_schema() and schema["additionalProperties"] is False
    for name, field in schema["properties"].items():  # docs/reference is generated from these descriptions
        assert field.get("description"), name
    assert {"cot", "mean_speed_mps", "complete", "stop_reason", "fault", "walkspace"} <= set(schema["properties"])


def test_the_session_check_catches_a_bad_field(tmp_path: Path) -> None:
    good = RunSummary(robot="bullet", cycles=10, cot=None, walkspace={"0": 0.16}).updated(complete=True)
    (tmp_path / "good").mkdir()
    (tmp_path / "good" / "summary.json").write_text(good.to_json(), encoding="utf-8")
    assert summary_problems(tmp_path) == []
    bad = tmp_path / "bad"
    bad.mkdir()
    for text in ('{"cycles": "ten"}', '{"cycles": -1}', '{"fell": "no"}', '{"no_such_key": 1}'):
        (bad / "summary.json").write_text(text, encoding="utf-8")
        [problem] = summary_problems(tmp_path)
        assert problem.startswith(f"{bad / 'summary.json'}: ")
    (bad / "summary.json").unlink()


def test_written_fields_are_the_ones_set(tmp_path: Path) -> None:
    """A kind of run writes only its own fields; one set to None is written as null (the file says it was
    computed and there is nothing, e.g. no cost of transport standing still)."""
    summary = RunSummary(robot="bullet", cot=None)
    assert json.loads(summary.to_json()) == {"robot": "bullet", "cot": None}
    assert json.loads(summary.updated(complete=False, stop_reason="SIGINT").to_json()) == {
        "robot": "bullet", "cot": None, "complete": False, "stop_reason": "SIGINT"}


@pytest.mark.parametrize(("text", "message"), [
    ('{"step_period_cycles": 1.5}', "step_period_cycles: 1.5"),
    ('{"robot": 5}', "robot: 5"),
    ('{"duty_factor": -0.5}', "duty_factor: -0.5"),
    ("[1, 2]", "not an object"),
])
def test_a_bad_summary_is_one_line(plan_dir: Path, tmp_path: Path, text: str, message: str) -> None:
    import shutil

    from shc_cli.errors import SpecError
    from shc_cli.record.runread import read_run

    run = tmp_path / "run"
    shutil.copytree(plan_dir, run)
    (run / "summary.json").write_text(text, encoding="utf-8")
    with pytest.raises(SpecError) as raised:
        read_run(run)
    assert len(str(raised.value).splitlines()) == 1 and message in str(raised.value)
    shutil.rmtree(run)  # not a summary the session check should see


def test_unknown_keys_of_other_versions_are_left_out(plan_dir: Path, tmp_path: Path) -> None:
    import shutil

    from shc_cli.record.runread import read_run

    run = tmp_path / "run"
    shutil.copytree(plan_dir, run)
    data = json.loads((run / "summary.json").read_text(encoding="utf-8"))
    (run / "summary.json").write_text(json.dumps({**data, "a_future_key": 1}), encoding="utf-8")
    assert read_run(run).summary.cycles == data["cycles"]
    shutil.rmtree(run)


@pytest.fixture(scope="module")
def plan_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shc_cli.domain.plan import plan

    path, summary = plan("bullet", None, "1,0,0", 0.5, None, tmp_path_factory.mktemp("plan") / "run", False).pair
    assert json.loads((path / "summary.json").read_text(encoding="utf-8")) == summary.model_dump(
        mode="json", exclude_unset=True)
    return path
