"""``summary.json``: the typed summary every run directory ends with (``plan``, ``simulate``, ``run-hw``).

:class:`RunSummary` is written by :meth:`shc_cli.record.runlog.RunDirectory.finish` and read by
:func:`shc_cli.record.runread.read_run` (and the bag reader); every tool that reads a run (``analyze``, ``view``,
``render``, ``export bag``, sweeps, studies, the Python API) reads its fields, never string keys. One model holds
every kind of run: a field a kind of run does not have is absent from its file (``None`` here). Keys keep the
names they always had; ``shc schema summary`` prints the JSON Schema (docs/reference generates from it).

What each kind writes:

* ``plan``: the step cycle, the ideal body path's speeds, the stance feet's speed against paper eq. 16, odometry,
  IK counts, the walkspace.
* ``simulate``: the step cycle, the physics timings, the body's speeds, power, mass and cost of transport over the
  RUNNING window, fall detection, terrain, seed, engine and versions.
* ``run-hw`` (``scenario = "hardware"``): bus, cycle-time statistics, overruns, the fault, the final state, the
  input, what a real robot does not measure.
* ``plan``, ``simulate``, ``run-hw`` with ``--path``: the path file's copy, the follower's tolerance and each
  waypoint's result (:class:`WaypointSummary`).
* every run: ``complete`` and ``stop_reason`` (an interrupted run is marked only by them), and how often the
  controller had to limit a joint's speed (``joint_speed_limited_cycles``, ``joint_speed_limited_share``).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, NonNegativeFloat, NonNegativeInt

SUMMARY_FILE = "summary.json"
"""The summary's file name in a run directory."""


class WaypointSummary(BaseModel):
    """One waypoint of a path run as the follower saw it (its odometry; ``shc analyze`` adds the ground truth)."""

    model_config = ConfigDict(extra="forbid")

    x: float = Field(description="Waypoint x in the odometry frame [m].")
    y: float = Field(description="Waypoint y in the odometry frame [m].")
    yaw: float | None = Field(None, description="Heading asked for there [rad]; null: any.")
    reached: bool = Field(description="The odometry came within the tolerances before the follower moved on.")
    closest_m: NonNegativeFloat | None = Field(None, description="Closest odometry distance to it [m]; null: never "
                                                                 "the target.")
    reached_s: NonNegativeFloat | None = Field(None, description="Time it was reached, from the path's start [s].")
    left_s: NonNegativeFloat | None = Field(None, description="Time the follower moved on from it (or stopped at "
                                                              "it), from the path's start [s].")
    position_error_m: NonNegativeFloat | None = Field(None, description="Odometry distance from it when the "
                                                                        "follower moved on [m].")
    heading_error_rad: float | None = Field(None, description="Odometry heading error when the follower moved on "
                                                              "[rad]; null: no heading asked.")


class RunSummary(BaseModel):
    """The summary of one run (``summary.json``); every field is optional except where noted, absent when the kind
    of run does not have it."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True,
                              json_schema_extra={"title": "summary.json"})

    # what ran
    robot: str | None = Field(None, description="Robot name (all runs).")
    gait: str | None = Field(None, description="Gait name at the start (all runs).")
    gaits: list[str] | None = Field(None, description="plan: every gait the run walked, in order (a plan script may "
                                                      "switch).")
    scenario: str | None = Field(None, description="simulate: WG (walk on the ground), SG (stand on the ground), "
                                                   "WA (walk in the air), SA (stand in the air); run-hw: hardware.")
    cycles: NonNegativeInt | None = Field(None, description="Logged control cycles (plan, run-hw) [cycles].")
    duration_s: NonNegativeFloat | None = Field(None, description="plan: cycles × control period [s].")
    time_delta_s: NonNegativeFloat | None = Field(None, description="plan: the control period [s].")
    startup_cycles: NonNegativeInt | None = Field(None, description="plan: cycles before RUNNING [cycles].")
    sim_time_s: NonNegativeFloat | None = Field(None, description="simulate, run-hw: logged cycles × control period "
                                                                  "(start-up included) [s].")
    analysed_time_s: NonNegativeFloat | None = Field(None, description="simulate: duration of the RUNNING window the "
                                                                       "speeds, power and CoT are taken over [s].")
    wall_time_s: NonNegativeFloat | None = Field(None, description="plan, simulate: wall-clock time of the run, "
                                                                   "start-up and summary included [s].")
    running_wall_time_s: NonNegativeFloat | None = Field(None, description="simulate: wall-clock time since the "
                                                                           "first RUNNING cycle [s].")
    running_physics_time_s: NonNegativeFloat | None = Field(None, description="simulate: wall-clock time spent in "
                                                                              "the physics engine since the first "
                                                                              "RUNNING cycle [s].")
    physics_time_s: NonNegativeFloat | None = Field(None, description="simulate: wall-clock time spent in the "
                                                                      "physics engine [s].")
    physics_rate_hz: NonNegativeFloat | None = Field(None, description="simulate: physics steps per simulated "
                                                                       "second [Hz].")

    # the step cycle
    step_frequency_hz: NonNegativeFloat | None = Field(None, description="Step frequency of the gait in use at the "
                                                                         "end [Hz].")
    step_period_cycles: NonNegativeInt | None = Field(None, description="Control cycles of one gait cycle "
                                                                        "[cycles].")
    cycle_frequency_hz: NonNegativeFloat | None = Field(None, description="plan, simulate: gait cycles per second "
                                                                          "[Hz].")
    duty_factor: NonNegativeFloat | None = Field(None, description="Share of the gait cycle a foot is in stance "
                                                                   "(from the gait) [ratio].")
    moving_cycles: NonNegativeInt | None = Field(None, description="plan: cycles the walker was MOVING [cycles].")

    # speeds and progress over the RUNNING window
    distance_m: NonNegativeFloat | None = Field(None, description="simulate: straight-line horizontal distance "
                                                                  "of the body from the start to the end of the "
                                                                  "window [m].")
    forward_distance_m: float | None = Field(None, description="simulate: the same along the world x axis [m].")
    mean_speed_mps: NonNegativeFloat | None = Field(None, description="simulate: displacement_speed_mps under its "
                                                                      "first name [m/s].")
    displacement_speed_mps: NonNegativeFloat | None = Field(None, description="plan, simulate: straight-line "
                                                                              "start-to-end distance of the body "
                                                                              "÷ the window's duration [m/s].")
    path_speed_mps: NonNegativeFloat | None = Field(None, description="plan, simulate: length of the body's path ÷ "
                                                                      "the window's duration (plan: the ideal "
                                                                      "path) [m/s].")
    commanded_speed_mps: NonNegativeFloat | None = Field(None, description="plan, simulate: mean horizontal "
                                                                           "desired velocity after the limits "
                                                                           "[m/s].")
    commanded_distance_m: NonNegativeFloat | None = Field(None, description="plan, simulate: commanded speed × the "
                                                                            "window's duration [m].")
    walked_share: NonNegativeFloat | None = Field(None, description="plan, simulate: body path (sampled once per "
                                                                    "gait cycle) ÷ commanded distance [ratio]; "
                                                                    "null when nothing was commanded.")
    no_progress: bool | None = Field(None, description="plan, simulate: walking was commanded and the body "
                                                       "travelled less than a quarter of it.")
    achieved_mean_speed_mps: NonNegativeFloat | None = Field(None, description="plan: mean speed of the stance "
                                                                               "feet while MOVING [m/s].")
    eq16_speed_mps: NonNegativeFloat | None = Field(None, description="plan: paper eq. 16 prediction l_s·f/β of "
                                                                      "the inputs while MOVING [m/s].")
    odometry_distance_m: NonNegativeFloat | None = Field(None, description="plan: distance of the walker's ideal "
                                                                           "odometry from the start [m].")
    odometry_yaw_rad: float | None = Field(None, description="plan: yaw of the walker's ideal odometry [rad].")
    odometry_pose: list[float] | None = Field(None, description="plan, simulate, run-hw: the leg odometry's final "
                                                                "pose (x [m], y [m], yaw [rad]) in the odom frame "
                                                                "(the start pose).")
    true_pose: list[float] | None = Field(None, description="plan, simulate: the final ground-truth pose (x [m], "
                                                            "y [m], yaw [rad]) in the same odom frame (simulate: "
                                                            "the engine's body pose relative to the first cycle's; "
                                                            "plan: the ideal body path).")
    ik_deviation_count: NonNegativeInt | None = Field(None, description="plan: leg-cycles whose IK tip missed "
                                                                        "its target by more than 5 mm.")
    ik_clamp_count: NonNegativeInt | None = Field(None, description="plan: leg-cycles with a joint clamped to its "
                                                                    "limit.")
    joint_speed_limited_cycles: NonNegativeInt | None = Field(None, description="plan, simulate, run-hw, ros: "
                                                                                "control cycles (start-up included) "
                                                                                "in which the controller limited a "
                                                                                "joint's commanded speed to its "
                                                                                "max_vel (the IK's velocity clamp or "
                                                                                "shc's per-cycle guard) [cycles].")
    joint_speed_limited_share: NonNegativeFloat | None = Field(None, description="plan, simulate, run-hw, ros: "
                                                                                 "joint_speed_limited_cycles ÷ the "
                                                                                 "control cycles [ratio].")
    speed_limits_verified: dict[str, float] | None = Field(None, description="plan, simulate, run-hw, ros: for a robot "
                                                                           "that verifies its speed limits "
                                                                           "(walker.verify_speed_limits), the share "
                                                                           "of OpenSHC's limit it kept per bearing "
                                                                           "[degrees → ratio] and for turning "
                                                                           "(\"turn\"), where below 1.")
    walkspace: dict[str, float] | None = Field(None, description="plan: the walkspace radius per bearing "
                                                                 "[degrees → m].")

    # power and cost of transport
    mean_power_w: float | None = Field(None, description="simulate: mean total servo power over the "
                                                                    "window [W].")
    mass_kg: NonNegativeFloat | None = Field(None, description="simulate: mass of the simulated body (body, links, "
                                                               "feet) [kg].")
    servo_model: str | None = Field(None, description="simulate: the robot's servo model (servo.model; 'generic' "
                                                      "when its file gives no [servo]: power is then indicative).")
    cot: float | None = Field(None, description="simulate: cost of transport, paper eq. 22: mean power "
                                                "÷ (mass · g · v), v the distance walked (the body's path sampled "
                                                "once per gait cycle: a curve or a closed path counts) ÷ the window "
                                                "[dimensionless]; null when not walking on the ground (scenario "
                                                "other than WG) or the body hardly moved.")
    cot_displacement: float | None = Field(None, description="simulate: the same with v the displacement speed "
                                                             "(straight-line start to end: a path back to its "
                                                             "start has none) [dimensionless].")
    walked_m: NonNegativeFloat | None = Field(None, description="simulate: distance walked over the window, the "
                                                                "body's path sampled once per gait cycle [m].")
    max_tilt_rad: NonNegativeFloat | None = Field(None, description="simulate: largest body tilt while RUNNING "
                                                                    "[rad].")
    fell: bool | None = Field(None, description="simulate: the robot fell (tilt or height check); the run stopped "
                                                "there.")
    fall: str | None = Field(None, description="simulate, when it fell: how (flipped, thrown up or collapsed), "
                                               "when (during start-up or walking) and the tilt and height.")

    # the simulated world
    seed: int | None = Field(None, description="simulate: seed of every random thing.")
    terrain: str | None = Field(None, description="simulate: the terrain, as --terrain gives it.")
    perception: str | None = Field(None, description="simulate: 'rays' when a simulated depth sensor's height map "
                                   "shaped the steps (absent: blind, --perception off).")
    engine: str | None = Field(None, description="simulate: the physics engine (pybullet or mujoco).")
    engine_version: str | None = Field(None, description="simulate: the physics engine's version.")
    engine_warnings: list[str] | None = Field(None, description="simulate: the engine's warnings (e.g. an unstable "
                                                                "physics rate).")
    versions: dict[str, str] | None = Field(None, description="simulate: versions of shc, the engine and numpy.")

    # a run on hardware
    port: str | None = Field(None, description="run-hw: the serial port(s), comma-separated.")
    baud: NonNegativeInt | None = Field(None, description="run-hw: the bus baud rate [bit/s].")
    dry_run: bool | None = Field(None, description="run-hw: no goal, torque or current-limit write was made.")
    cycle_time_mean_ms: NonNegativeFloat | None = Field(None, description="run-hw, ros: mean cycle time [ms].")
    cycle_time_p50_ms: NonNegativeFloat | None = Field(None, description="ros: median cycle period [ms].")
    cycle_time_p99_ms: NonNegativeFloat | None = Field(None, description="run-hw, ros: 99th percentile cycle time "
                                                                         "[ms].")
    cycle_time_max_ms: NonNegativeFloat | None = Field(None, description="run-hw, ros: longest cycle [ms].")
    rate_hz: NonNegativeFloat | None = Field(None, description="ros: mean control rate held against the wall clock, "
                                                               "waits while SUSPENDED left out [Hz].")
    pauses: NonNegativeInt | None = Field(None, description="ros: waits (SUSPENDED system) left out of the cycle "
                                                            "times.")
    realtime_ratio: NonNegativeFloat | None = Field(None, description="--realtime, ros: simulated time ÷ wall time "
                                                                      "from the first cycle's start to the last's end "
                                                                      "(1: the run kept the clock).")
    realtime_lag_max_ms: NonNegativeFloat | None = Field(None, description="--realtime, ros: the furthest a cycle "
                                                                           "fell behind its due time [ms].")
    overruns: NonNegativeInt | None = Field(None, description="run-hw, ros: cycles longer than the control period.")
    node: str | None = Field(None, description="ros: the node's name.")
    ros_master: str | None = Field(None, description="ros: the ROS master's URI.")
    backend: str | None = Field(None, description="ros: none (outputs only) or the physics engine.")
    wire_time_ms: NonNegativeFloat | None = Field(None, description="run-hw: bus time one cycle needs (packets and "
                                                                    "return delays) [ms].")
    read_retries: NonNegativeInt | None = Field(None, description="run-hw, ros on a bus: state reads asked again at "
                                                                  "once, in the same cycle, after a missing or bad "
                                                                  "reply.")
    bridged_cycles: NonNegativeInt | None = Field(None, description="run-hw, ros on a bus: cycles in which a servo's "
                                                                    "state read failed even after the retry, its "
                                                                    "last reading standing in.")
    bridged_reads: NonNegativeInt | None = Field(None, description="run-hw, ros on a bus: servo readings stood in "
                                                                   "for (bridged_cycles counted per servo).")
    missed_cycles_max: NonNegativeInt | None = Field(None, description="run-hw, ros on a bus: the most consecutive "
                                                                       "cycles a servo went without a reading.")
    missed_reads_fault: NonNegativeInt | None = Field(None, description="run-hw, ros on a bus: consecutive cycles "
                                                                        "without a servo's reading that are a fault "
                                                                        "(hardware.missed_reads_fault).")
    failed_legs: list[str] | None = Field(None, description="run-hw --on-fault adapt: the legs failed by a servo "
                                                            "fault and walked on without (empty: none).")
    fault: str | None = Field(None, description="run-hw: the fault that ended the run (names the servo); null "
                                                "when none.")
    stopped_by_request: bool | None = Field(None, description="run-hw: the run ended by a stop request or the "
                                                              "input's end, not a fault.")
    final_state: str | None = Field(None, description="run-hw: the controller's robot state at the end.")
    stop_state: str | None = Field(None, description="run-hw: the state a stop shuts down to (--stop-state).")
    input: str | None = Field(None, description="run-hw, simulate: the input source (timeline, stdin, keyboard, "
                                                "gamepad).")
    watchdog_trips: NonNegativeInt | None = Field(None, description="run-hw: times the stdin watchdog stopped the "
                                                                    "robot.")
    unmeasured: list[str] | None = Field(None, description="run-hw: log.csv columns a real robot does not measure "
                                                           "(written as 0).")

    # a path run (--path)
    path_file: str | None = Field(None, description="plan, simulate, run-hw with --path: the path file's copy in "
                                                    "the run directory (its name).")
    path_tolerance_m: NonNegativeFloat | None = Field(None, description="--path: distance within which a waypoint "
                                                                        "counts as reached [m].")
    path_heading_tolerance_rad: NonNegativeFloat | None = Field(None, description="--path: heading error within "
                                                                                  "which a waypoint's heading "
                                                                                  "counts as reached [rad].")
    path_start_cycle: NonNegativeInt | None = Field(None, description="--path: the logged cycle the follower "
                                                                      "started at (the path's times count from "
                                                                      "it).")
    waypoints: list[WaypointSummary] | None = Field(None, description="--path: each waypoint's result, in order.")

    # how it ended (every run)
    complete: bool = Field(True, description="The run played its input to its end (every run; runs written "
                                             "before it existed count as complete).")
    stop_reason: str = Field("end", description="Why it ended: end, SIGINT, SIGTERM, fault or fell (every run).")
    summary_skipped: bool | None = Field(None, description="A second signal stopped the summary: only cycles, "
                                                           "complete and stop_reason are written.")
    plots_skipped: bool | None = Field(None, description="A second signal stopped the plots.")

    def updated(self, **fields: object) -> RunSummary:
        """This summary with ``fields`` set (validated; the fields set so far keep their values)."""
        return RunSummary.model_validate({**self.model_dump(exclude_unset=True), **fields})

    def to_json(self) -> str:
        """The ``summary.json`` text: the fields that were set (a ``null`` one included), two-space indented."""
        import json

        return json.dumps(self.model_dump(mode="json", exclude_unset=True), indent=2) + "\n"


def summary_schema() -> dict[str, Any]:
    """The JSON Schema of ``summary.json`` (``shc schema summary``)."""
    return RunSummary.model_json_schema()


def parse_summary(data: object) -> RunSummary:
    """A summary read from JSON: keys this version does not know are left out (runs from other versions stay
    readable); raises :class:`pydantic.ValidationError` on a wrong type."""
    if not isinstance(data, dict):
        raise TypeError(f"a JSON {type(data).__name__}, not an object")
    known = RunSummary.model_fields
    return RunSummary.model_validate({key: value for key, value in data.items() if key in known})


def write_summary(directory: Path, summary: RunSummary) -> None:
    """Write ``directory/summary.json``."""
    (directory / SUMMARY_FILE).write_text(summary.to_json(), encoding="utf-8")
