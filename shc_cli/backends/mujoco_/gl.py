"""MuJoCo's headless OpenGL: none for the physics, chosen when a frame is first rendered.

MuJoCo picks its GL backend (``MUJOCO_GL``) when it is imported, and a GL backend imports PyOpenGL (0.1 s). The
physics needs no GL, so :func:`import_for_physics` imports MuJoCo with GL disabled; :func:`enable_rendering` then
gives a process that renders later (``simulate --video``, a test session) the backend :func:`choose_gl` picks.
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import Any

_deferred = False
"""Whether this process imported MuJoCo with GL disabled by :func:`import_for_physics` (not by the user)."""


def choose_gl(fallback: str | None) -> None:
    """Set ``MUJOCO_GL`` unless the user did: OSMesa when libOSMesa is installed, else ``fallback``.

    Args:
        fallback: the backend without OSMesa — ``"egl"`` to render; ``None`` to leave ``MUJOCO_GL`` unset (the
            physics needs no GL, and a missing EGL library would make ``import mujoco`` fail).
    """
    if "MUJOCO_GL" in os.environ:
        return
    import ctypes.util

    backend = "osmesa" if ctypes.util.find_library("OSMesa") else fallback
    if backend is None:
        return
    os.environ["MUJOCO_GL"] = backend
    if backend == "osmesa":
        os.environ.setdefault("PYOPENGL_PLATFORM", "osmesa")


def import_for_physics() -> Any:
    """``mujoco`` for stepping only: imported with ``MUJOCO_GL=disable`` unless the user set ``MUJOCO_GL`` (the
    environment is restored at once: child processes see the user's). Already imported: as it is."""
    global _deferred
    if "mujoco" in sys.modules or "MUJOCO_GL" in os.environ:
        import mujoco

        return mujoco
    os.environ["MUJOCO_GL"] = "disable"
    try:
        import mujoco
    finally:
        del os.environ["MUJOCO_GL"]
    _deferred = True
    return mujoco


def enable_rendering(fallback: str = "egl") -> Any:
    """``mujoco`` ready to render offscreen: :func:`choose_gl`'s backend, also when :func:`import_for_physics`
    imported MuJoCo without GL (its GL-context module, which ``mujoco.Renderer`` reads when it is made, is loaded
    again with the chosen backend)."""
    global _deferred
    choose_gl(fallback)
    import mujoco

    if _deferred:
        context = getattr(sys.modules.get(getattr(mujoco.Renderer, "__module__", "")), "gl_context", None)
        if context is not None:
            importlib.reload(context)
        _deferred = False
    return mujoco
