"""The physics engines by name (``--engine``): the one list of engine names and how each is opened.

Above :mod:`shc_cli.backends.engine` (the interface) and the engines that implement it, so the interface never
imports an engine (no import circle); ``pybullet`` and ``mujoco`` are imported only when one is opened.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, get_args

from shc_cli.backends.engine import AIR_LIFT as AIR_LIFT
from shc_cli.backends.engine import Engine, EngineOptions
from shc_cli.backends.engine import EngineName as EngineName

if TYPE_CHECKING:
    import numpy as np

    from shc_cli.spec.robot import Robot

ENGINES: tuple[EngineName, ...] = get_args(EngineName)
"""The physics engines ``--engine`` takes; the first is the default."""
DEFAULT_ENGINE: EngineName = ENGINES[0]

Opener = Callable[["Robot", "EngineOptions", "np.ndarray"], Engine]
"""Opens one engine: ``(robot, options, initial_joints)`` (as :func:`open_engine`)."""


def _open_pybullet(robot: Robot, options: EngineOptions, initial_joints: np.ndarray) -> Engine:
    from shc_cli.backends.pybullet_.world import World

    return World(robot, options, initial_joints)


def _open_mujoco(robot: Robot, options: EngineOptions, initial_joints: np.ndarray) -> Engine:
    from shc_cli.errors import BackendError

    if options.gui:
        raise BackendError("MuJoCo: the simulator has no viewer here; run without --gui or with --engine pybullet")
    from shc_cli.backends.mujoco_.world import MujocoWorld

    return MujocoWorld(robot, options, initial_joints)


OPENERS: dict[EngineName, Opener] = {"mujoco": _open_mujoco, "pybullet": _open_pybullet}
"""Engine name → the function that opens it (the same names as :data:`ENGINES`)."""
assert tuple(OPENERS) == ENGINES


def open_engine(robot: Robot, options: EngineOptions, initial_joints: np.ndarray) -> Engine:
    """Open physics engine ``options.engine`` with the robot spawned on the terrain in ``initial_joints``
    ``(L, n)`` [rad], at the robot's control period (``time_delta``).

    Raises:
        BackendError: an unknown engine, or a GUI that cannot open.
    """
    from shc_cli.errors import BackendError

    name = options.engine
    if name not in ENGINES:
        raise BackendError(f"unknown physics engine '{name}'; use {' or '.join(ENGINES)}")
    return OPENERS[name](robot, options, initial_joints)
