"""The summary of each kind of run on a shared base: which ``summary.json`` fields a kind writes, checked when its
summary is made.

``summary.json`` has one format (:class:`~shc_cli.record.summary.RunSummary`, the one model every reader reads, its
keys in one order); each kind of run writes a part of it. :data:`SHARED` are the fields every run has (the run
assembler makes them, :class:`~shc_cli.loop.assembly.Finished`); :data:`KINDS` adds each kind's own. A kind's
summariser makes its summary once from the finished record with :func:`summary_of`, which validates the fields
against the kind's model (:func:`kind_model`: a field the kind does not write is an error, not a silent key) and
returns the :class:`RunSummary` that is written. ``shc ros`` on a backend is that backend's kind plus
:data:`ROS`. A replay writes no run directory (its comparison is its output).
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import Literal, cast

from pydantic import BaseModel, ConfigDict

from shc_cli.record.summary import RunSummary

Kind = Literal["plan", "simulate", "hardware", "ros"]
"""A kind of run: ``plan``, ``simulate``, ``run-hw`` (hardware) and what ``shc ros`` adds to its backend's."""

PACING = ("cycle_time_p50_ms", "cycle_time_p99_ms", "cycle_time_max_ms", "cycle_time_mean_ms", "rate_hz", "overruns",
          "pauses", "realtime_ratio", "realtime_lag_max_ms")
"""The wall-clock pacer's statistics (``--realtime``, ``shc ros``; :meth:`shc_cli.loop.pacing.WallClock.statistics`)."""
PATH = ("path_file", "path_tolerance_m", "path_heading_tolerance_rad", "path_start_cycle", "waypoints")
"""A path run's fields (``--path``)."""
SHARED = ("robot", "gait", "step_frequency_hz", "step_period_cycles", "duty_factor", "odometry_pose",
          "joint_speed_limited_cycles", "joint_speed_limited_share", "speed_limits_verified", *PACING, *PATH,
          "complete", "stop_reason", "summary_skipped", "plots_skipped")
"""Every run's fields: what ran, its step cycle and final odometry, the controller's joint-speed limiting, the
pacer's statistics and a path's result (when it has them), how it ended."""
PLAN = ("gaits", "cycles", "duration_s", "time_delta_s", "startup_cycles", "wall_time_s", "cycle_frequency_hz",
        "moving_cycles", "achieved_mean_speed_mps", "path_speed_mps", "displacement_speed_mps", "commanded_speed_mps",
        "commanded_distance_m", "walked_share", "no_progress", "eq16_speed_mps", "odometry_distance_m",
        "odometry_yaw_rad", "true_pose", "ik_deviation_count", "ik_clamp_count", "walkspace")
"""``plan`` (and ``shc ros --backend none``): the ideal body path, the stance feet against eq. 16, odometry, IK."""
SIMULATE = ("scenario", "sim_time_s", "analysed_time_s", "wall_time_s", "running_wall_time_s",
            "running_physics_time_s", "physics_time_s", "physics_rate_hz", "cycle_frequency_hz", "distance_m",
            "forward_distance_m", "mean_speed_mps", "displacement_speed_mps", "path_speed_mps", "commanded_speed_mps",
            "commanded_distance_m", "walked_share", "no_progress", "true_pose", "mean_power_w", "mass_kg",
            "servo_model", "cot", "cot_displacement", "walked_m", "max_tilt_rad", "fell", "fall", "fault", "seed",
            "terrain", "engine", "engine_version", "engine_warnings", "versions", "input", "perception")
"""``simulate`` (and ``shc ros`` on an engine): physics timings, speeds, power, cost of transport, the fall."""
HARDWARE = ("scenario", "cycles", "sim_time_s", "port", "baud", "dry_run", "wire_time_ms", "read_retries",
            "bridged_cycles", "bridged_reads", "missed_cycles_max", "missed_reads_fault", "fault", "stopped_by_request",
            "final_state", "stop_state", "unmeasured", "input", "watchdog_trips", "failed_legs")
"""``run-hw`` (and ``shc ros --backend bus``): the bus, its cycle times and reads, the fault, the final state."""
ROS = ("cycles", "node", "ros_master", "backend")
"""What ``shc ros`` adds to its backend's kind."""
KINDS: dict[Kind, tuple[str, ...]] = {"plan": PLAN, "simulate": SIMULATE, "hardware": HARDWARE, "ros": ROS}


@functools.cache
def kind_model(*kinds: Kind) -> type[BaseModel]:
    """The model of a summary of ``kinds`` (``("simulate", "ros")``: ``shc ros`` on an engine): :data:`SHARED` and
    the kinds' fields, each as :class:`RunSummary` declares it; any other field is refused."""
    names = {*SHARED, *(name for kind in kinds for name in KINDS[kind])}
    kept = {name: info for name, info in RunSummary.model_fields.items() if name in names}
    namespace: dict[str, object] = {"__annotations__": {name: info.annotation for name, info in kept.items()},
                                    "model_config": ConfigDict(extra="forbid"), "__module__": __name__, **kept}
    return cast("type[BaseModel]", type("".join(kind.title() for kind in kinds) + "Summary", (BaseModel,), namespace))


def summary_of(kinds: tuple[Kind, ...], fields: Mapping[str, object]) -> RunSummary:
    """The summary of a run of ``kinds``, made once from ``fields`` (validated against :func:`kind_model`; a
    field the kind does not write raises :class:`pydantic.ValidationError`)."""
    checked = kind_model(*kinds).model_validate(dict(fields))
    return RunSummary.model_validate(checked.model_dump(exclude_unset=True))
