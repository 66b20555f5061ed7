"""How a command's end becomes an exit code and one line on stderr (docs/commands.md, "Exit codes"): user errors
(:class:`~shc_cli.errors.ShcError`) 2, a command stopped by SIGINT (Ctrl-C) or SIGTERM 130 or 143 with what was
kept (:class:`~shc_cli.errors.Interrupted`), a bug 1; no traceback unless ``--debug``.

SIGTERM is raised as :class:`~shc_cli.errors.Terminated`, a KeyboardInterrupt, so whatever keeps its work at a
Ctrl-C (a sweep's rows, a study's trials, a render's clean-up) keeps it at a SIGTERM too; a run's own handlers
(:mod:`shc_cli.record.stop_signals`) take both signals while it runs.
"""

from __future__ import annotations

import signal
import sys
from collections.abc import Callable

import typer

from shc_cli.errors import EXIT_SIGNAL, Interrupted, ShcError, Terminated


def _terminated(signum: int, frame: object) -> None:
    raise Terminated


def _interrupt_of(done: SystemExit) -> KeyboardInterrupt | None:
    """The KeyboardInterrupt behind typer's exit 130 (typer turns one into a silent exit), or None."""
    seen: BaseException | None = done if done.code == 130 else None
    while seen is not None:
        if isinstance(seen, KeyboardInterrupt):
            return seen
        seen = seen.__cause__ or seen.__context__
    return None


def _interrupted(stop: KeyboardInterrupt) -> None:
    name = "SIGTERM" if isinstance(stop, Terminated) else "SIGINT"
    typer.echo(f"error: interrupted by {name}; nothing was written (shc writes an output whole or not at all)",
               err=True)
    sys.exit(EXIT_SIGNAL[name])


def run_command(command: Callable[[], object], debug: bool) -> None:
    """Run ``command`` (the typer app) and turn how it ended into the exit code and its one line (SIGTERM raises
    :class:`~shc_cli.errors.Terminated` meanwhile; the previous handler is put back after)."""
    previous = signal.getsignal(signal.SIGTERM)
    if previous is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _terminated)
    try:
        _run(command, debug)
    finally:
        if previous is signal.SIG_DFL:
            signal.signal(signal.SIGTERM, previous)


def _run(command: Callable[[], object], debug: bool) -> None:
    try:
        command()
    except Interrupted as error:
        if debug:
            raise
        typer.echo(f"error: interrupted by {error.signal}: {error}", err=True)
        sys.exit(EXIT_SIGNAL[error.signal])
    except ShcError as error:
        if debug:
            raise
        for line in str(error).splitlines():
            typer.echo(f"error: {line}", err=True)
        sys.exit(2)
    except SystemExit as done:
        stop = _interrupt_of(done)
        if stop is None or debug:
            raise
        _interrupted(stop)
    except KeyboardInterrupt as error:  # Ctrl-C outside a run's loop (a run's own signals finish its directory first)
        if debug:
            raise
        _interrupted(error)
    except Exception as error:  # a bug in shc, not bad input: still one line unless --debug
        if debug:
            raise
        typer.echo(f"error: internal error: {type(error).__name__}: {error} (rerun with --debug and report it)",
                   err=True)
        sys.exit(1)
