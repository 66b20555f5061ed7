"""The run-directory table reader (``shc_cli.record.runread._table``): mixed text and number columns in one pass of
numpy's parser, and one-line errors for a bad table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from shc_cli.errors import SpecError
from shc_cli.record.runread import _table


def test_text_and_number_columns_come_back_as_written(tmp_path: Path) -> None:
    file = tmp_path / "log.csv"
    file.write_text("cycle,t,robot_state,x,walk_state\n"
                    "0,0.0000,PACKED,1.5,STOPPED\n"
                    "1,0.0100,RUNNING,nan,MOVING\n"
                    "2,0.0200,RUNNING,-2e-3,STOPPED\n", encoding="utf-8")
    table = _table(file)
    assert sorted(table) == ["cycle", "robot_state", "t", "walk_state", "x"]
    assert table["robot_state"].tolist() == ["PACKED", "RUNNING", "RUNNING"]
    assert table["walk_state"].tolist() == ["STOPPED", "MOVING", "STOPPED"]
    assert table["robot_state"].dtype.kind == "U"
    assert table["t"].tolist() == [0.0, 0.01, 0.02]
    assert table["x"][0] == 1.5 and np.isnan(table["x"][1]) and table["x"][2] == -0.002
    assert table["cycle"].dtype == np.float64


@pytest.mark.parametrize(("content", "message"), [
    ("cycle,t\n", "no rows"),
    ("", "no rows"),
    ("cycle,t,state\n0,0.0,RUNNING\n1,oops,RUNNING\n", "malformed row"),
    ("cycle,t,state\n0,0.0,RUNNING\n1,0.01\n", "malformed row"),
    ("cycle,t,state\n0,0.0\n", "2 columns where the header has 3"),
])
def test_a_bad_table_is_one_line_naming_the_file(tmp_path: Path, content: str, message: str) -> None:
    file = tmp_path / "log.csv"
    file.write_text(content, encoding="utf-8")
    with pytest.raises(SpecError) as caught:
        _table(file)
    assert message in str(caught.value) and "log.csv" in str(caught.value)
    assert "\n" not in str(caught.value)


def test_a_table_that_is_not_utf8_says_where(tmp_path: Path) -> None:
    file = tmp_path / "log.csv"
    file.write_bytes(b"cycle,t,state\n0,0.0,RUNNING\n1,0.01,RUN\xffNING\n")
    with pytest.raises(SpecError, match="not UTF-8 text at byte"):
        _table(file)
