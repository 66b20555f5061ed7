"""``shc run-hw``: the one controller on real Dynamixel servos (:mod:`shc_cli.domain.hardware`); prints the bus
set-up, warnings and faults as they happen, then one summary line; exits 3 after a servo fault, 5 when it finished on
fewer legs (``--on-fault adapt``)."""

from __future__ import annotations

from pathlib import Path

import typer

from shc_cli.domain.hardware import HardwareConfig

__all__ = ["run_hw"]


def run_hw(config: HardwareConfig) -> Path:
    """Run on the servos, print one line; returns the run directory (exit 3 after a servo fault)."""
    from shc_cli.analysis.run_line import speed_note
    from shc_cli.api import run_hardware
    from shc_cli.commands.outcome import EXIT_FAULT, EXIT_FEWER_LEGS

    run = run_hardware(config)
    summary = run.summary
    fault = f", FAULT: {summary.fault}" if summary.fault else ""
    if summary.failed_legs:
        fault += f", FINISHED ON FEWER LEGS (failed: {', '.join(summary.failed_legs)})"
    typer.echo(f"{summary.robot} on {summary.port}: {summary.cycles} cycles, cycle time mean "
               f"{summary.cycle_time_mean_ms:.2f} ms, p99 {summary.cycle_time_p99_ms:.2f} ms, "
               f"{summary.overruns} overruns, ended {summary.final_state}{speed_note(summary)}{fault} → {run.path}")
    if summary.fault:
        raise typer.Exit(EXIT_FAULT)
    if summary.failed_legs:
        raise typer.Exit(EXIT_FEWER_LEGS)
    return run.path
