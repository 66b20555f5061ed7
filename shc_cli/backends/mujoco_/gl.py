"""MuJoCo's headless OpenGL, chosen once, before ``mujoco`` is first imported (it fixes its GL backend then)."""

from __future__ import annotations

import os


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
