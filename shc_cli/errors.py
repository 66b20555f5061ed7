"""The one exception tree of shc.

Every error a user can cause derives from :class:`ShcError` and renders as one line
(``str(error)``) that names the file, the line or field, what is wrong and how to fix it.
The CLI prints that line and exits with code 2; tracebacks appear only with ``--debug``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

REINSTALL = "python3 -m uv pip install --python .venv -e ."
"""The command, run in shc's clone, that installs shc with every dependency its commands need (README, Set-up)."""


def install_hint(extra: str | None = None) -> str:
    """How to install a missing dependency from shc's clone: the README's install with ``extra`` (e.g. ``dask``),
    or the plain install when the dependency is one of shc's own (a partial install)."""
    if extra is None:
        return f"reinstall shc from its clone: {REINSTALL}"
    return f"install shc's '{extra}' extra from its clone: {REINSTALL[:-1]}'.[{extra}]'"


class ShcError(Exception):
    """Base class of every error shc reports to a user."""


@dataclass(frozen=True)
class Issue:
    """One problem found in an input file.

    Attributes:
        file: The file the problem is in (or the file that was read, if the field has no line).
        line: 1-based line of the offending key, or ``None`` when it cannot be located.
        field: Dotted path of the field, e.g. ``legs.AR.joints.coxa.max``; empty for whole-file problems.
        problem: What is wrong, e.g. ``max (0.2) must be greater than min (0.5)``.
        fix: How to fix it, e.g. ``swap the two values``; may be empty.
    """

    file: Path | None
    line: int | None
    field: str
    problem: str
    fix: str = ""

    def __str__(self) -> str:
        where = "" if self.file is None else str(self.file)
        if self.line is not None:
            where += f":{self.line}"
        parts = [p for p in (where, self.field) if p]
        text = ": ".join([*parts, self.problem])
        return f"{text} ({self.fix})" if self.fix else text


class SpecError(ShcError):
    """A robot, gait or command file is malformed or inconsistent; carries every issue found."""

    def __init__(self, issues: list[Issue]) -> None:
        if not issues:
            raise ValueError("SpecError needs at least one issue")
        self.issues = issues
        super().__init__(str(issues[0]))

    def __str__(self) -> str:
        return "\n".join(str(issue) for issue in self.issues)


class NotFoundError(ShcError):
    """A named robot, gait or file does not exist; lists what does."""


class KinematicsError(ShcError):
    """A kinematic computation cannot be done (e.g. a leg with no reachable stance)."""


class OutputError(ShcError):
    """An output cannot be written (e.g. the output directory is not writable)."""


class BackendError(ShcError):
    """A backend (physics engine, servo bus) cannot do what was asked."""


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where a Ctrl-C raises :class:`KeyboardInterrupt` (so every ``except KeyboardInterrupt``
    that keeps what is done handles both; :func:`signal_name` tells them apart)."""


class Interrupted(ShcError):
    """A command stopped by SIGINT or SIGTERM; the text says what was kept. The CLI prints ``interrupted by
    SIGNAL: TEXT`` and exits 130 (SIGINT) or 143 (SIGTERM).

    Attributes:
        signal: ``"SIGINT"`` or ``"SIGTERM"``.
    """

    def __init__(self, kept: str, signal: str = "SIGINT") -> None:
        super().__init__(kept)
        self.signal = signal


EXIT_SIGNAL = {"SIGINT": 130, "SIGTERM": 143}
"""A command stopped by a signal exits 128 + the signal's number, as shells report it."""


def interrupt(name: str) -> KeyboardInterrupt:
    """The exception a signal named ``name`` raises: :class:`Terminated` for SIGTERM, else a KeyboardInterrupt."""
    return Terminated() if name == "SIGTERM" else KeyboardInterrupt()


def signal_name(error: BaseException) -> str:
    """``"SIGTERM"`` when ``error`` (or what caused it) is a :class:`Terminated`, else ``"SIGINT"``."""
    seen: BaseException | None = error
    while seen is not None:
        if isinstance(seen, Terminated):
            return "SIGTERM"
        if isinstance(seen, Interrupted):
            return seen.signal
        seen = seen.__cause__ or seen.__context__
    return "SIGINT"


def spoken(items: Iterable[str]) -> str:
    """``a, b or c``: a list of choices as a sentence says it."""
    words = list(items)
    return words[0] if len(words) == 1 else f"{', '.join(words[:-1])} or {words[-1]}"


def check_choice(option: str, value: object, allowed: Iterable[object], what: str, fix: str | None = None) -> None:
    """Refuse a command-line value that is not one of ``allowed`` with one line: ``OPTION: 'VALUE' is not WHAT
    (FIX)``, ``FIX`` by default ``use`` and the choices (:func:`spoken`).

    Args:
        option: the option, e.g. ``--engine``.
        value: what the user gave.
        allowed: the values accepted.
        what: what a right value is, with its article (``a physics engine``).
        fix: how to fix it, when the plain list of choices does not say enough.
    """
    choices = list(allowed)
    if value not in choices:
        raise SpecError([Issue(None, None, option, f"'{value}' is not {what}",
                               fix or f"use {spoken(str(c) for c in choices)}")])
