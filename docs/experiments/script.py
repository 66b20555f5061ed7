"""The command-line entry of the scripts in docs/experiments: argument count, and one error line instead of a
traceback for a missing or malformed input (exit 2), as the ``shc`` commands do."""

from __future__ import annotations

import sys
from collections.abc import Callable

from shc_cli.errors import ShcError


def run(main: Callable[[list[str]], None], usage: str, least: int, most: int | None = None) -> None:
    """Call ``main(arguments)`` when ``least`` … ``most`` (None: any number) arguments were given.

    Args:
        main: the script's work, given the command-line arguments.
        usage: the arguments, shown when they are wrong, e.g. ``"RUN_DIR [RUN_DIR ...]"``.
        least, most: how many arguments the script takes.
    """
    arguments = sys.argv[1:]
    name = sys.argv[0]
    if len(arguments) < least or (most is not None and len(arguments) > most):
        sys.exit(f"usage: {name} {usage}")
    try:
        main(arguments)
    except (ShcError, OSError, ValueError, KeyError) as error:
        text = f"missing column {error}" if isinstance(error, KeyError) else str(error)
        print(f"error: {text} (the arguments are {usage})", file=sys.stderr)
        sys.exit(2)
