"""``shc analyze --reference``: the speed along the commanded heading retained vs an intact run, and falls
(issue 39)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest


@pytest.fixture(scope="module")
def runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, Path]:
    from shc_cli import api

    base = tmp_path_factory.mktemp("retained")
    intact = api.plan("bullet", duration=10.0, out=base / "intact", plots=False).path
    failed = api.plan("bullet", duration=10.0, out=base / "br", plots=False, fail_leg="BR").path
    sideways = api.plan("bullet", duration=10.0, out=base / "side", plots=False, velocity="0,1,0").path
    return intact, failed, sideways


def test_a_kinematic_walks_heading_speed_is_its_stance_feet_speed(runs: tuple[Path, Path, Path]) -> None:
    """A plan moves the body as commanded: the median per-cycle speed along the heading is the steady stance-feet
    speed the plan reports (eq. 16 of the CoT study, computed from the gait's stride and timing) within 2 % (the
    ramp-up reaches into the first whole cycles of a 10 s plan)."""
    from shc_cli.analysis.metrics import Window
    from shc_cli.analysis.retained import heading_speed
    from shc_cli.api import open_run

    for run in runs:
        summary = json.loads((run / "summary.json").read_text())
        assert heading_speed(open_run(run), Window()) == pytest.approx(summary["eq16_speed_mps"], rel=0.02)


def test_analyze_reports_the_share_retained_and_falls(runs: tuple[Path, Path, Path],
                                                      capsys: pytest.CaptureFixture[str],
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    from shc_cli.cli import main

    intact, failed, _ = runs
    monkeypatch.setattr(sys, "argv", ["shc", "analyze", str(intact), str(failed), "--reference", str(intact),
                                      "--json"])
    with pytest.raises(SystemExit) as done:
        main()
    assert done.value.code in (0, None)
    rows = json.loads(capsys.readouterr().out)
    speeds = [json.loads((run / "summary.json").read_text())["eq16_speed_mps"] for run in (intact, failed)]
    assert rows[0]["speed_retained"] == pytest.approx(1.0)
    assert rows[1]["speed_retained"] == pytest.approx(speeds[1] / speeds[0], rel=0.02)
    assert rows[1]["fell"] is False and "stability_margin_median_m" in rows[1]
    monkeypatch.setattr(sys, "argv", ["shc", "analyze", str(failed), "--reference", str(intact)])
    with pytest.raises(SystemExit):
        main()
    table = capsys.readouterr().out
    assert "retained" in table.splitlines()[0]
    shown = [float(cell[:-1]) / 100 for cell in table.splitlines()[1].split() if cell.endswith("%")]
    assert shown and shown[-1] == pytest.approx(speeds[1] / speeds[0], rel=0.02)  # heading speed vs eq. 16
