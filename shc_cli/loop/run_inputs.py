"""What every run command reads before it runs: the robot and gait, the command timeline or path, the auto-pose sets.

Shared by ``plan``, ``simulate`` and ``run-hw`` (and the Python API), so they accept the same options the same way.
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.errors import Issue, SpecError
from shc_cli.loop.input_sources import TimelineCommands, TimelineInput, timeline_commands
from shc_cli.spec.autopose import AutoPoseSet, compatibility_issues, load_auto_pose_set
from shc_cli.spec.gait import Gait
from shc_cli.spec.path import Path2D, load_path
from shc_cli.spec.robot import Robot
from shc_cli.spec.timeline import Timeline, constant, load_timeline

if TYPE_CHECKING:
    from shc_cli.backends.base import InputSource
    from shc_cli.control.controller import Controller

logger = logging.getLogger(__name__)

PATH_TIME_PER_WAYPOINT_S = 60.0
"""Without ``--duration``, a path run lasts at most this long per waypoint [s] (the follower's per-waypoint timeout,
:class:`~shc_cli.control.path_follower.FollowerOptions`); it ends when the robot has stopped at the last."""

MAX_DURATION_ENV = "SHC_MAX_DURATION"
"""Environment variable (a test aid): when set to seconds, every run's time after start-up is cut to at most that,
whatever ``--duration``, a timeline file, a sweep or a study asks (the docs tests run the docs' commands as written,
only shorter)."""


def max_duration() -> float | None:
    """``SHC_MAX_DURATION`` [s] when set to a positive number, else None (a malformed value is a one-line error)."""
    text = os.environ.get(MAX_DURATION_ENV, "").strip()
    if not text:
        return None
    try:
        seconds = float(text)
    except ValueError:
        seconds = math.nan
    if not (seconds > 0 and math.isfinite(seconds)):
        raise SpecError([Issue(None, None, MAX_DURATION_ENV, f"'{text}' is not a positive number of seconds",
                               f"unset it or set e.g. {MAX_DURATION_ENV}=2")])
    return seconds


def parse_velocity(text: str) -> tuple[float, float, float]:
    """``"VX,VY,WZ"`` → floats, or a one-line error."""
    parts = text.split(",")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != 3 or any(not math.isfinite(v) for v in values):
        raise SpecError([Issue(None, None, "--velocity", f"'{text}' is not three numbers VX,VY,WZ",
                               "e.g. --velocity 0.5,0,0")])
    return values


def check_throttle(robot: Robot, velocity: tuple[float, float, float], field: str = "--velocity") -> None:
    """A one-line error when a throttle velocity input is outside −1…1 (the controller would clamp it silently);
    robots whose ``walker.velocity_input_mode`` is ``real`` take m/s and rad/s and are not checked."""
    if robot.walker.velocity_input_mode != "throttle":
        return
    over = [f"{name} {value:g}" for name, value in zip(("VX", "VY", "WZ"), velocity, strict=True) if abs(value) > 1.0]
    if over:
        raise SpecError([Issue(None, None, field, f"{', '.join(over)} is outside the throttle range −1…1 (fractions "
                               f"of {robot.name}'s maximum speed)", "e.g. --velocity 1,0,0 for full speed ahead")])


def check_duration(duration: float | None) -> None:
    """A one-line error unless ``duration`` is None or a positive number of seconds."""
    if duration is not None and (duration <= 0 or not math.isfinite(duration)):
        raise SpecError([Issue(None, None, "--duration", f"{duration:g} must be a positive number of seconds",
                               "e.g. --duration 20")])


def walk_cycles(timeline: Timeline, duration: float | None, dt: float, from_file: bool,
                default_s: float = 10.0) -> int:
    """Control cycles to play after start-up: ``duration`` [s] if given, else a timeline file's length plus 1 s,
    else ``default_s`` [s]; at most ``SHC_MAX_DURATION`` [s] when that is set (:func:`max_duration`)."""
    if duration is not None:
        cycles = max(1, round(duration / dt))
    elif from_file:
        cycles = timeline.last_cycle + round(1.0 / dt)
    else:
        cycles = round(default_s / dt)
    cap = max_duration()
    if cap is not None and cycles * dt > cap:
        logger.warning("%s=%g: the run is cut to %g s after start-up (%g s asked)", MAX_DURATION_ENV, cap, cap,
                       cycles * dt)
        cycles = max(1, round(cap / dt))
    return cycles


def pose_sets_for(robot: Robot, gait: Gait, timeline: Timeline, folder: Path) -> dict[str, AutoPoseSet]:
    """The auto-pose set of every gait a run uses (``pose.auto_pose_type``; 'auto' = named after the gait);
    empty when the robot does not auto-pose."""
    if not robot.pose.auto:
        return {}
    gaits = [gait, *(switch for _, c in timeline.changes if isinstance(switch := c.get("gait"), Gait))]
    sets: dict[str, AutoPoseSet] = {}
    for used in gaits:
        loaded = load_auto_pose_set(robot.pose.auto_pose_type, used, relative_to=folder)
        problems = compatibility_issues(loaded, used, list(robot.legs))
        if problems:
            raise SpecError(problems)
        sets[used.name] = loaded.pose_set
    return sets


def check_timeline(robot: Robot, timeline: Timeline, commands: Path | None) -> None:
    """Legs and gaits a timeline names must fit the robot (one-line errors)."""
    for _, change in timeline.changes:
        tips = {**_mapping(change.get("tip_velocity")), **_mapping(change.get("tip_position"))}
        named = [change.get("leg_toggle"), *tips]
        unknown = [leg for leg in named if leg is not None and leg not in robot.legs]
        if unknown:
            raise SpecError([Issue(commands, None, "step", f"no leg '{unknown[0]}' on robot '{robot.name}'",
                                   f"legs: {', '.join(robot.legs)}")])
        new_gait = change.get("gait")
        if isinstance(new_gait, Gait) and set(new_gait.offset_multiplier) != set(robot.legs):
            raise SpecError([Issue(commands, None, "gait", f"gait '{new_gait.name}' does not fit robot '{robot.name}'",
                                   f"give one multiplier for each of {', '.join(robot.legs)}")])


def _mapping(value: object) -> dict[str, object]:
    return dict(value) if isinstance(value, dict) else {}


@dataclass(frozen=True)
class RunInputs:
    """A run's robot, gait, timeline or path (and how many cycles of it to play) and auto-pose sets."""

    robot: Robot
    gait: Gait
    timeline: Timeline
    cycles: int
    pose_sets: dict[str, AutoPoseSet]
    path: Path2D | None = None

    def commands(self) -> TimelineCommands:
        """The command of every cycle of the run, made when asked for."""
        return timeline_commands(self.timeline, self.cycles)

    def source(self, controller: Controller) -> InputSource:
        """The run's input: the path follower steering ``controller`` (:class:`~shc_cli.loop.path_input.PathInput`)
        when there is a path, else the timeline."""
        if self.path is not None:
            from shc_cli.loop.path_input import PathInput

            return PathInput(self.path, controller, self.cycles)
        return TimelineInput(self.commands())


def load_inputs(robot_name: str, gait_name: str | None, velocity: str | tuple[float, float, float],
                duration: float | None, commands: Path | None, default_s: float, walking: bool = True,
                robot_change: object = None, check_fit: bool = False, path: Path | None = None) -> RunInputs:
    """Load and check a run's inputs.

    Args:
        robot_name: robot file or bundled name.
        gait_name: gait file or name (None: the robot's).
        velocity: constant velocity input ``"VX,VY,WZ"`` (used without ``commands``).
        duration: seconds after start-up (None: the timeline's length + 1 s, or ``default_s``).
        commands: a command timeline file (CSV or TOML plan script).
        default_s: the run length without ``duration`` and ``commands`` [s].
        walking: False: a constant zero velocity (the stance scenarios).
        robot_change: a callable ``Robot → Robot`` applied after loading (``simulate``'s feedback switches).
        check_fit: check the legs and gaits the timeline names against the robot.
        path: a path file (``--path``): the follower walks it (instead of ``velocity`` or ``commands``); the run
            lasts ``duration``, else until the robot stopped at the last waypoint (at most
            :data:`PATH_TIME_PER_WAYPOINT_S` per waypoint).
    """
    from shc_cli.validation import load_checked

    robot, gait, loaded = load_checked(robot_name, gait_name)
    if callable(robot_change):
        robot = robot_change(robot)
    check_duration(duration)
    waypoints = None
    if path is not None:
        if commands:
            raise SpecError([Issue(None, None, "--path", "--path and --commands both give the run's input",
                                   "give one of them")])
        waypoints = load_path(path)
        default_s = PATH_TIME_PER_WAYPOINT_S * len(waypoints.waypoints)
    if commands:
        timeline = load_timeline(commands, robot.time_delta)
    else:
        if not walking or waypoints is not None:
            timeline = constant((0.0, 0.0, 0.0))
        else:
            values = parse_velocity(velocity) if isinstance(velocity, str) else velocity
            check_throttle(robot, values)
            timeline = constant(values)
    if check_fit:
        check_timeline(robot, timeline, commands)
    cycles = walk_cycles(timeline, duration, robot.time_delta, commands is not None, default_s=default_s)
    gait_file, _ = loaded.where(("walker", "gait"))
    return RunInputs(robot, gait, timeline, cycles, pose_sets_for(robot, gait, timeline, gait_file.parent), waypoints)
