"""``shc run-hw``: the one controller on real Dynamixel servos, at the robot's control period.

Start: open every bus, ping every servo, check models, hardware errors, operating modes and position limits (refuse
to start with every problem listed), write the robot file's return delay and current limit, read the present
positions — the controller starts from them and runs the robot file's start-up (direct, or unpack + start-up
sequence). Each cycle:
one sync read per bus (positions, velocities, currents), the controller step, goal positions clamped to the joint
limits and to the joints' speed limits, one sync write per bus (optionally with profile velocity). The loop keeps
its period with a drift-free deadline (``next += period``) and counts overruns. The input (timeline, stdin,
keyboard, gamepad) drives velocity, posing, gait and the robot state once the start-up is done. Ctrl-C, SIGTERM or
the end of the input: the robot stops walking and shuts down to ``--stop-state`` (sequence mode: shut-down sequence
and pack; direct mode: back to the joints it started from), then the torque goes off (or is held, ``--on-stop``).
A servo fault (no reply to the sync read, hardware error status) stops commanding motion at once — no further goal
is written — and holds or turns the torque off (``--on-fault``), naming the servo. ``--dry-run`` does everything
except the current-limit, torque-enable and goal writes.

The run directory has the ``simulate`` log format (quantities a real robot does not measure — body pose, IMU,
foot forces — are 0 and listed in the summary's ``unmeasured``) plus ``cycle_time_ms`` in ``timing.csv``; the
summary adds cycle-time statistics, overruns and faults. The loop is the one run loop
(:mod:`shc_cli.loop.run_loop`) on the Dynamixel backend (:mod:`shc_cli.backends.dynamixel`). A fault exits 3.
"""

from __future__ import annotations

from datetime import datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

import typer

from shc_cli.errors import Issue, SpecError
from shc_cli.loop.input_sources import STATES
from shc_cli.loop.run_inputs import parse_velocity, pose_sets_for, walk_cycles

if TYPE_CHECKING:
    from collections.abc import Sequence

    from shc_cli.backends.base import InputSource
    from shc_cli.control.controller import Command
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

__all__ = ["INPUTS", "STOP_TIMEOUT_S", "parse_velocity", "pose_sets_for", "run_hw", "walk_cycles"]

STOP_TIMEOUT_S = 10.0
"""Longest controlled stop and shut-down after Ctrl-C, beyond the sequences' own time, before the torque goes off
anyway [s]."""
INPUTS = "timeline, commands:FILE, stdin, keyboard, gamepad or gamepad:DEVICE"


def run_hw(robot_name: str, gait_name: str | None, ports: list[str], baud: int | None, velocity: str,
           duration: float | None, commands: Path | None, out: Path | None, dry_run: bool, on_fault: str,
           on_stop: str, input_mode: str = "timeline", watchdog: float = 0.5, stop_state: str = "packed",
           profile_velocity: bool = False, overwrite: bool = False) -> Path:
    """Start up, run the input on the servos, stop and shut down safely; returns the run directory (exit 3 after a
    servo fault; ``overwrite``: replace an existing one when the run finishes)."""
    from shc_cli.backends.dynamixel import UNMEASURED, DynamixelBackend
    from shc_cli.commands.outcome import EXIT_FAULT
    from shc_cli.control.controller import Controller
    from shc_cli.hardware.bus import HardwareError, ServoBus
    from shc_cli.loop.run_inputs import load_inputs
    from shc_cli.loop.run_loop import ControlledStop, RunLoop, StartUp
    from shc_cli.loop.runlog import LogRecorder, RunDirectory
    from shc_cli.loop.session import execute
    from shc_cli.loop.summary import RunSummary

    for option, value in (("--on-fault", on_fault), ("--on-stop", on_stop)):
        if value not in ("hold", "torque-off"):
            raise SpecError([Issue(None, None, option, f"'{value}' is not hold or torque-off",
                                   "use hold or torque-off")])
    if stop_state not in STATES:
        raise SpecError([Issue(None, None, "--stop-state", f"'{stop_state}' is not a robot state",
                               "use packed, ready or running")])
    kind, _, argument = input_mode.partition(":")
    takes = {"timeline": False, "commands": True, "stdin": False, "keyboard": False, "gamepad": None}
    if kind not in takes or takes[kind] not in (None, bool(argument)):
        raise SpecError([Issue(None, None, "--input", f"'{input_mode}' is not an input", f"use {INPUTS}")])
    if kind == "commands":
        commands = Path(argument)
    inputs = load_inputs(robot_name, gait_name, velocity, duration, commands, default_s=20.0)
    robot, gait = inputs.robot, inputs.gait
    bus = ServoBus(robot, ports, baud, profile_velocity)
    source: Any = None
    backend: DynamixelBackend | None = None
    faulted = False
    try:
        source = _source(kind, argument, robot, gait, inputs.timeline.commands(inputs.cycles), watchdog)
        bus.open()
        problems = bus.check()
        if problems:
            raise HardwareError(f"{bus.port_name}: refusing to start: " + "; ".join(problems))
        if not dry_run:
            for done in bus.configure():
                typer.echo(done, err=True)
        bus_time = bus.wire_time()
        if bus_time > robot.time_delta:
            typer.echo(f"warning: one cycle needs {bus_time * 1e3:.1f} ms on the bus (packets and return "
                       f"delays at {bus.baud} baud), more than the {robot.time_delta * 1e3:.0f} ms period: raise the "
                       "baud rate, lower Return Delay Time (hardware.return_delay_us) or split the servos over "
                       "more buses", err=True)
        directory = out or Path("runs") / f"{datetime.now():%Y%m%d-%H%M%S}-run-hw"
        run = RunDirectory(directory, overwrite)
        backend = DynamixelBackend(robot, bus, dry_run, run, on_fault, on_stop)
        controller = Controller(robot, gait, joints=backend.start(), pose_sets=inputs.pose_sets,
                                direct_shutdown=True)
        run.write_robot(robot)
        dt = robot.time_delta
        stop = STATES[stop_state]
        loop = RunLoop(controller, backend, source, LogRecorder(run, robot, backend),
                       StartUp(round((robot.start_up.time_to_start * 2.5 + 10.0) / dt), as_fault=True),
                       ControlledStop(stop, STOP_TIMEOUT_S), flush_every=100,
                       on_fault=lambda text: typer.echo(
                           f"fault: {text} — {'holding' if on_fault == 'hold' else 'torque off'}", err=True))

        def release(result: Any) -> None:
            nonlocal faulted
            faulted = result.fault is not None
            assert backend is not None
            backend.close(faulted)

        def summarise(result: Any) -> RunSummary:
            assert backend is not None
            cycles = result.cycles
            if len(backend.cycle_times) > 20 and sum(t > dt for t in backend.cycle_times) / len(backend.cycle_times) \
                    > 0.05:
                typer.echo(f"warning: the loop missed its {dt * 1e3:.0f} ms period in {backend.overruns} of {cycles} "
                           "cycles", err=True)
            return RunSummary.model_validate({
                "robot": robot.name, "gait": controller.gait.name, "scenario": "hardware", "port": bus.port_name,
                "baud": bus.baud, "dry_run": dry_run, "cycles": cycles, "sim_time_s": cycles * dt,
                **backend.statistics(), "wire_time_ms": bus.wire_time() * 1e3, "read_retries": bus.retries,
                "fault": result.fault, "stopped_by_request": bool(result.stop_reason != "fault"),
                "final_state": controller.state.name, "stop_state": stop.name,
                "step_frequency_hz": controller.parameters["step_frequency"],
                "step_period_cycles": controller.cycle.period, "duty_factor": controller.cycle.duty_factor,
                "input": input_mode, "watchdog_trips": getattr(source, "watchdog_trips", 0),
                "unmeasured": UNMEASURED,
            })

        path, summary, _ = execute(loop, run, summarise, after_loop=release)
    finally:
        if backend is not None:
            backend.close(faulted)  # torque off (or held) also when the loop raised
        if source is not None:
            source.close()
        bus.close()
    fault = f", FAULT: {summary.fault}" if summary.fault else ""
    typer.echo(f"{robot.name} on {bus.port_name}: {summary.cycles} cycles, cycle time mean "
               f"{summary.cycle_time_mean_ms:.2f} ms, p99 {summary.cycle_time_p99_ms:.2f} ms, "
               f"{summary.overruns} overruns, ended {summary.final_state}{fault} → {path}")
    if summary.fault:
        raise typer.Exit(EXIT_FAULT)
    return path


def _source(kind: str, argument: str, robot: Robot, gait: Gait, commands: Sequence[Command],
            watchdog: float) -> InputSource:
    """The input source (keyboard and gamepad cycle through the bundled gaits that fit the robot's legs)."""
    from shc_cli.loop.input_sources import GamepadInput, KeyboardInput, StdinInput, TimelineInput
    from shc_cli.spec.loading import bundled, load_gait

    def gait_of(name: str) -> Any:
        found = load_gait(name).gait
        if found is not None and set(found.offset_multiplier) != set(robot.legs):
            legs = ", ".join(found.offset_multiplier)
            raise SpecError([Issue(None, None, "gait", f"gait '{name}' is for legs {legs}",
                                   f"use a gait for {', '.join(robot.legs)}")])
        return found

    if kind == "stdin":
        return StdinInput(watchdog_s=watchdog, load_gait=gait_of)
    if kind in ("keyboard", "gamepad"):
        gaits = [g for g in (load_gait(name).gait for name in bundled("gaits"))
                 if g is not None and set(g.offset_multiplier) == set(robot.legs)]
        source: KeyboardInput | GamepadInput = KeyboardInput(gaits) if kind == "keyboard" else GamepadInput(
            argument or None, gaits)
        names = [g.name for g in gaits]
        source.gait_index = names.index(gait.name) if gait.name in names else 0  # the next gait is the one after
        return source
    return TimelineInput(commands)
