"""Fall detection and the physics run's series and summary (engine-independent: they read a backend's reading).

:class:`PhysicsRecord` is an observer of the run loop: it keeps the series the summary and the plots need (time,
body position, total power, contacts, RUNNING), finds the analysed window (the RUNNING cycles) and stops the run
when the robot has fallen: body tilt above :data:`FALL_TILT`, or (on the ground) the body lower than
:data:`FALL_HEIGHT_SHARE` of the body clearance.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.analysis.cot import cost_of_transport
from shc_cli.backends.engine import tilt
from shc_cli.control.controller import RobotState
from shc_cli.loop.summary import RunSummary

if TYPE_CHECKING:
    from shc_cli.backends.engine import Reading
    from shc_cli.backends.simulated import SimulatedBackend
    from shc_cli.control.controller import Command, Controller, CycleOutput
    from shc_cli.spec.robot import Robot

FALL_TILT = 0.8
"""Body tilt above which the robot has fallen [rad] (≈ 46°)."""
FALL_HEIGHT_SHARE = 0.3
"""The robot has fallen when its body is lower than this share of the body clearance above the terrain."""


class PhysicsRecord:
    """Series, fall detection and summary of a physics run (an observer of :class:`~shc_cli.loop.run_loop.RunLoop`).

    Args:
        robot: the robot.
        backend: the physics backend (its world's physics time; its last total power).
        airborne: the body is held in the air (no height check).
    """

    def __init__(self, robot: Robot, backend: SimulatedBackend, airborne: bool) -> None:
        self.robot, self.backend, self.airborne = robot, backend, airborne
        self.series: dict[str, list[Any]] = {"t": [], "position": [], "power": [], "contact": [], "running": [],
                                             "desired": []}
        self.window_start: np.ndarray | None = None
        self.max_tilt = 0.0
        self.fell = False
        self.low_height = FALL_HEIGHT_SHARE * robot.walker.body_clearance
        self.started = time.perf_counter()
        self._running_since: tuple[float, float] | None = None

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: Reading) -> str | None:
        series = self.series
        running = out.robot_state == RobotState.RUNNING
        series["t"].append(cycle * self.robot.time_delta)
        series["position"].append(reading.position)
        series["power"].append(self.backend.total_power)
        series["contact"].append(reading.foot_contact)
        series["running"].append(running)
        series["desired"].append(out.velocity)
        if running:
            if self.window_start is None:  # where the body was when the first RUNNING cycle began
                self.window_start = series["position"][-2] if len(series["position"]) > 1 else reading.position
                self._running_since = (time.perf_counter(), self.backend.world.physics_time)
            self.max_tilt = max(self.max_tilt, tilt(reading.rpy))
            low = reading.body_height < self.low_height
            if self.max_tilt > FALL_TILT or (low and not self.airborne):
                self.fell = True
                return "fell"
        return None

    def summary(self, scenario: str, gait: str, controller: Controller) -> RunSummary:
        """Paper eq. 22 cost of transport over the RUNNING window: mean power / (m·g·v) (WG only)."""
        world = self.backend.world
        wall = time.perf_counter() - self.started
        since_wall, since_physics = self._running_since or (time.perf_counter(), world.physics_time)
        robot, dt, series = self.robot, self.robot.time_delta, self.series
        running = np.array(series["running"], dtype=bool)
        power = np.array(series["power"])
        window = float(running.sum()) * dt
        end = series["position"][-1] if series["position"] else np.zeros(3)
        start = self.window_start if self.window_start is not None else end
        distance = float(np.linalg.norm((end - start)[:2]))
        speed = distance / window if running.sum() >= 2 else 0.0  # as path speed: one cycle is no walk (a robot
        # thrown off the floor at start-up, caught by the fall check in its first RUNNING cycle, once had 7 m/s)
        from shc_cli.analysis.metrics import window_speeds
        from shc_cli.analysis.progress import cycle_path_length, progress_fields

        xy = np.array(series["position"])[:, :2] if series["position"] else np.zeros((0, 2))
        path_speed, _ = window_speeds(xy, np.flatnonzero(running), dt)
        desired = np.array(series["desired"]).reshape(-1, 3)[running[:len(series["desired"])], :2]
        commanded = float(np.linalg.norm(desired, axis=1).mean()) if len(desired) else 0.0
        mean_power = float(power[running].mean()) if running.any() else 0.0
        mass = robot.total_mass()
        cot = cost_of_transport(mean_power, mass, speed) if scenario == "WG" else None
        return RunSummary.model_validate({
            "robot": robot.name,
            "gait": gait,
            "scenario": scenario,
            "sim_time_s": len(series["t"]) * dt,
            "analysed_time_s": window,
            "wall_time_s": wall,
            "running_wall_time_s": time.perf_counter() - since_wall,
            "running_physics_time_s": world.physics_time - since_physics,
            "physics_time_s": world.physics_time,
            "physics_rate_hz": world.substeps / dt,
            "distance_m": distance,
            "forward_distance_m": float((end - start)[0]),
            "mean_speed_mps": speed,  # = displacement_speed_mps, its first name
            "displacement_speed_mps": speed,
            "path_speed_mps": path_speed,
            "commanded_speed_mps": commanded,
            **progress_fields(cycle_path_length(_window_path(xy, running), controller.cycle.period), commanded,
                              window),
            "mean_power_w": mean_power,
            "mass_kg": mass,
            "step_frequency_hz": controller.parameters["step_frequency"],
            "step_period_cycles": controller.cycle.period,
            "cycle_frequency_hz": controller.cycle.frequency,
            "duty_factor": controller.cycle.duty_factor,
            "cot": cot,
            "max_tilt_rad": self.max_tilt,
            "fell": self.fell,
        })


def _window_path(xy: np.ndarray, running: np.ndarray) -> np.ndarray:
    """The body path over the RUNNING rows, starting where the row before the first of them ended."""
    rows = np.flatnonzero(running)
    if len(rows) == 0:
        return np.zeros((0, 2))
    return np.vstack([xy[max(rows[0] - 1, 0)], xy[rows[0]:rows[-1] + 1]])
