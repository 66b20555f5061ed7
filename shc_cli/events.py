"""Logging: the package's loggers, what the terminal shows, and every run directory's ``events.log``.

Every module logs through ``logging.getLogger(__name__)`` (loggers under ``shc_cli``); nothing below the commands
prints. Two places read the records:

* the terminal — :func:`configure_terminal` (``shc --verbose`` / ``--quiet``): by default messages at
  :data:`NOTICE` and above (operator notices, warnings, errors), as the message alone on stderr; ``--verbose`` adds
  INFO (state changes, set-up steps), ``--quiet`` keeps only errors. A record logged with ``terminal=False`` (see
  :func:`event`) goes to ``events.log`` only: the command reports it itself (the summary line says FELL, a fault or
  an engine note is printed by the command). Without the CLI (the Python API), a run prints its warnings as Python's
  own last-resort handler would, unless the application configured logging itself.
* a run's ``events.log`` — :func:`recording` (while :func:`shc_cli.loop.assembly.assemble` runs the loop and
  finishes the directory): one JSON object per line, INFO and above, with the keys ``time`` (UTC, ISO 8601 with
  milliseconds), ``cycle`` (the control cycle, ``null`` outside the loop), ``level`` (``info``, ``notice``,
  ``warning``, ``error``), ``event`` (a short name: ``robot_state``, ``walk_state``, ``fell``, ``fault``,
  ``stop_requested``, ``stopped``, ``engine_warning``, ``input``…; the logger's name for a plain record) and
  ``message``.
"""

from __future__ import annotations

import logging
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from pathlib import Path

NOTICE = 25
"""Level between INFO and WARNING: what the operator should see by default (the keys of ``--input keyboard``, the
gamepad in use)."""
logging.addLevelName(NOTICE, "NOTICE")

PACKAGE_LOGGER = "shc_cli"
EVENTS_FILE = "events.log"
"""The events file of a run directory."""
EVENTS_FORMAT = (
    "Warnings, faults and state changes of the run, one JSON object per line (INFO and above), with the keys "
    "`time` (UTC, ISO 8601 with milliseconds), `cycle` (the control cycle, null outside the loop), `level` (info, "
    "notice, warning, error), `event` (robot_state, walk_state, stop_requested, stopped, fell, fault, "
    "engine_warning, input, watchdog; the logger's name for any other record) and `message` (the text shc logs; "
    "`shc --verbose` also prints the info ones on stderr).")
"""``events.log``'s format, for the reference page (docs/run_outputs.py)."""
VERBOSITY = {"quiet": logging.ERROR, "normal": NOTICE, "verbose": logging.INFO}
"""Terminal level per ``--quiet`` / default / ``--verbose``."""


def event(logger: logging.Logger, level: int, name: str, message: str, *args: object, cycle: int | None = None,
          terminal: bool = True) -> None:
    """Log an event: ``message % args`` at ``level`` named ``name`` in ``events.log``, at control cycle ``cycle``
    (default: the running loop's); ``terminal=False`` keeps it off the terminal (the command reports it)."""
    logger.log(level, message, *args, extra={"event": name, "cycle": cycle, "terminal": terminal})


class _Terminal(logging.Handler):
    """The message alone on the current ``sys.stderr`` (looked up at each record: test runners swap it)."""

    def __init__(self, level: int) -> None:
        super().__init__(level)
        self.addFilter(lambda record: getattr(record, "terminal", True))

    def emit(self, record: logging.LogRecord) -> None:
        try:
            sys.stderr.write(self.format(record) + "\n")
            sys.stderr.flush()
        except Exception:  # as logging's own handlers: a broken stderr must not break the run
            self.handleError(record)


_terminal: _Terminal | None = None


def configure_terminal(verbosity: str = "normal") -> None:
    """What ``shc`` shows on stderr: ``"quiet"``, ``"normal"`` or ``"verbose"`` (:data:`VERBOSITY`); called once per
    command (again replaces the handler)."""
    global _terminal
    logger = logging.getLogger(PACKAGE_LOGGER)
    if _terminal is not None:
        logger.removeHandler(_terminal)
    _terminal = _Terminal(VERBOSITY[verbosity])
    logger.addHandler(_terminal)
    logger.setLevel(min(VERBOSITY[verbosity], logging.INFO))


class EventLog(logging.Handler):
    """Writes every record of the ``shc_cli`` loggers at INFO and above as one JSON line (module docstring).

    Args:
        path: the ``events.log`` file (created, or appended to).
        cycle: gives the running loop's control cycle for a record that names none (``None``: null).
    """

    def __init__(self, path: Path, cycle: Callable[[], int | None] | None = None) -> None:
        super().__init__(logging.INFO)
        self.path = path
        self.cycle = cycle
        self._file = path.open("a", encoding="utf-8")

    def emit(self, record: logging.LogRecord) -> None:
        import json
        from datetime import UTC, datetime

        try:
            cycle = getattr(record, "cycle", None)
            if cycle is None and self.cycle is not None:
                cycle = self.cycle()
            line = {"time": datetime.fromtimestamp(record.created, UTC).isoformat(timespec="milliseconds"),
                    "cycle": cycle, "level": record.levelname.lower(),
                    "event": getattr(record, "event", None) or record.name, "message": record.getMessage()}
            self._file.write(json.dumps(line) + "\n")
            self._file.flush()
        except Exception:
            self.handleError(record)

    def close(self) -> None:
        self._file.close()
        super().close()


@contextmanager
def recording(directory: Path, cycle: Callable[[], int | None] | None = None) -> Iterator[EventLog]:
    """Record the ``shc_cli`` loggers into ``directory/events.log`` (created, possibly empty) for the duration."""
    logger = logging.getLogger(PACKAGE_LOGGER)
    handler = EventLog(directory / EVENTS_FILE, cycle)
    level = logger.level
    fallback = None
    if _terminal is None and not logging.getLogger().handlers:
        fallback = _Terminal(logging.WARNING)  # what Python's last resort would print without this handler
        logger.addHandler(fallback)
    if logger.getEffectiveLevel() > logging.INFO:
        logger.setLevel(logging.INFO)
    logger.addHandler(handler)
    try:
        yield handler
    finally:
        logger.removeHandler(handler)
        if fallback is not None:
            logger.removeHandler(fallback)
        logger.setLevel(level)
        handler.close()
