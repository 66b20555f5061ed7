"""``shc warmup``: compile the numba kernels into their cache (the README's set-up command runs it once)."""

from __future__ import annotations

import typer


def run_warmup() -> None:
    """Compile (or load) every kernel and say how long it took."""
    from shc_cli.api import warm_up

    seconds = warm_up()
    typer.echo(f"shc's kernels compiled and cached in {seconds:.1f} s (later commands load them from the cache)")
