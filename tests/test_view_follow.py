"""``shc view RUN --follow`` without a browser: what the follower reads of a run directory being written (a row cut
mid-write is left for the next read; a kinematic run's tables are cut to the same length), and the finished run
taking over (tests/test_view.py follows a real simulation in Chromium)."""

from __future__ import annotations

import shutil
import time
from pathlib import Path

import numpy as np
import pytest

from shc_cli.errors import ShcError
from shc_cli.record.runread import read_run
from shc_cli.view.follow import Follower, run_paths, snapshot


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shc_cli import api

    out = tmp_path_factory.mktemp("follow") / "plan"
    api.plan("bullet", duration=2.0, out=out, plots=False)
    return out


def _in_progress(finished: Path, where: Path, cut: dict[str, int]) -> Path:
    """A copy of a finished run as it looked while running: ``RUN.partial`` without its summary, each table cut
    after ``cut[name]`` bytes."""
    partial = where / "run.partial"
    shutil.copytree(finished, partial)
    (partial / "summary.json").unlink()
    for name, size in cut.items():
        data = (partial / name).read_bytes()
        (partial / name).write_bytes(data[:size])
    return partial


def test_complete_rows_only_and_the_tables_cut_to_one_length(planned: Path, tmp_path: Path) -> None:
    full = read_run(planned)
    joints = (planned / "joints.csv").read_bytes()
    lines = joints.splitlines(keepends=True)
    cut = len(b"".join(lines[:51])) + 7  # the header, 50 rows and 7 bytes of the 51st
    partial = _in_progress(planned, tmp_path, {"joints.csv": cut})
    run = snapshot(partial)
    assert run is not None and run.path == partial and len(run.t) == 50  # body.csv has more rows: cut to 50
    assert np.array_equal(run.joints, full.joints[:50]) and np.array_equal(run.position, full.position[:50])
    assert np.array_equal(run.t, full.t[:50])


def test_nothing_yet_and_no_such_run(tmp_path: Path) -> None:
    partial = tmp_path / "run.partial"
    partial.mkdir()
    assert snapshot(partial) is None  # no robot file, no rows
    with pytest.raises(ShcError, match="no run in progress"):
        run_paths(str(tmp_path / "other"))
    assert run_paths(str(tmp_path / "run")) == run_paths(str(partial)) == (partial, tmp_path / "run")


def test_the_follower_reports_growth_then_the_finished_run(planned: Path, tmp_path: Path) -> None:
    partial = _in_progress(planned, tmp_path, {})
    header = (planned / "joints.csv").read_bytes().splitlines(keepends=True)[0]
    rows = {name: (planned / name).read_bytes().splitlines(keepends=True) for name in ("joints.csv", "body.csv",
                                                                                    "tips.csv")}
    for name, lines in rows.items():
        (partial / name).write_bytes(b"".join(lines[:11]))  # 10 rows written so far
    seen: list[tuple[int, bool]] = []
    follower = Follower(partial, tmp_path / "run", lambda run, finished: seen.append((len(run.t), finished)))
    assert len(follower.first().t) == 10 and header
    follower.start()
    try:
        for name, lines in rows.items():
            (partial / name).write_bytes(b"".join(lines[:101]))  # 100 rows
        deadline = time.monotonic() + 20
        while not seen and time.monotonic() < deadline:
            time.sleep(0.1)
        shutil.copytree(planned, tmp_path / "done")  # the run finishes: complete, it gets its name
        shutil.rmtree(partial)
        (tmp_path / "done").rename(tmp_path / "run")
        while (not seen or not seen[-1][1]) and time.monotonic() < deadline:
            time.sleep(0.1)
    finally:
        follower.stop()
    assert seen[0] == (100, False) and seen[-1] == (len(read_run(planned).t), True)
