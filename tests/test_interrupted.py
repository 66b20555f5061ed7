"""Interrupted runs (SIGINT/SIGTERM) are finished run directories marked ``"complete": false``; exit codes of runs
that failed (a servo fault, a fall with --fail-on-fall); ``--gui`` without a display."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from shc_cli.record.runread import read_run

SHC = [sys.executable, "-m", "shc_cli.cli"]


def _wait_rows(table: Path, running: bool = True, timeout_s: float = 120.0) -> None:
    """Wait until a streamed table of a run in progress has flushed rows (RUNNING ones if ``running``)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if table.exists():
            text = table.read_text()
            if text.count("\n") > 2 and (not running or ",RUNNING," in text):
                return
        time.sleep(0.1)
    raise AssertionError(f"{table}: no rows")


def _interrupt(args: list[str], table: Path, stop_signal: signal.Signals, twice: bool = False
               ) -> subprocess.CompletedProcess[str]:
    process = subprocess.Popen([*SHC, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_rows(table)
        process.send_signal(stop_signal)
        if twice:  # a second Ctrl-C while the run is being finished
            time.sleep(0.05)
            process.send_signal(stop_signal)
        stdout, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr)


def _check_readers(run: Path, tmp_path: Path) -> None:
    """``analyze`` and ``export bag`` accept the interrupted run and say it is partial."""
    analysis = subprocess.run([*SHC, "analyze", str(run), "--json"], capture_output=True, text=True, timeout=120)
    assert analysis.returncode == 0, analysis.stderr
    report = json.loads(analysis.stdout)
    assert report["complete"] is False and report["stop_reason"] in ("SIGINT", "SIGTERM")
    assert "a partial run (stopped by SIG" in analysis.stderr
    bag = subprocess.run([*SHC, "export", "bag", str(run), "--out", str(tmp_path / "run_bag")], capture_output=True,
                         text=True, timeout=120)
    assert bag.returncode == 0, bag.stderr
    assert "a partial run" in bag.stderr and (tmp_path / "run_bag" / "metadata.yaml").exists()


@pytest.mark.slow  # signals sent to shc subprocesses mid-run
def test_interrupted_plan_is_a_finished_partial_run(tmp_path: Path) -> None:
    run = tmp_path / "plan"
    result = _interrupt(["plan", "--duration", "3000", "--no-plots", "--out", str(run)],
                        run.with_name("plan.partial") / "body.csv", signal.SIGINT)
    assert result.returncode == 130, result.stderr
    assert "INTERRUPTED (SIGINT; partial run)" in result.stdout and str(run) in result.stdout
    assert not run.with_name("plan.partial").exists()
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is False and summary["stop_reason"] == "SIGINT"
    rows = (run / "joints.csv").read_text().splitlines()
    assert len(rows) - 1 == summary["cycles"] < 300_000 + summary["startup_cycles"]  # every cycle run, no more
    assert all(len((run / name).read_text().splitlines()) == len(rows) for name in ("tips.csv", "body.csv"))
    _check_readers(run, tmp_path)


@pytest.mark.parametrize("twice", [False, True])
@pytest.mark.slow  # signals sent to shc subprocesses mid-run
def test_interrupted_simulate_is_a_finished_partial_run(twice: bool, tmp_path: Path) -> None:
    """SIGTERM: the run directory is finished (summary, plots unless a second signal skipped them); a second signal
    while finishing still leaves every logged row."""
    run = tmp_path / "sim"
    result = _interrupt(["simulate", "--duration", "600", "--out", str(run)], run.with_name("sim.partial") / "log.csv",
                        signal.SIGTERM, twice)
    assert result.returncode == 143, result.stderr
    assert "Traceback" not in result.stderr
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is False and summary["stop_reason"] == "SIGTERM"
    log = read_run(run)
    assert not log.complete and log.running.any()
    assert len(log.t) == round(summary["sim_time_s"] / log.dt) < 60_000  # every logged cycle, stopped early
    if not twice:
        assert (run / "trajectory.png").stat().st_size > 0
    _check_readers(run, tmp_path)


@pytest.mark.slow  # signals sent to shc subprocesses mid-run
def test_interrupted_run_hw_is_marked_partial(tmp_path: Path) -> None:
    """On the emulated bus: Ctrl-C stops walking and shuts down (exit 0, the normal end of an open-ended run); the
    summary says the run did not play its input to the end, and analyze and export bag say so."""
    from tests.run_waits import wait_running
    from tests.test_run_hw import _bus

    run = tmp_path / "hw"
    with _bus() as bus:
        process = subprocess.Popen([*SHC, "run-hw", "bullet", "--port", bus.port, "--out", str(run), "--velocity",
                                    "1,0,0", "--duration", "60"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                   text=True)
        wait_running(run, process, extra_s=1.0)  # as test_run_hw's Ctrl-C test: into walking
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=120)
        assert process.returncode == 0, stderr
        assert bus.ids() and all(bus.table(i, 64) == b"\0" for i in bus.ids())  # torque off
    summary = json.loads((run / "summary.json").read_text())
    assert summary["complete"] is False and summary["stop_reason"] == "SIGINT" and summary["fault"] is None
    assert summary["final_state"] == "PACKED"
    assert len(read_run(run).t) == summary["cycles"]
    _check_readers(run, tmp_path)


@pytest.mark.slow  # signals sent to shc subprocesses mid-run
def test_simulate_fail_on_fall_exit_code(tmp_path: Path) -> None:
    """A robot whose servos cannot hold it (0.3 N·m stall torque) collapses: the run stops as fallen and exits 4
    with --fail-on-fall, 0 without."""
    robot = tmp_path / "weak.toml"
    bullet = Path(__file__).parents[1] / "robots" / "bullet_openshc.toml"
    robot.write_text(f'extends = "{bullet.as_posix()}"\n\n[servo]\nstall_torque = 0.3\n')
    args = ["simulate", str(robot), "--engine", "pybullet", "--duration", "2", "--no-plots"]
    result = subprocess.run([*SHC, *args, "--out", str(tmp_path / "a"), "--fail-on-fall"], capture_output=True,
                            text=True, timeout=300)
    summary = json.loads((tmp_path / "a" / "summary.json").read_text())
    assert summary["fell"] is True and summary["stop_reason"] == "fell" and summary["complete"] is False
    assert result.returncode == 4 and "FELL" in result.stdout
    result = subprocess.run([*SHC, *args, "--out", str(tmp_path / "b")], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr


def test_gui_without_a_display_is_one_line(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    result = subprocess.run([*SHC, "simulate", "--gui", "--duration", "1", "--out", str(tmp_path / "g")],
                            capture_output=True, text=True, timeout=120, env=env)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines() == [
        "error: --gui: no display (DISPLAY is not set) (drop --gui, or set DISPLAY / run under a virtual display: "
        "xvfb-run shc simulate ...)"] or ("no display" in result.stderr and len(result.stderr.splitlines()) == 1)
    assert not list(tmp_path.iterdir())  # no run directory


def _peak_rss_mb(pid: int) -> float:
    """The process's peak resident memory so far (VmHWM) [MB]."""
    status = Path(f"/proc/{pid}/status").read_text()
    return int(status.split("VmHWM:")[1].split()[0]) / 1024


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads the peak memory from /proc (Linux)")
@pytest.mark.slow  # signals sent to shc subprocesses mid-run
def test_a_ten_hour_simulate_holds_no_memory_for_its_duration_and_a_sigterm_finishes_it(tmp_path: Path) -> None:
    """``--duration 36000`` once built 3.6 million commands (1.7 GB) before its first step, and a SIGTERM then left
    ``.partial/`` with only ``robot.toml``: memory must not depend on the requested duration, and the signal
    finishes the run directory."""
    out = tmp_path / "long"
    process = subprocess.Popen([*SHC, "simulate", "--engine", "mujoco", "--duration", "36000", "--out", str(out),
                                "--no-plots"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        _wait_rows(out.with_name("long.partial") / "log.csv")
        peak = _peak_rss_mb(process.pid)
        process.send_signal(signal.SIGTERM)
        _, stderr = process.communicate(timeout=120)
    finally:
        process.kill()
    assert peak < 400, f"{peak:.0f} MB at the first walking rows of a 10-hour run"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] is False and summary["stop_reason"] == "SIGTERM", stderr


def test_a_signal_before_the_first_cycle_finishes_the_run_directory(tmp_path: Path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A SIGTERM while the physics opens (the run directory exists, the loop has not started) is kept: the loop
    stops at once and the run is finished with no rows and ``"complete": false``."""
    from shc_cli.backends import simulated
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.simulate import simulate

    opened = simulated.open_world

    def open_then_signal(*args, **kwargs):  # type: ignore[no-untyped-def]
        world = opened(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGTERM)  # handled in the main thread before the loop's first cycle
        return world

    monkeypatch.setattr(simulated, "open_world", open_then_signal)
    path, summary = simulate(SimulationConfig(robot="bullet", duration=1.0, out=tmp_path / "early", engine="mujoco",
                                              plots=False)).pair
    assert summary.complete is False and summary.stop_reason == "SIGTERM"
    assert (path / "summary.json").exists() and (path / "log.csv").read_text().count("\n") == 1  # the header only
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
