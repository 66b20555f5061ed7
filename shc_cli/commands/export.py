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


def export_bag(run: Path, format: str, out: Path | None, overwrite: bool = False) -> None:
    """A run as a ROS bag at ``out`` (default :func:`~shc_cli.interop.bag.default_bag_path`: ``RUN_bag`` for
    mcap, ``RUN_bag_sqlite3`` for sqlite3, ``RUN.bag`` for ros1); an existing bag there is replaced only with
    ``overwrite``; a ROS 2 bag's ``out`` must name a folder, a ROS 1 bag's a ``.bag`` file (else one line)."""
    from shc_cli.api import open_run
    from shc_cli.interop.bag import check_bag_out, default_bag_path
    from shc_cli.interop.bag import export_bag as write_bag

    target = out or default_bag_path(run, format)
    check_bag_out(target, format, overwrite)  # before the run is read
    log = open_run(run)
    note = log.partial_note()
    if note is not None:
        typer.echo(f"note: {note}", err=True)
    path = write_bag(log, target, format, overwrite)
    typer.echo(f"wrote {path}")
