"""Fall detection and the physics run's summary (engine-independent: they read a backend's reading and the log).

:class:`PhysicsRecord` is an observer of the run loop: it stops the run when the robot has fallen — from the first
cycle, start-up included, body tilt above :data:`FALL_TILT` (a flip) or (on the ground) the body higher than
:data:`LAUNCH_SHARE` of its standing height plus a leg's length (thrown up: a knee pushed through the floor);
while RUNNING also the body lower than :data:`FALL_HEIGHT_SHARE` of the body clearance (a start-up rises from the
ground); a fall seen during start-up is confirmed :data:`START_UP_GRACE_S` later — and times the RUNNING part.
Its summary is made from the finished log (``log.csv``, read back): the speeds, power and cost of transport are
:func:`shc_cli.analysis.metrics.walk_figures` over the RUNNING rows, the numbers
``shc analyze`` gives for the same window.
"""

from __future__ import annotations

import logging
import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from shc_cli.backends.engine import tilt
from shc_cli.control.controller import RobotState
from shc_cli.events import event
from shc_cli.record.summary_kinds import Kind, summary_of

if TYPE_CHECKING:
    from shc_cli.backends.engine import Reading
    from shc_cli.backends.simulated import SimulatedBackend
    from shc_cli.control.controller import Command, Controller, CycleOutput
    from shc_cli.record.runread import RunLog
    from shc_cli.record.summary import RunSummary
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

FALL_TILT = 0.8
"""Body tilt above which the robot has fallen [rad] (≈ 46°)."""
FALL_HEIGHT_SHARE = 0.3
"""The robot has fallen when its body is lower than this share of the body clearance above the terrain."""
MAX_BODY_SPEED = 20.0
"""Body speed above which the physics has diverged [m/s] (a walking robot moves well under 2 m/s, one falling
from its height under 5 m/s: beyond this the simulation is blowing up, e.g. energy gained at each contact)."""
_MAX_SPEED_SQUARED = MAX_BODY_SPEED * MAX_BODY_SPEED
LAUNCH_SHARE = 2.0
"""The robot was launched when its body is higher above the terrain than this many times its standing height
plus its longest leg's length (no gait lifts a body above the height its straight legs reach)."""
START_UP_GRACE_S = 2.0
"""A fall seen during start-up stops the run this long after it [s] (at once once RUNNING), unless the physics
diverges first: a blow-up tips the body over before its speed shows it (ATHENA at a 20 Hz physics rate flips at
1.0 s and passes :data:`MAX_BODY_SPEED` at 2.0 s), and a diverged run says what to change."""
DIVERGED = "diverged"
"""The stop reason of a run whose physics blew up (:meth:`PhysicsRecord.__call__`)."""


class PhysicsRecord:
    """Fall detection and summary of a physics run (an observer of :class:`~shc_cli.loop.run_loop.RunLoop`).

    Args:
        robot: the robot.
        backend: the physics backend (its world's physics time and rate).
        airborne: the body is held in the air (no height check).
    """

    def __init__(self, robot: Robot, backend: SimulatedBackend, airborne: bool) -> None:
        self.robot, self.backend, self.airborne = robot, backend, airborne
        self.cycles = 0
        self.max_tilt = 0.0
        self.fell = False
        self.diverged: str | None = None
        """What showed the physics had blown up (the run stopped, ``stop_reason`` :data:`DIVERGED`), or None."""
        self.low_height = FALL_HEIGHT_SHARE * robot.walker.body_clearance
        self.high_height = LAUNCH_SHARE * (robot.walker.body_clearance + leg_length(robot))
        """Body height above which the robot was thrown up [m]."""
        self.whole_max_tilt = 0.0
        """The largest tilt of the whole run, start-up included [rad] (``max_tilt`` is RUNNING's)."""
        self.fall: str | None = None
        """How the robot fell (the summary's ``fall``), or None."""
        self.started = time.perf_counter()
        self.log: RunLog | None = None
        """The finished log, once :meth:`summary` has read it."""
        self._running_since: tuple[float, float] | None = None
        self._pending: tuple[int, str] | None = None
        """A fall seen during start-up (its cycle and how), confirmed :data:`START_UP_GRACE_S` later."""

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: Reading) -> str | None:
        self.cycles += 1
        vx, vy, vz = reading.linear_velocity.tolist()
        x, y, z = reading.position.tolist()
        speed_squared = vx * vx + vy * vy + vz * vz
        if not (speed_squared <= _MAX_SPEED_SQUARED and math.isfinite(x + y + z)):  # NaN fails both
            return self._blew_up(cycle, reading, speed_squared)
        angle = tilt(reading.rpy)
        self.whole_max_tilt = max(self.whole_max_tilt, angle)
        running = out.robot_state == RobotState.RUNNING
        if running:
            if self._running_since is None:
                self._running_since = (time.perf_counter(), self.backend.world.physics_time)
            self.max_tilt = max(self.max_tilt, angle)
        height = reading.body_height
        low = running and height < self.low_height and not self.airborne
        high = height > self.high_height and not self.airborne
        if self._pending is None and (angle > FALL_TILT or low or high):
            phase = "walking" if running else "during start-up"
            how = "flipped" if angle > FALL_TILT else ("thrown up" if high else "collapsed")
            self._pending = (cycle, f"{how} {phase} at {cycle * self.robot.time_delta:.2f} s: body tilt {angle:.3f} "
                                    f"rad (limit {FALL_TILT:g}), height {height:.3f} m (limits {self.low_height:.3f} "
                                    f"… {self.high_height:.3f})")
        if self._pending is not None and (running or (cycle - self._pending[0]) * self.robot.time_delta
                                          >= START_UP_GRACE_S):
            self.fell, self.fall = True, self._pending[1]
            event(log, logging.WARNING, "fell", "fell: %s", self.fall, cycle=self._pending[0], terminal=False)
            return "fell"
        return None

    def _blew_up(self, cycle: int, reading: Reading, speed_squared: float) -> str:
        position = ", ".join(f"{v:.3g}" for v in reading.position)
        self.diverged = (f"the physics diverged at cycle {cycle}: body speed {speed_squared ** 0.5:.3g} m/s (limit "
                         f"{MAX_BODY_SPEED:g}), position ({position}) m")
        event(log, logging.WARNING, "diverged", "%s", self.diverged, cycle=cycle, terminal=False)
        return DIVERGED

    def summary(self, directory: Path, scenario: str, gait: str, controller: Controller,
                fields: dict[str, object] | None = None, kinds: tuple[Kind, ...] = ("simulate",)) -> RunSummary:
        """The summary from the finished log in ``directory`` (the run directory, still ``.partial``); paper eq. 22
        cost of transport over the RUNNING window: mean power / (m·g·v) (WG only). ``fields``: the run's other
        fields (its engine, the fields every run shares, :class:`~shc_cli.loop.assembly.Finished`), made into the
        summary with these (a field of both: ``fields``' value), a summary of ``kinds``
        (:func:`~shc_cli.record.summary_kinds.summary_of`)."""
        from shc_cli.analysis.metrics import walk_figures
        from shc_cli.record.runread import read_tables

        world = self.backend.world
        now = time.perf_counter()  # the timings are the run's, not the reading of its log
        for warning in world.warnings:  # the command prints them as notes
            event(log, logging.WARNING, "engine_warning", "%s: %s", world.name, warning, terminal=False)
        since_wall, since_physics = self._running_since or (now, world.physics_time)
        robot, dt = self.robot, self.robot.time_delta
        finished = self.log = read_tables(directory, robot) if self.cycles else None
        rows = np.flatnonzero(finished.running) if finished is not None else np.zeros(0, dtype=np.intp)
        if finished is not None:
            figures = walk_figures(finished, rows, scenario == "WG", controller.cycle.period)
            progress = window_progress(finished, rows, controller.cycle.period,  # nothing to travel in the air
                                       0.0 if self.airborne else figures.commanded_speed_mps)
            distance, forward, speed = figures.distance_m, figures.forward_distance_m, figures.displacement_speed_mps
            path_speed, commanded, power = figures.path_speed_mps, figures.commanded_speed_mps, figures.mean_power_w
            mass, cot, cot_displacement, walked = figures.mass_kg, figures.cot, figures.cot_displacement, \
                figures.walked_m
        else:  # stopped before its first cycle: nothing was walked
            from shc_cli.analysis.progress import progress_fields
            from shc_cli.model.body import body_mass

            progress = progress_fields(0.0, 0.0, 0.0)
            distance = forward = speed = path_speed = commanded = 0.0
            power, mass, cot, cot_displacement, walked = None, body_mass(robot), None, None, 0.0
        return summary_of(kinds, {
            "robot": robot.name,
            "gait": gait,
            "scenario": scenario,
            "sim_time_s": self.cycles * dt,
            "analysed_time_s": len(rows) * dt,
            "wall_time_s": now - self.started,
            "running_wall_time_s": now - since_wall,
            "running_physics_time_s": world.physics_time - since_physics,
            "physics_time_s": world.physics_time,
            "physics_rate_hz": world.substeps / dt,
            "distance_m": distance,
            "forward_distance_m": forward,
            "mean_speed_mps": speed,  # = displacement_speed_mps, its first name
            "displacement_speed_mps": speed,
            "path_speed_mps": path_speed,
            "commanded_speed_mps": commanded,
            **progress,
            "mean_power_w": power,  # None: nothing walked to measure
            "mass_kg": mass,
            "servo_model": robot.servo.model,
            "step_frequency_hz": controller.parameters["step_frequency"],
            "step_period_cycles": controller.cycle.period,
            "cycle_frequency_hz": controller.cycle.frequency,
            "duty_factor": controller.cycle.duty_factor,
            "cot": cot,
            "cot_displacement": cot_displacement,
            "walked_m": walked,
            "max_tilt_rad": self.max_tilt,
            "fell": self.fell,
            **({"fall": self.fall} if self.fall is not None else {}),
            **({"fault": self.diverged} if self.diverged is not None else {}),
            **final_poses(finished),
            **(fields or {}),
        })

    def plot_series(self, directory: Path) -> dict[str, Any]:
        """What :func:`shc_cli.plots.plot_simulation` draws, from the finished log in ``directory`` (the one
        :meth:`summary` read, or read now: a second signal may have cut the summary short)."""
        from shc_cli.record.runread import read_tables

        log = self.log if self.log is not None else read_tables(directory, self.robot)
        return {"t": log.t, "position": log.position, "power": log.power, "contact": log.contact,
                "running": log.running, "yaw": log.rpy[:, 2], "odometry": log.odometry}


def leg_length(robot: Robot) -> float:
    """The longest leg's length: the sum of its links' lengths (DH offsets), from its first joint to its tip [m]."""
    from shc_cli.model.body import joint_offset

    return max(sum(math.dist((0.0, 0.0, 0.0), joint_offset(joint)) for joint in leg.joints.values())
               for leg in robot.legs.values())


def final_poses(log: RunLog | None) -> dict[str, list[float]]:
    """The summary's ``odometry_pose`` and ``true_pose``: the last row's leg odometry and ground truth, the truth
    relative to the first row's pose (the odom frame); empty when there is no row or no odometry column."""
    if log is None or log.odometry is None or not len(log.t):
        return {}
    from shc_cli.analysis.odometry import has_ground_truth, relative

    poses = {"odometry_pose": [float(v) for v in log.odometry[-1]]}
    if has_ground_truth(log):
        truth = relative(np.column_stack([log.position[:, :2], log.rpy[:, 2]]))
        poses["true_pose"] = [float(v) for v in truth[-1]]
    return poses


def window_progress(log: RunLog, rows: np.ndarray, period: int, commanded_speed_mps: float) -> dict[str, Any]:
    """The summary's progress fields (:func:`shc_cli.analysis.progress.progress_fields`) over the window ``rows``:
    the body's path from where the window began, sampled once per gait cycle of ``period`` rows."""
    from shc_cli.analysis.metrics import window_path
    from shc_cli.analysis.progress import cycle_path_length, progress_fields

    walked = cycle_path_length(window_path(log.position[:, :2], rows), period)
    return progress_fields(walked, commanded_speed_mps, len(rows) * log.dt)
