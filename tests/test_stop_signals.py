"""A run's SIGINT/SIGTERM handler (shc_cli/record/stop_signals.py): a signal between the loop's own end and the finished
run directory is kept, not lost (an optimize study interrupted then went on: the run's summary said it had ended
on its own and the study never saw the Ctrl-C)."""

from __future__ import annotations

import os
import signal

import pytest

from shc_cli.record.stop_signals import StopSignals


def test_a_signal_after_the_loop_ended_is_kept_and_interrupts_nothing_until_asked() -> None:
    signals = StopSignals()
    requests: list[str] = []
    signals.install()
    try:
        signals.on_stop = requests.append
        os.kill(os.getpid(), signal.SIGINT)  # while the loop runs: its stop request
        assert requests == ["SIGINT"] and signals.late is None
        signals.loop_over = True
        os.kill(os.getpid(), signal.SIGTERM)  # the loop is over: kept, no exception (the robot is being released)
        os.kill(os.getpid(), signal.SIGINT)
        assert requests == ["SIGINT"] and signals.late == "SIGTERM"
        signals.finishing = True
        with pytest.raises(KeyboardInterrupt):  # finishing: a signal skips what is left
            os.kill(os.getpid(), signal.SIGINT)
    finally:
        signals.restore()
