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
        current: motor current at the end of each cycle ``(N, J)`` [A] where the replay models it (a bench's
            load-free joints), else None (the electrical model gives it from torque and speed).
    """

    position: np.ndarray
    torque: np.ndarray
    current: np.ndarray | None = None

    def speed(self, dt: float) -> np.ndarray:
        """Mean joint speed of each cycle ``(N, J)`` [rad/s] (the log's differences; the first row 0)."""
        return speeds(self.position, dt)


def replay(recording: Recording, servo: Servo, engine: EngineName = "mujoco") -> Trace:
    """Replay ``recording``'s goals with ``servo`` in ``engine`` (a BENCH recording: the load-free servo joints of
    :func:`bench_replay`, no engine)."""
    if recording.scenario == "BENCH":
        return bench_replay(recording, servo)
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


def bench_replay(recording: Recording, servo: Servo) -> Trace:
    """Replay ``recording``'s goals on load-free servo joints (:func:`shc_cli.backends.servo_joint.free_response`,
    the servo emulator's model) from the first logged positions, on the run's own time line where it has one
    (:func:`cycle_timing`): positions and motor currents as the bus reads them, and the output torque
    ``k_t·I − viscous·ω`` for the power model."""
    from shc_cli.backends.servo_joint import free_response

    timing = cycle_timing(recording)
    period, delay = timing if timing is not None else (recording.dt, None)
    response = free_response(servo, goal_ticks(recording), period, recording.position[0], delay)
    torque = servo.torque_constant * response.current - servo.viscous_friction * response.speed
    return Trace(response.position, torque, response.current)


def goal_ticks(recording: Recording) -> np.ndarray:
    """The goals as the servos received them ``(N, J)`` [rad]: whole ticks of each joint's servo model
    (``[hardware]``), on the grid of its own readings (zero tick and joint offset included). Half a tick of goal is
    a few mA of a stiff servo's current."""
    import math

    from shc_cli.hardware.models import MODELS
    from shc_cli.record.runlog import joint_columns

    hardware = recording.robot.hardware
    per_radian = []
    for key in joint_columns(recording.robot):
        entry = hardware.servos.get(key)
        model = MODELS.get((entry.model if entry is not None and entry.model else None) or hardware.model)
        generic = model is None or model.name == "generic"
        ticks = hardware.ticks_per_revolution if generic or model is None else model.ticks_per_revolution
        per_radian.append(ticks / (2.0 * math.pi))
    scale = np.array(per_radian)
    grid = recording.position[0]
    return np.asarray(grid + np.round((recording.commanded - grid) * scale) / scale)


def cycle_timing(recording: Recording) -> tuple[np.ndarray, np.ndarray] | None:
    """A run-hw recording's time line from its ``timing.csv`` (None without one): per cycle, the time from one
    reading to the next [s] — the control period, or the cycle time itself after an overrun (run-hw then reads at
    once) — and the time from the previous reading to the goal's write [s] (the cycle time, capped at the period)."""
    path = recording.path / "timing.csv"
    if not path.exists():
        return None
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    count = len(recording.commanded)
    if table.shape[0] < count or table.shape[1] < 4:
        return None
    cycle_time, overrun = table[:count, 2] / 1000.0, table[:count, 3] > 0
    period = np.where(overrun, np.maximum(cycle_time, recording.dt), recording.dt)
    return period, np.minimum(cycle_time, period)


def world_rows(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """Leg and joint index of each servo in the padded ``(L, n)`` arrays."""
    from shc_cli.model.chains import joint_slots

    return joint_slots(robot)


def _padded(slots: tuple[np.ndarray, np.ndarray], values: np.ndarray) -> np.ndarray:
    rows, cols = slots
    out = np.zeros((int(rows.max()) + 1, int(cols.max()) + 1))
    out[rows, cols] = values
    return out
