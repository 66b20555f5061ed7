"""What a finished run returns: its directory and its summary."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.record.summary import RunSummary


@dataclass(frozen=True)
class RunResult:
    """A finished run (also an interrupted one: ``summary.complete`` is False).

    Attributes:
        path: the run directory.
        summary: its ``summary.json`` as written.
    """

    path: Path
    summary: RunSummary

    @property
    def pair(self) -> tuple[Path, RunSummary]:
        """``(path, summary)``, to unpack."""
        return self.path, self.summary
