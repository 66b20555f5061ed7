"""``shc export``: a robot's generated physics model as URDF, a run as a ROS bag."""

from __future__ import annotations

from pathlib import Path

import typer


def export_urdf(robot: str, out: Path | None, overwrite: bool = False) -> None:
    """The URDF generated from the robot file (what ``simulate`` loads), printed or written to ``out`` (an existing
    file only with ``overwrite``)."""
    from shc_cli.backends.pybullet_.urdf import robot_urdf
    from shc_cli.outputs import refuse_existing, write_text
    from shc_cli.spec.loading import load_robot

    if out is not None:
        refuse_existing([out], overwrite)
    text = robot_urdf(load_robot(robot).robot)  # the schema only: a model of any readable robot file
    if out is None:
        typer.echo(text)
    else:
        write_text(out, text)
        typer.echo(f"wrote {out}")


def export_bag(run: Path, format: str, out: Path | None) -> None:
    """A run as a ROS bag at ``out`` (default: ``RUN_bag``, or ``RUN.bag`` for ros1)."""
    from shc_cli.api import open_run
    from shc_cli.interop.bag import export_bag as write_bag

    target = out or run.with_name(run.name + (".bag" if format == "ros1" else "_bag"))
    log = open_run(run)
    note = log.partial_note()
    if note is not None:
        typer.echo(f"note: {note}", err=True)
    path = write_bag(log, target, format)
    typer.echo(f"wrote {path}")
