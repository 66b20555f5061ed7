"""``shc ros2``: OpenSHC's node on ROS 2 (parse, call the API, print the summary line, choose the exit code)."""

from __future__ import annotations

from pathlib import Path

from shc_cli.domain.ros_node import NodeConfig


def run_ros2(config: NodeConfig, params_file: Path | None) -> None:
    """Run the ROS 2 node; as ``shc ros`` (:func:`shc_cli.commands.ros.run_ros`)."""
    import typer

    from shc_cli.api import ros2_node
    from shc_cli.commands.ros import report

    report(ros2_node(config, params_file, on_ready=lambda line: typer.echo(line, err=True)))
