"""Open any run: a run directory (``plan``, ``simulate``, ``run-hw``) or a bag written from one by ``shc export
bag``, as a :class:`~shc_cli.runread.RunLog`.

The one module above :mod:`shc_cli.runread` (directories) and :mod:`shc_cli.interop.bagrun` (bags), so neither
needs the other.
"""

from __future__ import annotations

from pathlib import Path

from shc_cli.runread import RunLog, is_bag, read_run


def open_run(path: Path | str) -> RunLog:
    """The run at ``path`` (a directory or a bag); a one-line :class:`~shc_cli.errors.SpecError` otherwise."""
    path = Path(path)
    if is_bag(path):
        from shc_cli.interop.bagrun import read_bag_run

        return read_bag_run(path)
    return read_run(path)
