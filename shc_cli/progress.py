"""The progress bar of long commands (simulate, sweep): rich on a terminal, nothing in pipes and CI."""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.progress import Progress


class ProgressBar:
    """A transient rich progress bar over ``total`` steps.

    Args:
        label: what is counted.
        total: steps to the end.
    """

    def __init__(self, label: str, total: int) -> None:
        from rich.progress import Progress

        self.label, self.total = label, total
        self.bar: Progress = Progress(transient=True)
        self.task = self.bar.add_task(label, total=total)
        self.bar.start()

    def update(self, done: int, detail: str | None = None) -> None:
        """``done`` steps so far (``detail`` shown beside the label); the bar goes at the end."""
        self.bar.update(self.task, completed=done, description=f"{self.label} ({detail})" if detail else self.label)
        if done >= self.total:
            self.stop()

    def stop(self) -> None:
        self.bar.stop()


def progress_bar(label: str, total: int) -> ProgressBar | None:
    """A :class:`ProgressBar` when stderr is a terminal outside CI, else ``None`` (quiet)."""
    if not sys.stderr.isatty() or os.environ.get("CI"):
        return None
    return ProgressBar(label, total)
