"""``shc view``: a robot file or a run in the browser (viser), until Ctrl-C."""

from __future__ import annotations

import os
import sys


def run_view(target: str, host: str, port: int, follow: bool = False) -> None:
    """Serve ``target`` on ``host:port`` (``follow``: a run in progress, as it is written); prints the URL. After
    Ctrl-C the process ends at once (exit code 0).

    viser runs the pages' callbacks in a pool of worker threads that Python's exit waits for: a page still being
    built when Ctrl-C comes (a workspace search, seconds on a loaded machine) would keep the viewer alive that
    long. The server is stopped (:func:`shc_cli.view.server.serve`), so nothing is left to finish: leave now.
    """
    from shc_cli.view.server import serve

    serve(target, host, port, follow)
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
