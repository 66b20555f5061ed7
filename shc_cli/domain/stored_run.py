"""Open any run: a run directory (``plan``, ``simulate``, ``run-hw``) or a bag written from one by ``shc export
bag``, as a :class:`~shc_cli.record.runread.RunLog`.

The one module above :mod:`shc_cli.record.runread` (directories) and :mod:`shc_cli.interop.bagrun` (bags), so neither
needs the other.
"""

from __future__ import annotations

from pathlib import Path

from shc_cli.record.runread import RunLog, bad_run, first_line, is_bag, read_run


def open_run(path: Path | str) -> RunLog:
    """The run at ``path`` (a directory or a bag); a one-line :class:`~shc_cli.errors.SpecError` otherwise."""
    path = Path(path)
    if is_bag(path):
        from shc_cli.errors import ShcError
        from shc_cli.interop.bagrun import read_bag_run

        try:
            return read_bag_run(path)
        except ShcError:
            raise
        except Exception as error:  # rosbags, YAML and the message decoders raise many kinds for a damaged bag
            raise bad_run(path, f"not a readable bag: {first_line(error)}",
                          "export the run again with shc export bag") from None
    return read_run(path)
