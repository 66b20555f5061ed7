"""A path as the run loop's input source (``--path FILE`` of ``plan``, ``simulate``, ``run-hw`` and ``ros``).

:class:`PathInput` is an :class:`~shc_cli.backends.base.InputSource` with the optional feedback hook
:meth:`PathInput.observe`, which the loop (:class:`shc_cli.loop.run_loop.RunLoop`) calls with every cycle's
output: the follower (:class:`shc_cli.control.path_follower.PathFollower`) steers by the controller's odometry
(``CycleOutput.odometry``), never by a simulator's ground truth. Each cycle it asks the walker for its limits in the
direction it wants to go and sends the velocity input (throttle fractions or m/s, the robot's
``walker.velocity_input_mode``) that makes the walker walk the follower's velocity. After the last waypoint it
commands zero velocity until the walker has stopped, then ends the input (``plan`` and ``simulate`` end there,
``run-hw`` shuts down).
"""

from __future__ import annotations

import logging
import math
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.control.controller import Command, Controller, CycleOutput
from shc_cli.control.path_follower import (
    FollowerLimits,
    FollowerOptions,
    PathFollower,
    WaypointResult,
    velocity_input,
)
from shc_cli.control.walk import WalkState
from shc_cli.events import event

if TYPE_CHECKING:
    from shc_cli.spec.path import Path2D

log = logging.getLogger(__name__)


class PathInput:
    """Walks a path with the controller's odometry as feedback.

    Args:
        path: the waypoints.
        controller: the controller whose walker's limits bound the commands (read, never changed).
        cycles: the most cycles to follow for (the run's duration); the input ends then, done or not.
        options: the follower's tolerances and gains (the path file's ``tolerance`` wins over the default).
        cycle: the loop's cycles so far (a path given while the run goes on: ``shc ros``).
    """

    def __init__(self, path: Path2D, controller: Controller, cycles: int | None = None,
                 options: FollowerOptions | None = None, cycle: int = 0) -> None:
        if options is None:
            options = FollowerOptions(turn_while_walking=path.turn_while_walking)
            if path.tolerance_m is not None:
                options = FollowerOptions(tolerance_m=path.tolerance_m,
                                          arrive_m=min(options.arrive_m, path.tolerance_m),
                                          turn_while_walking=path.turn_while_walking)
        self.path = path
        self.follower = PathFollower(path.waypoints, options)
        self.controller = controller
        self.cycles = cycles
        self.played = 0
        self.dt = controller.robot.time_delta
        self._throttle = controller.robot.walker.velocity_input_mode == "throttle"
        self._pose: tuple[float, float, float] | None = None
        self._walk_state = WalkState.STOPPED
        self._observed = cycle
        self.start_cycle: int | None = None
        """The loop's cycle of the input's first command (the follower's time 0)."""
        self._announced = 0
        self.goal_cycle: int | None = None
        """The input's cycle (from its first) at which the last waypoint was left (``None``: not yet)."""

    @property
    def results(self) -> list[WaypointResult]:
        """Per waypoint: reached or missed, closest approach, times (from the input's first cycle)."""
        return self.follower.results

    def observe(self, out: CycleOutput) -> None:
        """The loop's feedback after every controller step: the odometry and the walk state."""
        self._pose = out.odometry
        self._walk_state = out.walk_state
        self._observed += 1

    def limits_for(self, vx: float, vy: float, wz: float) -> FollowerLimits:
        """The walker's limits for a body direction of motion (the walkspace of the current gait): walking in the
        direction of (vx, vy), or turning (the sign of ``wz``) when there is no linear part."""
        size = math.hypot(vx, vy)
        if size > 0.0:
            return self._walker_limits(vx / size, vy / size, 0.0)
        return self._walker_limits(0.0, 0.0, float(np.sign(wz)))

    def _walker_limits(self, x: float, y: float, yaw: float) -> FollowerLimits:
        """The walker's limits for the velocity input (x, y, yaw), as its own cycle will compute them."""
        walker = self.controller.walker
        if walker is None:
            return FollowerLimits(0.0, 0.0, 0.0, 0.0)
        speed, angular, acceleration, angular_acceleration = walker.limits_for(np.array([x, y]), yaw)
        return FollowerLimits(speed, angular, acceleration, angular_acceleration)

    def _input(self, velocity: tuple[float, float, float]) -> tuple[float, float, float]:
        """The velocity input for the follower's body velocity: the walker's limits depend on the input itself
        (each leg's stride bearing), so the conversion is refined twice with the limits of the input found."""
        command = velocity_input(velocity, self.limits_for(*velocity), self._throttle)
        for _ in range(2):
            command = velocity_input(velocity, self._walker_limits(*command), self._throttle)
        vx, vy, wz = command
        if self._throttle:  # the walker clips a throttle input's norm to 1; keep the direction
            size = math.hypot(vx, vy)
            if size > 1.0:
                vx, vy = vx / size, vy / size
            wz = max(-1.0, min(1.0, wz))
        if vx == 0.0 and vy == 0.0 and wz == 0.0:  # a zero input would start the walker's stop
            vx = 1e-9
        return vx, vy, wz

    def next(self) -> Command | None:
        if self.cycles is not None and self.played >= self.cycles:
            return None
        follower = self.follower
        if follower.done and self._walk_state == WalkState.STOPPED:
            return None
        if self.start_cycle is None:
            self.start_cycle = self._observed
        self.played += 1
        if self._pose is None or self.controller.walker is None or follower.done:
            return Command()
        velocity = follower.update(self._pose, self.limits_for, self.dt)
        self._report()
        if follower.done:
            if self.goal_cycle is None:
                self.goal_cycle = self.played - 1
            return Command()
        return Command(velocity=self._input(velocity))

    def _report(self) -> None:
        """An event for each waypoint the follower has moved on from."""
        while self._announced < self.follower.index:
            result = self.follower.results[self._announced]
            w = result.waypoint
            how = "reached" if result.reached else "missed"
            event(log, logging.INFO, "waypoint", "waypoint %d (%.3f, %.3f) %s: closest %.3f m, left after %.2f s",
                  result.index + 1, w.x, w.y, how, result.closest_m, result.left_s or 0.0)
            self._announced += 1

    def keep_file(self, directory: Path) -> str | None:
        """Copy the path file into the run ``directory`` as ``path.csv`` or ``path.toml``; its name there."""
        source = self.path.source
        if source is None:
            return None
        name = "path.toml" if source.suffix.lower() == ".toml" else "path.csv"
        shutil.copyfile(source, directory / name)
        return name

    def summary(self) -> dict[str, object]:
        """The run summary's path fields (:class:`~shc_cli.record.summary.RunSummary`)."""
        options = self.follower.options
        waypoints = [{
            "x": r.waypoint.x, "y": r.waypoint.y, "yaw": r.waypoint.yaw, "reached": r.reached,
            "closest_m": r.closest_m if math.isfinite(r.closest_m) else None, "reached_s": r.reached_s,
            "left_s": r.left_s, "position_error_m": r.position_error_m, "heading_error_rad": r.heading_error_rad,
        } for r in self.results]
        return {"path_tolerance_m": options.tolerance_m, "path_heading_tolerance_rad": options.heading_tolerance_rad,
                "path_start_cycle": self.start_cycle, "waypoints": waypoints}

    def close(self) -> None:
        """Nothing to release."""


def keep_path(source: object, directory: Path) -> Callable[[], dict[str, object]]:
    """For a run whose input is a path (:class:`PathInput`): its file copied into the run ``directory`` now, and the
    summary's path fields when called at the run's end; for any other input no copy and no fields."""
    if not isinstance(source, PathInput):
        return dict
    name = source.keep_file(directory)
    return lambda: {"path_file": name, **source.summary()}
