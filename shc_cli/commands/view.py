"""``shc view``: a robot file or a run in the browser (viser), until Ctrl-C."""

from __future__ import annotations


def run_view(target: str, host: str, port: int) -> None:
    """Serve ``target`` on ``host:port``; prints the URL."""
    from shc_cli.view.server import serve

    serve(target, host, port)
