"""One rule for a command stopped by a signal: exit 130 (SIGINT, Ctrl-C) or 143 (SIGTERM) with one line saying what
was kept — sweep, optimize and render as plan and simulate (tests/test_interrupted.py); in-process for the rule,
in subprocesses for each long command."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from shc_cli.errors import Interrupted, Terminated, signal_name

from .conftest import ROOT
from .test_render import needs_gl

SHC = [sys.executable, "-m", "shc_cli.cli"]


def _main(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str], raised: BaseException
          ) -> tuple[int, str]:
    """Run ``shc validate bullet`` in-process with its command raising ``raised``."""
    from shc_cli import cli
    from shc_cli.commands import validate

    def stop(*_: object, **__: object) -> None:
        raise raised

    monkeypatch.setattr(validate, "run_validate", stop)
    monkeypatch.setattr(sys, "argv", ["shc", "validate", "bullet"])
    with pytest.raises(SystemExit) as done:
        cli.main()
    return int(done.value.code or 0), capsys.readouterr().err


@pytest.mark.parametrize(("raised", "code", "line"), [
    (Interrupted("3 runs finished, their rows are in x.csv"), 130, "error: interrupted by SIGINT: 3 runs finished"),
    (Interrupted("kept", "SIGTERM"), 143, "error: interrupted by SIGTERM: kept"),
    (KeyboardInterrupt(), 130, "error: interrupted by SIGINT; nothing was written"),
    (Terminated(), 143, "error: interrupted by SIGTERM; nothing was written"),
])
def test_an_interrupted_command_is_one_line_and_128_plus_the_signal(raised: BaseException, code: int, line: str,
                                                                    monkeypatch: pytest.MonkeyPatch,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    got, err = _main(monkeypatch, capsys, raised)
    assert got == code and err.startswith(line) and err.count("\n") == 1, err


def test_the_signal_is_found_through_the_causes() -> None:
    try:
        try:
            raise Terminated
        except KeyboardInterrupt as first:
            raise RuntimeError("wrapped") from first
    except RuntimeError as error:
        assert signal_name(error) == "SIGTERM"
    assert signal_name(KeyboardInterrupt()) == "SIGINT"
    assert signal_name(Interrupted("x", "SIGTERM")) == "SIGTERM"


def _signal_when(command: list[str], ready: Callable[[], bool], stop_signal: signal.Signals
                 ) -> subprocess.CompletedProcess[str]:
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        deadline = time.monotonic() + 240
        while not ready():
            if process.poll() is not None:
                pytest.fail(f"it ended before the signal: {process.communicate()}")
            if time.monotonic() > deadline:
                pytest.fail("not ready in time")
            time.sleep(0.05)
        process.send_signal(stop_signal)
        stdout, stderr = process.communicate(timeout=180)
    finally:
        process.kill()
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


SWEEP = """name = "stop"
duration = 1.0

[grid]
robot = ["bullet"]
"walker.step_frequency" = [0.8, 0.9, 1.0, 1.1, 1.2, 1.3]

[fixed]
"start_up.time_to_start" = 1.0
"""


@pytest.mark.slow  # simulations in a subprocess
@pytest.mark.parametrize(("stop_signal", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_sweep_keeps_its_rows_and_exits_128_plus_the_signal(stop_signal: signal.Signals, code: int,
                                                                           tmp_path: Path) -> None:
    sweep, out = tmp_path / "stop.toml", tmp_path / "out"
    sweep.write_text(SWEEP)
    partial = out / "results.partial.csv"
    done = _signal_when([*SHC, "sweep", str(sweep), "--workers", "1", "--out", str(out)],
                        lambda: partial.exists() and partial.read_text().count("\n") >= 2, stop_signal)
    lines = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == code, done.stderr
    assert len(lines) == 1 and lines[0].startswith(f"error: interrupted by {stop_signal.name}: ")
    assert "runs finished, their rows are in" in lines[0] and "--resume" in lines[0]
    assert partial.read_text().count("\n") >= 2


@pytest.mark.slow
def test_an_optimize_study_stopped_by_sigterm_keeps_its_trials_and_exits_143(tmp_path: Path) -> None:
    from .test_optimize import SMALL, _write
    from .test_sweep import _rows

    path, out = _write(tmp_path, SMALL.format(duration=30.0, seeds="[0]")), tmp_path / "out"

    def in_a_trial() -> bool:  # a trial's simulation is running (as a long study is, most of its time)
        return ((out / "trials.csv").exists() and len(_rows(out / "trials.csv")) >= 1
                and any(out.glob("runs/*.partial")))

    done = _signal_when([*SHC, "optimize", str(path), "--trials", "6", "--workers", "1", "--out", str(out)],
                        in_a_trial, signal.SIGTERM)
    lines = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == 143, done.stderr
    assert len(lines) == 1 and lines[0].startswith("error: interrupted by SIGTERM: ") and "trials finished" in lines[0]


@needs_gl
@pytest.mark.slow
@pytest.mark.parametrize(("stop_signal", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_an_interrupted_render_says_no_video_was_written(stop_signal: signal.Signals, code: int,
                                                         tmp_path: Path) -> None:
    run = tmp_path / "plan"
    subprocess.run([*SHC, "plan", "bullet_openshc", "--duration", "20", "--out", str(run), "--no-plots"], check=True,
                   capture_output=True, cwd=ROOT)
    video = tmp_path / "walk.mp4"
    partial = video.with_name(f".{video.name}.partial{video.suffix}")
    done = _signal_when([*SHC, "render", str(run), "--out", str(video), "--size", "320x180"], partial.exists,
                        stop_signal)
    lines = [line for line in done.stderr.splitlines() if line.startswith("error:")]
    assert done.returncode == code, done.stderr
    assert lines == [f"error: interrupted by {stop_signal.name}: no video written ({video} was not made; the run "
                     f"{run} is unchanged)"]
    assert not video.exists() and not partial.exists()


def test_main_puts_the_sigterm_handler_back(monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
                                            ) -> None:
    """In-process callers (the tests, a notebook) keep their own SIGTERM handling after main()."""
    before = signal.getsignal(signal.SIGTERM)
    _main(monkeypatch, capsys, Interrupted("kept"))
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.slow
def test_a_sigterm_to_a_sweep_with_workers_stops_their_runs_too(tmp_path: Path) -> None:
    """A SIGTERM reaches only the sweep's own process (a Ctrl-C reaches its workers too): the sweep passes it on, so
    the runs under way end as partial runs (``stop_reason`` SIGTERM), kept for --resume, the runs waiting in the
    workers' queues do not start (they ran to their end: 20 s more), and it exits 143."""
    import json

    sweep, out = tmp_path / "stop.toml", tmp_path / "out"
    sweep.write_text(SWEEP.replace("duration = 1.0", "duration = 20.0"))
    done = _signal_when([*SHC, "sweep", str(sweep), "--workers", "2", "--out", str(out)],
                        lambda: len(list(out.glob("runs/*.partial/log.csv"))) == 2, signal.SIGTERM)
    assert done.returncode == 143, done.stderr
    assert "error: interrupted by SIGTERM: " in done.stderr
    stopped = [json.loads(path.read_text())["stop_reason"] for path in out.glob("runs/*/summary.json")]
    assert stopped == ["SIGTERM", "SIGTERM"], stopped  # and the runs queued in the workers did not start
