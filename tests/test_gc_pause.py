"""``shc simulate`` pauses Python's cyclic garbage collector in its set-up and finishing (0.1–0.2 s of the 60 s
walk's command were collections going over numba's, MuJoCo's and matplotlib's objects) and collects in the run loop
(an open-ended run's memory stays bounded)."""

from __future__ import annotations

import gc
from pathlib import Path
from typing import Any

import pytest

from shc_cli.loop.gc_pause import collecting, paused

from .test_cli import run


def test_paused_turns_the_collector_off_except_in_collecting_and_restores_it() -> None:
    assert gc.isenabled()
    with paused():
        assert not gc.isenabled()
        with paused():  # nested: nothing changes
            assert not gc.isenabled()
        assert not gc.isenabled()
        with collecting():
            assert gc.isenabled()
            assert gc.get_freeze_count() > 0  # the set-up's objects are not scanned again by the loop's passes
        assert not gc.isenabled()
    assert gc.isenabled() and gc.get_freeze_count() == 0
    with collecting():  # outside a paused block: as it was
        assert gc.isenabled()
    assert gc.get_freeze_count() == 0


def test_paused_restores_the_collector_when_the_block_raises() -> None:
    with pytest.raises(RuntimeError), paused():
        raise RuntimeError("stop")
    assert gc.isenabled() and gc.get_freeze_count() == 0


def test_simulate_collects_in_its_loop_and_video_only(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                            monkeypatch: pytest.MonkeyPatch) -> None:
    from shc_cli import plots
    from shc_cli.loop.run_loop import RunLoop

    seen: dict[str, bool] = {}
    loop_run, plot_simulation = RunLoop.run, plots.plot_simulation

    def watched_run(self: Any) -> Any:
        seen["loop"] = gc.isenabled()
        return loop_run(self)

    def watched_plots(*args: Any, **kwargs: Any) -> None:
        seen["plots"] = gc.isenabled()
        plot_simulation(*args, **kwargs)

    def watched_video(run_dir: Path, video: Path) -> None:  # --video's work grows with the run: collected
        seen["video"] = gc.isenabled()

    monkeypatch.setattr(RunLoop, "run", watched_run)
    monkeypatch.setattr(plots, "plot_simulation", watched_plots)
    monkeypatch.setattr("shc_cli.commands.render.render_video", watched_video)
    code, _, err = run(["simulate", "--duration", "0.2", "--out", str(tmp_path / "run"), "--video",
                        str(tmp_path / "run.gif")], capsys, monkeypatch)
    assert code == 0, err
    assert seen == {"loop": True, "plots": False, "video": True}
    assert gc.isenabled() and gc.get_freeze_count() == 0  # the process's collector as it was
    assert (tmp_path / "run" / "power.png").is_file()


def test_the_cli_process_freezes_its_objects_at_exit_and_still_flushes_its_log(tmp_path: Path) -> None:
    """The interpreter's last collection at exit (0.17 s of a simulation's command) has nothing to go over: every
    object is frozen first; a logging file handler left open is still flushed and closed (logging's own exit)."""
    import subprocess
    import sys

    log = tmp_path / "events.log"
    code = f"""
import atexit, gc, logging
atexit.register(lambda: print("frozen at exit:", gc.get_freeze_count() > 0))  # runs after shc's handler
handler = logging.FileHandler(r"{log}")
logging.getLogger("check").addHandler(handler)
from shc_cli.loop.gc_pause import no_collection_at_exit
no_collection_at_exit()
no_collection_at_exit()
logging.getLogger("check").warning("written at exit")
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["frozen at exit: True"]
    assert log.read_text() == "written at exit\n"
