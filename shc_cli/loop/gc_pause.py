"""Python's cyclic garbage collector paused around a command's bounded set-up and finishing, on in its run loop.

A simulation's set-up imports numba, MuJoCo and the controller, and its finishing imports matplotlib and draws the
figures: ≈ 150,000 long-lived objects, none of them garbage, that the collector's passes went over again and
again — 0.13 s of the 60 s walk's command on this machine (``gc.callbacks``: 0.06 s before the loop, 0.07 s after,
0.3 ms in it). :func:`paused` turns the collector off for such a block; :func:`collecting` turns it back on for
the run loop inside it, so an open-ended run's memory stays bounded as before.

:func:`no_collection_at_exit` skips the interpreter's last collection as it exits (0.17 s of every ``shc
simulate`` on this machine; Python does not promise finalizers at exit, and shc closes its files itself).
"""

from __future__ import annotations

import atexit
import gc
from collections.abc import Iterator
from contextlib import contextmanager

_paused = False
"""Whether a :func:`paused` block turned the collector off."""


@contextmanager
def paused() -> Iterator[None]:
    """No cyclic collection in this block, except inside :func:`collecting`; the collector's state is restored
    after it (nested blocks, or a collector already off, change nothing)."""
    global _paused
    if _paused or not gc.isenabled():
        yield
        return
    gc.disable()
    _paused = True
    try:
        yield
    finally:
        _paused = False
        gc.freeze()  # with unfreeze: every object into the oldest generation, unscanned (no long first pass)
        gc.unfreeze()
        gc.enable()


@contextmanager
def collecting() -> Iterator[None]:
    """Cyclic collection on in this block (a run loop), also inside :func:`paused` — there the objects made so far
    are first frozen (:func:`gc.freeze`: the loop's collections do not go over the set-up's objects again; they are
    unfrozen when the paused block ends). Outside a paused block: nothing changes."""
    if not _paused:
        yield
        return
    gc.freeze()
    gc.enable()
    try:
        yield
    finally:
        gc.disable()


def no_collection_at_exit() -> None:
    """At exit, before the interpreter's own last collection, freeze every object (:func:`gc.freeze`): that
    collection then has nothing to go over. Logging's handlers are still flushed and closed, and module teardown
    still frees every object outside a reference cycle. Registered once per process."""
    global _at_exit
    if not _at_exit:
        _at_exit = True
        atexit.register(gc.freeze)


_at_exit = False
"""Whether :func:`no_collection_at_exit` registered its exit handler."""
