"""numba's ``njit`` for shc's compiled kernels, and one notice when a command has to compile them.

Every kernel module takes ``njit`` from here (``cache=True``: compiled once per install, then loaded from numba's
cache in milliseconds). Importing this module registers a numba event listener that logs, at the first real
compilation of one of shc's kernels in a process (a cache miss: a new install that did not run ``shc warmup``,
edited sources, another numba), a NOTICE saying why the command is slow this once — on a terminal only (a pipe, a
test's captured stderr, a sweep's workers stay as they were).

Loading a kernel from the cache initialises only numba's runtime (:class:`_CacheLoader`), not the ≈ 40 modules of
typing and lowering rules numba's own loader installs first (0.2 s of every command's start-up, with SciPy's BLAS
check): a loaded kernel is machine code that needs no typing; a kernel that has to be compiled installs them then.
"""

from __future__ import annotations

import logging
import os
import sys
from collections.abc import Callable, Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType
from typing import Any


class _Without:
    """An import finder that makes the named top-level modules missing while it is on ``sys.meta_path``."""

    def __init__(self, names: set[str]) -> None:
        self.names = names

    def find_spec(self, name: str, path: Sequence[str] | None = None,
                  target: ModuleType | None = None) -> ModuleSpec | None:
        if name in self.names:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


def _import_numba() -> None:
    """Import numba without two imports its package makes only to check things shc does not use (≈ 0.03 s of every
    command that loads a kernel): SciPy, imported to check that its version is at least 1.0, and PyYAML, imported
    to read a ``.numba_config.yaml`` in the working directory (left alone when there is one). Modules already
    imported stay; nothing else changes: compiling a kernel (a cache miss) imports SciPy as numba needs it."""
    if "numba" in sys.modules:
        return
    names = {"scipy"} | (set() if os.path.isfile(".numba_config.yaml") else {"yaml"})
    finder = _Without({name for name in names if name not in sys.modules})
    sys.meta_path.insert(0, finder)
    try:
        import numba  # noqa: F401
    finally:
        sys.meta_path.remove(finder)


_import_numba()

import numba  # noqa: E402
from numba.core import event  # noqa: E402
from numba.core.caching import FunctionCache  # noqa: E402

from shc_cli.events import NOTICE  # noqa: E402

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


class _CacheLoader(FunctionCache):
    """numba's cache of one kernel, loading without installing the compiler's typing and lowering registries.

    numba's own ``load_overload`` calls ``target_context.refresh()`` first: it imports and installs every typing
    and lowering rule (``numba.np.arraymath``, whose BLAS check imports ``scipy.linalg``, …) — what compiling needs.
    Rebuilding a cached kernel needs only numba's runtime (NRT: the kernels allocate arrays) and the C helpers the
    target context installed when it was made. On a cache miss numba compiles, and its compiler refreshes the
    context itself (``numba.core.compiler.CompilerBase``).
    """

    def load_overload(self, sig: Any, target_context: Any) -> Any:
        """The cached overload of ``sig``, or None (a miss). These are numba's internals (checked on numba 0.68):
        should a numba release change them, or a kernel need more than the runtime to load, numba's own loader
        (registries first) takes over, slower and correct."""
        try:
            from numba.core.runtime import nrt

            nrt.rtsys.initialize(target_context)
            with self._guard_against_spurious_io_errors():
                return self._load_overload(sig, target_context)  # type: ignore[no-untyped-call]
        except Exception as error:  # any failure of the shortcut: numba's full path
            log.debug("kernel %s: loading with numba's own cache loader (%s)", getattr(self, "_name", "?"), error)
            return super().load_overload(sig, target_context)  # type: ignore[no-untyped-call]


def njit(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """numba's ``njit(**options)``; a ``cache=True`` kernel loads through :class:`_CacheLoader`."""
    compile_ = numba.njit(**options)

    def decorate(function: Callable[..., Any]) -> Any:
        kernel = compile_(function)
        if isinstance(getattr(kernel, "_cache", None), FunctionCache):  # not under NUMBA_DISABLE_JIT (a function)
            kernel._cache = _CacheLoader(kernel.py_func)  # type: ignore[no-untyped-call]
        return kernel

    return decorate
