"""The recorded goals replayed open-loop in a physics engine with a candidate servo model.

The engine world is the one ``simulate`` runs on (:func:`shc_cli.backends.simulated.open_world`, the
:class:`~shc_cli.backends.engine.Engine` interface its :class:`~shc_cli.backends.simulated.SimulatedBackend` wraps)
in the run's scenario; each logged cycle gives the world that cycle's goals, one control period of physics and a
reading — the backend's own cycle without the controller, since the goals are already known. The stand of a stand
start is released at the first RUNNING cycle, as the backend does. A simulated run replayed with its own servo
gives its own log back (to the log's 6 digits).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.domain.fit.recording import Recording, speeds

if TYPE_CHECKING:
    from shc_cli.backends.engine_registry import EngineName
    from shc_cli.spec.robot import Robot, Servo

PHYSICS_RATE = 400.0
"""Physics steps per second of the replay [Hz] (``simulate``'s default)."""


@dataclass(frozen=True)
class Trace:
    """What the replay measured, servo order.

    Attributes:
        position: joint positions at the end of each cycle ``(N, J)`` [rad].
        torque: output torque averaged over each cycle ``(N, J)`` [N·m].
    """

    position: np.ndarray
    torque: np.ndarray

    def speed(self, dt: float) -> np.ndarray:
        """Mean joint speed of each cycle ``(N, J)`` [rad/s] (the log's differences; the first row 0)."""
        return speeds(self.position, dt)


def replay(recording: Recording, servo: Servo, engine: EngineName = "mujoco") -> Trace:
    """Replay ``recording``'s goals with ``servo`` in ``engine``."""
    from shc_cli.backends.engine import EngineOptions
    from shc_cli.backends.engine_registry import open_engine
    from shc_cli.backends.simulated import open_world
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.domain.config import SCENARIOS

    robot = recording.robot.model_copy(update={"servo": servo})
    airborne = SCENARIOS[recording.scenario][0]
    substeps = max(1, round(PHYSICS_RATE * robot.time_delta))
    stand = robot.start_up.simulation == "stand" and not recording.measured_start
    options = EngineOptions(parse_terrain(recording.terrain), substeps, airborne, seed=recording.seed, stand=stand,
                            engine=engine)
    goals = recording.commanded
    world = None
    try:
        if recording.measured_start:
            world = open_engine(robot, options, _padded(world_rows(robot), recording.position[0]))
        else:
            world = open_world(robot, options)
        rows, cols = world.slot_rows, world.slot_cols
        padded = np.zeros((len(robot.legs), int(cols.max()) + 1))
        n = len(goals)
        position, torque = np.empty((n, len(rows))), np.empty((n, len(rows)))
        for i in range(n):
            padded[rows, cols] = goals[i]
            world.command(padded)
            world.step()
            reading = world.read()
            position[i] = reading.joints[rows, cols]
            torque[i] = reading.joint_efforts[rows, cols]
            if world.stand is not None and recording.running[i]:
                world.release_stand()
    finally:
        if world is not None:
            world.close()
    return Trace(position, torque)


def world_rows(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """Leg and joint index of each servo in the padded ``(L, n)`` arrays."""
    from shc_cli.model.chains import joint_slots

    return joint_slots(robot)


def _padded(slots: tuple[np.ndarray, np.ndarray], values: np.ndarray) -> np.ndarray:
    rows, cols = slots
    out = np.zeros((int(rows.max()) + 1, int(cols.max()) + 1))
    out[rows, cols] = values
    return out
