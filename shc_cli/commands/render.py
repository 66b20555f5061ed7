"""``shc render``: a finished run (or a bag from ``shc export bag``) as an MP4 or a GIF."""

from __future__ import annotations

import sys
from pathlib import Path

import typer

from shc_cli.errors import Interrupted, signal_name


def run_render(run_path: Path, out: Path, fps: float, size: str, camera: str, speed: float,
               overwrite: bool = False) -> Path:
    """Read the run, render it, print one line; returns the video's path (an existing ``out`` is refused unless
    ``overwrite``)."""
    from shc_cli.domain.stored_run import open_run as read_run  # directories and bags
    from shc_cli.outputs import refuse_existing
    from shc_cli.view.render import RenderOptions, check_options, parse_size, render_run

    width, height = parse_size(size)
    options = RenderOptions(fps=fps, width=width, height=height, camera=camera, speed=speed)
    check_options(out, options)
    refuse_existing([out], overwrite)
    run = read_run(run_path)
    try:
        result = render_run(run, out, options, progress=sys.stderr.isatty())
    except KeyboardInterrupt as error:  # the half-made video is removed: nothing is kept
        raise Interrupted(f"no video written ({out} was not made; the run {run_path} is unchanged)",
                          signal_name(error)) from None
    typer.echo(f"wrote {result.path}: {result.frames / fps:.1f} s of video ({result.frames} frames at {fps:g} fps, "
               f"{width}x{height}), rendered in {result.draw_s + result.encode_s:.1f} s")
    return result.path


DEFAULTS: tuple[float, str, str, float] = (25.0, "960x540", "follow", 1.0)
"""What ``--video`` on plan and simulate renders with: ``shc render``'s defaults (fps, size, camera, speed)."""


def render_video(run_path: Path, out: Path) -> Path:
    """``--video FILE``: the finished run rendered as ``shc render RUN --out FILE`` would (plan and simulate
    checked ``--video`` against ``--overwrite`` before the run)."""
    fps, size, camera, speed = DEFAULTS
    return run_render(run_path, out, fps, size, camera, speed, overwrite=True)
