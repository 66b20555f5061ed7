"""One run on real Dynamixel servos (``shc run-hw``), at the robot's control period.

Start: open every bus, ping every servo, check models, hardware errors, operating modes and position limits (refuse
to start with every problem listed), write the robot file's return delay and current limit, read the present
positions — the controller starts from them and runs the robot file's start-up (direct, or unpack + start-up
sequence). Each cycle:
one sync read per bus (positions, velocities, currents), the controller step, goal positions clamped to the joint
limits and to the joints' speed limits, one sync write per bus (optionally with profile velocity). The loop keeps
its period with a drift-free deadline (``next += period``) and counts overruns. The input (timeline, stdin,
keyboard, gamepad) drives velocity, posing, gait and the robot state once the start-up is done. Ctrl-C, SIGTERM or
the end of the input: the robot stops walking and shuts down to ``stop_state`` (sequence mode: shut-down sequence
and pack; direct mode: back to the joints it started from), then the torque goes off (or is held, ``on_stop``).
A servo fault (hardware error status; or no proper reply to its state read in ``hardware.missed_reads_fault``
consecutive cycles, default 3 — a single missed cycle is bridged with the servo's last reading and counted,
:class:`~shc_cli.backends.dynamixel.MissedReads`) stops commanding motion at once — no further goal is written —
and holds or turns the torque off (``on_fault``), naming the servo. ``dry_run`` does everything
except the current-limit, torque-enable and goal writes.

The run directory has the ``simulate`` log format (quantities a real robot does not measure — body pose, IMU,
foot forces — are 0 and listed in the summary's ``unmeasured``) plus ``cycle_time_ms`` in ``timing.csv``; the
summary adds cycle-time statistics, overruns and faults. The loop is the one run loop
(:mod:`shc_cli.loop.run_loop`) on the Dynamixel backend (:mod:`shc_cli.backends.dynamixel`). Never prints: the
bus set-up (NOTICE), warnings and faults are events (:mod:`shc_cli.events`).
"""

from __future__ import annotations

import logging
import time
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from pydantic import BaseModel, ConfigDict, ValidationInfo, field_validator

from shc_cli.domain.result import RunResult
from shc_cli.errors import Issue, SpecError, check_choice
from shc_cli.events import NOTICE, event
from shc_cli.loop.input_choice import check_input
from shc_cli.loop.input_sources import STATES

if TYPE_CHECKING:
    from collections.abc import Callable

    from shc_cli.backends.dynamixel import DynamixelBackend
    from shc_cli.control.controller import Controller
    from shc_cli.hardware.bus import BusState, ServoBus
    from shc_cli.loop.assembly import Assembly, Finished, RunSpec
    from shc_cli.loop.run_inputs import RunInputs
    from shc_cli.loop.run_loop import LoopResult
    from shc_cli.record.summary import RunSummary
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

STOP_TIMEOUT_S = 10.0
"""Longest controlled stop and shut-down after Ctrl-C, beyond the sequences' own time, before the torque goes off
anyway [s]."""
OnFault = Literal["hold", "torque-off"]
OnServoFault = Literal["hold", "torque-off", "adapt"]


class HardwareConfig(BaseModel):
    """Every option of ``shc run-hw`` (the same names, the same defaults), checked on construction.

    Attributes:
        robot: robot file or bundled name (its ``[hardware]`` servo table).
        ports: serial device of each servo bus, bus 0 first.
        baud: baud rate (None: ``hardware.baud``) [bit/s].
        gait: gait file or name (None: the robot's).
        input_mode: ``timeline``, ``commands:FILE``, ``stdin``, ``keyboard`` or ``gamepad[:DEVICE]``.
        velocity: constant velocity input ``"VX,VY,WZ"`` of the timeline.
        duration: seconds to run after start-up (None: a timeline's length + 1 s, or 20 s) [s].
        commands: command timeline (CSV or TOML plan script).
        path: a path file the follower walks by the odometry (``--input timeline`` only).
        out: run directory (None: ``runs/<timestamp>-run-hw``).
        dry_run: everything except current-limit, torque-enable and goal writes.
        stop_state: the state to shut down to: ``packed``, ``ready`` or ``running``.
        on_fault: on a servo fault, ``hold`` or ``torque-off``; ``adapt``: a fault of one leg's servos fails that leg
            and the others walk on (:mod:`shc_cli.loop.leg_fault`; any other fault: torque off).
        on_stop: after the controlled stop, ``hold`` or ``torque-off``.
        profile_velocity: also write Profile Velocity.
        watchdog: stdin: seconds without a line before the velocity goes to 0 [s].
        overwrite: replace an existing run directory at ``out`` when the run finishes.
        live: stream the run while it happens on a Foxglove WebSocket server on 127.0.0.1:``live_port`` (the
            controller's topics and the measured ``/joint_states``, :mod:`shc_cli.domain.live`).
        live_port: that server's port (0: any free port).
        missed_reads_fault: consecutive cycles without a servo's reading that are a fault (None: the robot file's
            ``hardware.missed_reads_fault``, default 3).
        policy: a ``gait`` or ``residual`` policy file acting on the controller while it walks
            (:mod:`shc_cli.loop.policy.drive`; the start-up, stop, clamps and fault checks unchanged).
        fail_leg: legs declared failed, ``LEG[:MODE][@T]`` comma-separated (:func:`shc_cli.domain.simulate.
            failed_legs`): the controller holds them and walks the gait re-planned for the legs left.
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    robot: str
    ports: list[str]
    baud: int | None = None
    gait: str | None = None
    on_fault: OnServoFault = "torque-off"
    on_stop: OnFault = "torque-off"
    stop_state: str = "packed"
    input_mode: str = "timeline"
    velocity: str = "0,0,0"
    duration: float | None = None
    commands: Path | None = None
    path: Path | None = None
    out: Path | None = None
    dry_run: bool = False
    profile_velocity: bool = False
    watchdog: float = 0.5
    overwrite: bool = False
    live: bool = False
    live_port: int = 8765
    missed_reads_fault: int | None = None
    policy: Path | None = None
    fail_leg: str | None = None

    @field_validator("missed_reads_fault")
    @classmethod
    def _missed(cls, value: int | None) -> int | None:
        if value is not None and not 1 <= value <= 100:
            raise SpecError([Issue(None, None, "--missed-reads-fault", f"{value} is not a count of cycles",
                                   "give 1 to 100 (1: the first missed cycle is a fault)")])
        return value

    @field_validator("on_fault", "on_stop", mode="before")
    @classmethod
    def _hold_or_off(cls, value: object, info: ValidationInfo) -> object:
        if info.field_name == "on_fault":
            check_choice("--on-fault", value, ("hold", "torque-off", "adapt"), "hold, torque-off or adapt")
        else:
            check_choice("--" + str(info.field_name).replace("_", "-"), value, ("hold", "torque-off"),
                         "hold or torque-off")
        return value

    @field_validator("stop_state")
    @classmethod
    def _stop_state(cls, value: str) -> str:
        check_choice("--stop-state", value, STATES, "a robot state")
        return value

    @field_validator("input_mode")
    @classmethod
    def _input(cls, value: str) -> str:
        return check_input(value)


def prepare_bus(bus: ServoBus, robot: Robot, dry_run: bool) -> None:
    """Open ``bus`` and make it safe to drive, or refuse (:class:`~shc_cli.hardware.bus.HardwareError`, one line
    naming every problem): every servo answers with its model, no hardware error, position mode and limits that
    cover the joints' (:meth:`ServoBus.check`); the return delay and current limit written (not in ``dry_run``); the
    measured read rate keeps the control period (only a warning in ``dry_run``). The caller closes the bus."""
    from shc_cli.hardware.bus import HardwareError

    bus.open()
    problems = bus.check()
    if problems:
        raise HardwareError(f"{bus.port_name}: refusing to start: " + "; ".join(problems))
    if not dry_run:
        for done in bus.configure():
            event(log, NOTICE, "bus_setup", "%s", done)
    slow = bus.rate_problem(robot.time_delta)  # measured: the adapter's latency and per-servo reads count
    if slow and not dry_run:
        raise HardwareError(f"{bus.port_name}: refusing to start: {slow}")
    if slow:
        event(log, logging.WARNING, "bus_rate", "warning: %s", slow)
    bus_time = bus.wire_time()
    if bus_time > robot.time_delta:
        event(log, logging.WARNING, "bus_time", "warning: one cycle needs %.1f ms on the bus (packets and return "
              "delays at %s baud), more than the %.0f ms period: raise the baud rate, lower Return Delay Time "
              "(hardware.return_delay_us) or split the servos over more buses", bus_time * 1e3, bus.baud,
              robot.time_delta * 1e3)


def bus_run_fields(robot: Robot, controller: Controller, backend: DynamixelBackend, result: LoopResult,
                   dry_run: bool, stop_state: str) -> dict[str, object]:
    """The summary fields every run on a servo bus gives (run-hw, ``shc ros --backend bus``): what ran, on which
    bus, how it ended, the reads it repeated and bridged (a warning when it bridged any)."""
    from shc_cli.backends.dynamixel import UNMEASURED

    bus, misses = backend.bus, backend.misses
    if misses.bridged_cycles and misses.fault is None:
        event(log, logging.WARNING, "reads_bridged", "warning: %d of %d cycles missed a servo's reading (the last "
              "one stood in; at most %d in a row, %d would be a fault); %d reads repeated", misses.bridged_cycles,
              result.cycles, misses.longest, misses.limit, bus.retries)
    return {
        "robot": robot.name, "gait": controller.gait.name, "scenario": "hardware", "port": bus.port_name,
        "baud": bus.baud, "dry_run": dry_run, "cycles": result.cycles, "sim_time_s": result.cycles * robot.time_delta,
        "wire_time_ms": bus.wire_time() * 1e3, **backend.bus_statistics(), "fault": result.fault,
        "stopped_by_request": result.stop_reason != "fault", "final_state": controller.state.name,
        "stop_state": stop_state, "step_frequency_hz": controller.parameters["step_frequency"],
        "step_period_cycles": controller.cycle.period, "duty_factor": controller.cycle.duty_factor,
        "unmeasured": UNMEASURED,
    }


def run_hardware(config: HardwareConfig, clock: Callable[[], float] | None = None,
                 sleep: Callable[[float], None] | None = None) -> RunResult:
    """Start up, run the input on the servos, stop and shut down safely; returns the run directory and its summary
    (``summary["fault"]`` names a servo fault). ``clock`` [s] and ``sleep`` replace the wall clock of the cycle's
    pacing (tests: an emulated bus on a virtual clock, :class:`~shc_cli.backends.dynamixel.DynamixelBackend`)."""
    from shc_cli.loop.assembly import assemble
    from shc_cli.loop.input_choice import commands_file
    from shc_cli.loop.run_inputs import load_inputs

    c = config
    if c.path is not None and c.input_mode != "timeline":
        raise SpecError([Issue(None, None, "--path", f"--path and --input {c.input_mode} both give the run's input",
                               "drop --input (a path is followed by itself)")])
    if c.fail_leg and c.on_fault == "adapt":
        raise SpecError([Issue(None, None, "--on-fault", "adapt plans for one failed leg of a robot with every leg "
                               "walking, and --fail-leg fails legs already", "drop one of --on-fault adapt and "
                               "--fail-leg")])
    inputs = load_inputs(c.robot, c.gait, c.velocity, c.duration, commands_file(c.input_mode, c.commands),
                         default_s=20.0, path=c.path)
    return RunResult(*assemble(lambda parts: _on_servos(parts, c, inputs, clock, sleep)).pair)


def _on_servos(parts: Assembly, c: HardwareConfig, inputs: RunInputs, clock: Callable[[], float] | None,
               sleep: Callable[[float], None] | None) -> RunSpec[BusState]:
    """run-hw's run specification: the checked bus, the input, the backend on the bus, the controller from the
    measured joints, a controlled stop, the release of the torque as soon as the loop ends (and whatever happens)."""
    from shc_cli.backends.dynamixel import DynamixelBackend
    from shc_cli.control.controller import Controller
    from shc_cli.domain.live import live_observer
    from shc_cli.domain.simulate import failed_legs, speed_source
    from shc_cli.hardware.buses import servo_bus
    from shc_cli.loop.assembly import RunSpec
    from shc_cli.loop.input_choice import open_input
    from shc_cli.loop.path_input import keep_path
    from shc_cli.loop.policy.drive import PolicyDrive
    from shc_cli.loop.run_loop import ControlledStop, StartUp
    from shc_cli.record.runlog import LogRecorder, RunDirectory, default_run_directory

    robot, gait, failure = failed_legs(inputs.robot, inputs.gait, c.fail_leg, c.velocity)
    drive = None if c.policy is None else PolicyDrive.load(c.policy, robot, hardware=True)
    bus = parts.closing(servo_bus(robot, c.ports, c.baud, c.profile_velocity))  # the servo models' protocol
    source = parts.closing(open_input(c.input_mode, robot, gait, inputs.commands(), c.watchdog))
    prepare_bus(bus, robot, c.dry_run)
    run = parts.enter(RunDirectory(c.out or default_run_directory("run-hw"), c.overwrite))
    backend = DynamixelBackend(robot, bus, c.dry_run, run, c.on_fault, c.on_stop, clock=clock or time.perf_counter,
                               sleep=sleep or time.sleep, missed_reads_fault=c.missed_reads_fault)
    release = Release(backend)
    parts.callback(release.close)  # torque off (or held) also when the run raised
    controller = Controller(robot, gait, joints=backend.start(), pose_sets=inputs.pose_sets,
                            direct_shutdown=True, failure=failure, speed_shares=speed_source(robot, failure))
    run.write_robot(robot)
    if inputs.path is not None:
        source.close()
        source = inputs.source(controller)
    path_fields = keep_path(source, run.partial)
    if drive is not None:
        source = drive.source(source)
    absorb = None
    if c.on_fault == "adapt":
        from shc_cli.loop.leg_fault import LegFaultAdapter

        absorb = LegFaultAdapter(robot, controller, backend)
    stop = STATES[c.stop_state]
    dt = robot.time_delta

    def summarise(finished: Finished) -> RunSummary:
        from shc_cli.record.summary_kinds import summary_of

        result = finished.result
        if len(backend.cycle_times) > 20 and sum(t > dt for t in backend.cycle_times) / len(backend.cycle_times) \
                > 0.05:
            event(log, logging.WARNING, "overruns", "warning: the loop missed its %.0f ms period in %d of %d "
                  "cycles", dt * 1e3, backend.overruns, result.cycles)
        return summary_of(("hardware",), {
            **bus_run_fields(robot, controller, backend, result, c.dry_run, stop.name), **backend.statistics(),
            "input": "path" if c.path is not None else c.input_mode,
            "watchdog_trips": getattr(source, "watchdog_trips", 0),
            "odometry_pose": list(controller.odometry.pose), **finished.shared,
            "failed_legs": list(backend.failed_legs) if c.on_fault == "adapt" else None,
        })

    return RunSpec(controller, backend, source, LogRecorder(run, robot, backend), StartUp.of(robot, hardware=True),
                   run, summarise, ControlledStop(stop, STOP_TIMEOUT_S),
                   live=live_observer(parts, c.live, c.live_port, robot, controller, sensors=False, joint_states=True),
                   path_fields=path_fields, after_loop=release, flush_every=100,
                   on_fault=fault_action(c.on_fault), absorb=absorb, on_loop=None if drive is None else drive.join)


def fault_action(on_fault: str) -> Callable[[str], None]:
    """Told a servo fault's text: the event naming it and what is done (holding, or the torque off)."""
    action = "holding" if on_fault == "hold" else "torque off"
    return lambda text: event(log, logging.ERROR, "fault_action", "fault: %s — %s", text, action)


class Release:
    """Releases the servos (torque off or held, :meth:`DynamixelBackend.close`) right after the loop ends — held on
    a fault — and again when the run is over, whatever happened (closing twice is harmless)."""

    def __init__(self, backend: DynamixelBackend) -> None:
        self.backend, self.faulted = backend, False

    def __call__(self, result: LoopResult) -> None:
        self.faulted = result.fault is not None
        self.backend.close(self.faulted)

    def close(self) -> None:
        self.backend.close(self.faulted)
