"""What a finished run returns: its directory and its summary."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass(frozen=True)
class RunResult:
    """A finished run (also an interrupted one: ``summary["complete"]`` is False).

    Attributes:
        path: the run directory.
        summary: its ``summary.json`` as written.
    """

    path: Path
    summary: dict[str, Any]

    @property
    def pair(self) -> tuple[Path, dict[str, Any]]:
        """``(path, summary)``, to unpack."""
        return self.path, self.summary
