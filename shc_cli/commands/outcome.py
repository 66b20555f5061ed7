"""How a run command ends: its exit code and the note on its summary line (docs/commands.md, "Exit codes").

0 done (also ``run-hw`` stopped by Ctrl-C: that is how an open-ended run ends), 1 internal error, 2 bad input,
3 ``run-hw`` ended by a servo fault, 4 ``simulate --fail-on-fall`` and the robot fell, 5 ``run-hw --on-fault
adapt`` finished on fewer legs, 6 ``simulate``: the physics diverged, 130 / 143 ``plan`` or
``simulate`` stopped by SIGINT / SIGTERM (the run directory is finished, marked ``"complete": false``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import typer

from shc_cli.errors import EXIT_SIGNAL

if TYPE_CHECKING:
    from shc_cli.record.summary import RunSummary

EXIT_FAULT = 3
"""``run-hw``: a servo fault ended the run."""
EXIT_FELL = 4
"""``simulate --fail-on-fall``: the robot fell."""
EXIT_FEWER_LEGS = 5
"""``run-hw --on-fault adapt``: a servo fault failed a leg and the run finished on the legs left."""
EXIT_DIVERGED = 6
"""``simulate``: the physics blew up (NaN or a runaway body speed); the run directory is kept,
``stop_reason: "diverged"``, ``fault`` says what showed it. (5 is kept for a run that finished on fewer legs.)"""
EXIT_INTERRUPTED = EXIT_SIGNAL
"""``plan``/``simulate`` stopped by a signal: 128 + the signal's number, as shells report it."""


def interrupted_note(summary: RunSummary) -> str:
    """``", INTERRUPTED (SIGINT; partial run)"`` for a run that did not play to its end, else ``""``."""
    if summary.stop_reason == "diverged":
        return ", PHYSICS DIVERGED (partial run)"
    if summary.complete or summary.stop_reason in ("fault", "fell"):
        return ""
    return f", INTERRUPTED ({summary.stop_reason}; partial run)"


def exit_if_diverged(summary: RunSummary) -> None:
    """One line and exit 6 when the physics blew up (the run directory is kept)."""
    if summary.stop_reason == "diverged":
        typer.echo(f"error: {summary.fault} — the run was stopped; its directory is kept (try a higher "
                   "--physics-rate, or milder --friction/--restitution)", err=True)
        raise typer.Exit(EXIT_DIVERGED)


def exit_if_interrupted(summary: RunSummary) -> None:
    """Exit 130/143 when a signal stopped the run."""
    code = EXIT_INTERRUPTED.get(summary.stop_reason)
    if code is not None:
        raise typer.Exit(code)

