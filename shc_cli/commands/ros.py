"""``shc ros``: OpenSHC's node on ROS 1 (parse, call the API, print the summary line, choose the exit code)."""

from __future__ import annotations

import typer

from shc_cli.domain.result import RunResult
from shc_cli.domain.ros_node import NodeConfig


def run_ros(config: NodeConfig) -> None:
    """Run the node; print where it listens, then one line when it stops (exit 0 also after Ctrl-C: that is how an
    open-ended node ends; 3 after a servo fault, as run-hw)."""
    from shc_cli.api import ros_node

    report(ros_node(config, on_ready=lambda line: typer.echo(line, err=True)))


def report(result: RunResult) -> None:
    """The node's one line when it stops; exit 3 after a servo fault."""
    from shc_cli.analysis.run_line import speed_note
    from shc_cli.commands.outcome import EXIT_FAULT

    s = result.summary
    timing = (f" at {s.rate_hz:.1f} Hz (period p50 {s.cycle_time_p50_ms:.2f} ms, p99 {s.cycle_time_p99_ms:.2f} ms, max "
              f"{s.cycle_time_max_ms:.2f} ms)" if s.rate_hz and s.cycle_time_p50_ms is not None
              and s.cycle_time_p99_ms is not None and s.cycle_time_max_ms is not None else "")
    fault = f", FAULT: {s.fault}" if s.fault else ""
    typer.echo(f"{s.robot} / {s.gait}: {s.cycles} cycles{timing}, stopped by {s.stop_reason}{speed_note(s)}{fault} "
               f"→ {result.path}")
    if s.fault:
        raise typer.Exit(EXIT_FAULT)
