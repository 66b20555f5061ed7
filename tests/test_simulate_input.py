"""``shc simulate --input keyboard|stdin``: the simulated robot driven by hand in real time, through a pseudo-terminal
(python's ``pty``) or a pipe, as a person drives it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from shc_cli.record.runread import read_run
from tests.run_waits import wait_running

pytestmark = pytest.mark.slow  # real-time simulations in subprocesses

ROOT = Path(__file__).parents[1]
SHC = [sys.executable, "-m", "shc_cli.cli"]


def test_keyboard_keys_walk_the_simulated_robot_and_the_terminal_is_restored(tmp_path: Path) -> None:
    import pty
    import termios

    run = tmp_path / "run"
    master, slave = pty.openpty()
    before = termios.tcgetattr(slave)
    try:
        process = subprocess.Popen([*SHC, "simulate", "--engine", "mujoco", "--input", "keyboard", "--out", str(run),
                                    "--no-plots"], cwd=ROOT, stdin=slave, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True)
        wait_running(run, process, timeout_s=120.0)
        time.sleep(0.5)  # standing: the input is still zero
        os.write(master, b"wwwww")  # five presses: 0.5 of full speed forward
        time.sleep(4.0)
        os.write(master, b" ")  # zero
        time.sleep(1.0)
        os.write(master, b"x")  # stop
        _, stderr = process.communicate(timeout=120)
        assert process.returncode == 0, stderr
        assert "keys: w/s forward/back" in stderr
        assert termios.tcgetattr(slave) == before  # cbreak mode undone
    finally:
        os.close(master)
        os.close(slave)
    summary = json.loads((run / "summary.json").read_text())
    assert summary["input"] == "keyboard" and summary["complete"] is True  # the input ended: 'x'
    assert 50.0 < summary["rate_hz"] <= 101.0  # --input keyboard implies --realtime (100 Hz; a loaded CI falls behind)
    log = read_run(run)
    forward = np.round(log.command[:, 0], 6)
    pressed = forward == 0.5
    assert pressed.sum() > 250 and forward[-1] == 0.0  # the presses add up, held ~4 s; space zeroes
    first = int(np.flatnonzero(pressed)[0])
    start = int(np.flatnonzero(forward != 0.0)[0])  # the five presses may be read over a few cycles: 0.1, 0.2, …
    burst = forward[start:first]
    assert len(burst) <= 5 and (np.diff(np.append(burst, 0.5)) >= 0.0).all(), burst
    assert (forward[log.running][: start - int(np.flatnonzero(log.running)[0])] == 0.0).all()  # nothing before
    moved = log.position[-1, 0] - log.position[first, 0]
    assert moved > 0.15, moved  # [m]: it walked forward
    assert abs(log.position[-1, 1] - log.position[first, 1]) < 0.3 * moved  # and not sideways


def test_stdin_lines_drive_the_simulated_robot(tmp_path: Path) -> None:
    run = tmp_path / "run"
    process = subprocess.Popen([*SHC, "simulate", "--engine", "mujoco", "--input", "stdin", "--watchdog", "5",
                                "--out", str(run), "--no-plots"], cwd=ROOT, stdin=subprocess.PIPE,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert process.stdin is not None
    wait_running(run, process, timeout_s=120.0)
    process.stdin.write(json.dumps({"velocity": [0.0, 0.0, 0.5]}) + "\n")  # turn left on the spot
    process.stdin.flush()
    time.sleep(3.0)
    process.stdin.write(json.dumps({"stop": True}) + "\n")
    process.stdin.flush()
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 0, stderr
    log = read_run(run)
    turning = np.round(log.command[:, 2], 6) == 0.5
    assert turning.sum() > 200
    assert log.rpy[-1, 2] - log.rpy[int(np.flatnonzero(turning)[0]), 2] > 0.1  # [rad]: it turned left


@pytest.mark.parametrize(("input_mode", "message"), [
    ("keyboard", "standard input is not a terminal"),
    ("gamepad:/dev/input/event99", "/dev/input/event99: cannot open the gamepad"),
    ("joystick", "'joystick' is not an input"),
])
def test_unusable_inputs_are_one_line_errors(input_mode: str, message: str, tmp_path: Path) -> None:
    result = subprocess.run([*SHC, "simulate", "--input", input_mode, "--out", str(tmp_path / "run")], cwd=ROOT,
                            capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert result.returncode == 2 and message in result.stderr, result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and not (tmp_path / "run").exists()
    assert not (tmp_path / "run.partial").exists()
