"""numba's ``njit`` for shc's compiled kernels, and one notice when a command has to compile them.

Every kernel module takes ``njit`` from here (``cache=True``: compiled once per install, then loaded from numba's
cache in milliseconds). Importing this module registers a numba event listener that logs, at the first real
compilation of one of shc's kernels in a process (a cache miss: a new install that did not run ``shc warmup``,
edited sources, another numba), a NOTICE saying why the command is slow this once — on a terminal only (a pipe, a
test's captured stderr, a sweep's workers stay as they were).
"""

from __future__ import annotations

import logging
import sys
from typing import Any

from numba import njit
from numba.core import event

from shc_cli.events import NOTICE

__all__ = ["njit"]

log = logging.getLogger(__name__)


class _CompileNotice(event.Listener):
    """Tells once per process that shc's kernels are being compiled."""

    told = False

    def on_start(self, ev: Any) -> None:
        dispatcher = (ev.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        if not self.told and module.startswith("shc_cli") and sys.stderr.isatty():
            self.told = True
            log.log(NOTICE, "compiling shc's kernels into numba's cache (once per install, ≈ 10 s; `shc warmup` "
                            "does it ahead)")

    def on_end(self, ev: Any) -> None:
        """Nothing at the end."""


event.register("numba:compile", _CompileNotice())  # type: ignore[no-untyped-call]
