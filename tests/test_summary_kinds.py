"""Summaries per kind of run on a shared base (shc_cli/record/summary_kinds.py): every summary.json field belongs to
the shared base or a kind, a kind's model refuses another kind's field, a summary made through its kind is the one
RunSummary writes (same keys, values and order), and each kind of run writes only its kind's fields."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from pydantic import ValidationError

from shc_cli import api
from shc_cli.record.summary import RunSummary
from shc_cli.record.summary_kinds import KINDS, SHARED, kind_model, summary_of


def test_every_field_is_shared_or_of_a_kind_and_named_once_per_group() -> None:
    grouped = [SHARED, *KINDS.values()]
    assert all(len(group) == len(set(group)) for group in grouped)
    assert set(SHARED).union(*KINDS.values()) == set(RunSummary.model_fields)


def test_a_kind_refuses_a_field_it_does_not_write() -> None:
    with pytest.raises(ValidationError, match="eq16_speed_mps"):
        summary_of(("simulate",), {"robot": "bullet", "eq16_speed_mps": 0.1})  # a plan field
    with pytest.raises(ValidationError, match="cot"):
        summary_of(("hardware", "ros"), {"cot": 1.0})
    assert "node" in kind_model("plan", "ros").model_fields and "node" not in kind_model("plan").model_fields


def test_a_summary_made_through_its_kind_keeps_the_keys_values_and_order() -> None:
    fields = {"stop_reason": "SIGINT", "robot": "bullet", "cycles": 12, "fault": None, "complete": False,
              "port": "/dev/ttyUSB0"}
    made = summary_of(("hardware",), fields)
    direct = RunSummary.model_validate(fields)
    assert made.to_json() == direct.to_json()
    assert list(json.loads(made.to_json())) == ["robot", "cycles", "port", "fault", "complete", "stop_reason"]


@pytest.mark.slow  # a plan and a simulation
def test_plan_and_simulate_write_only_their_kinds_fields(tmp_path: Path) -> None:
    plan = api.plan("bullet", duration=1.0, out=tmp_path / "plan", plots=False)
    simulate = api.simulate("bullet", engine="mujoco", duration=1.0, out=tmp_path / "sim", plots=False)
    for path, kind in ((tmp_path / "plan", "plan"), (tmp_path / "sim", "simulate")):
        written = set(json.loads((path / "summary.json").read_text()))
        assert written <= set(SHARED) | set(KINDS[kind]), written - set(SHARED) - set(KINDS[kind])  # type: ignore[index]
        assert {"complete", "stop_reason", "joint_speed_limited_cycles"} <= written
    assert plan.summary.walkspace and simulate.summary.mass_kg and simulate.summary.engine == "mujoco"
