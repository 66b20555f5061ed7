"""``--bag`` and ``--video`` of ``plan`` and ``simulate``: checked before the run, written after it."""

from __future__ import annotations

from pathlib import Path

import typer

from shc_cli.errors import Issue, SpecError, check_choice

BAG_FORMATS = ("mcap", "sqlite3", "ros1")


def check_outputs(bag: str | None, video: Path | None, overwrite: bool = False) -> None:
    """Refuse a bad ``--bag`` format or ``--video`` name, or an existing video without ``overwrite``, before the run,
    not after it."""
    if bag is not None:
        check_choice("--bag", bag, BAG_FORMATS, "a bag format")
    if video is not None and video.suffix.lower() not in (".mp4", ".gif"):
        raise SpecError([Issue(None, None, "--video", f"'{video}' is neither .mp4 nor .gif", "e.g. --video walk.mp4")])
    if video is not None:
        from shc_cli.outputs import refuse_existing

        refuse_existing([video], overwrite, "--video")


def finish_outputs(run: Path, bag: str | None, video: Path | None) -> None:
    """``--bag`` and ``--video`` of a finished run (also an interrupted one, before its exit code): the bag inside
    its directory (``bag/``, or ``run.bag`` for ros1), the video as ``shc render RUN --out FILE`` would — with the
    garbage collector on, also inside the command's pause of it (their work grows with the run's length)."""
    from shc_cli.loop.gc_pause import collecting

    with collecting():
        if bag is not None:
            from shc_cli.api import open_run
            from shc_cli.interop.bag import export_bag

            path = export_bag(open_run(run), run / ("run.bag" if bag == "ros1" else "bag"), bag)
            typer.echo(f"wrote {path}")
        if video is not None:
            from shc_cli.commands.render import render_video

            render_video(run, video)
