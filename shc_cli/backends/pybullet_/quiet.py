"""Silencing PyBullet's C-level output (warnings on file descriptor 1, its build-time banner on 2)."""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager


@contextmanager
def quiet_stdout() -> Iterator[None]:
    """Silence PyBullet's C-level messages: warnings go to file descriptor 1, the build-time banner to 2."""
    import ctypes

    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with open(os.devnull, "w") as null:
        os.dup2(null.fileno(), 1)
        os.dup2(null.fileno(), 2)
    try:
        yield
    finally:
        libc.fflush(None)  # C stdio buffers fully when stdout is a pipe: drop its text while 1 is still /dev/null
        for fd, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, fd)
            os.close(copy)
