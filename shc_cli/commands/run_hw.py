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
foot forces — are 0) plus ``cycle_time_ms`` in ``timing.csv``; the summary adds cycle-time statistics, overruns
and faults.
"""

from __future__ import annotations

import signal
import time
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import typer

from shc_cli.commands.plan import parse_velocity, pose_sets_for, walk_cycles
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.sensing import Sensors
from shc_cli.control.walk import WalkState
from shc_cli.errors import Issue, SpecError
from shc_cli.hardware.inputs import STATES, TimelineInput
from shc_cli.runlog import RunDirectory, joint_columns

STOP_TIMEOUT_S = 10.0
"""Longest controlled stop and shut-down after Ctrl-C, beyond the sequences' own time, before the torque goes off
anyway [s]."""
LOG_COLUMNS_ZERO = ["x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "wx", "wy", "wz", "imu_qx", "imu_qy",
                    "imu_qz", "imu_qw", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z", "height", "power_w"]
INPUTS = "timeline, commands:FILE, stdin, keyboard, gamepad or gamepad:DEVICE"


def run_hw(robot_name: str, gait_name: str | None, ports: list[str], baud: int | None, velocity: str,
           duration: float | None, commands: Path | None, out: Path | None, dry_run: bool, on_fault: str,
           on_stop: str, input_mode: str = "timeline", watchdog: float = 0.5, stop_state: str = "packed",
           profile_velocity: bool = False, overwrite: bool = False) -> Path:
    """Start up, run the input on the servos, stop and shut down safely; returns the run directory (``overwrite``:
    replace an existing one when the run finishes)."""
    from shc_cli.hardware.bus import HardwareError, ServoBus
    from shc_cli.spec.checks import load_checked
    from shc_cli.spec.timeline import constant, load_timeline

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
    robot, gait, loaded = load_checked(robot_name, gait_name)
    timeline = load_timeline(commands, robot.time_delta) if commands else constant(parse_velocity(velocity))
    cycles = walk_cycles(timeline, duration, robot.time_delta, commands is not None, default_s=20.0)
    gait_file, _ = loaded.where(("walker", "gait"))
    pose_sets = pose_sets_for(robot, gait, timeline, gait_file.parent)
    bus = ServoBus(robot, ports, baud, profile_velocity)
    source: Any = None
    try:
        source = _source(kind, argument, robot, gait, timeline.commands(cycles), watchdog)
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
        state = bus.read_state()
        controller = Controller(robot, gait, joints=state.positions, pose_sets=pose_sets, direct_shutdown=True)
        directory = out or Path("runs") / f"{datetime.now():%Y%m%d-%H%M%S}-run-hw"
        log = RunDirectory(directory, overwrite)
        log.write_robot(robot)
        loop = _Loop(robot, controller, bus, log, dry_run, on_fault, on_stop, STATES[stop_state])
        summary = loop.run(source, state)
        summary["input"] = input_mode
        summary["watchdog_trips"] = getattr(source, "watchdog_trips", 0)
        path = log.finish(summary)
    finally:
        if source is not None:
            source.close()
        bus.close()
    fault = f", FAULT: {summary['fault']}" if summary["fault"] else ""
    typer.echo(f"{robot.name} on {bus.port_name}: {summary['cycles']} cycles, cycle time mean "
               f"{summary['cycle_time_mean_ms']:.2f} ms, p99 {summary['cycle_time_p99_ms']:.2f} ms, "
               f"{summary['overruns']} overruns, ended {summary['final_state']}{fault} → {path}")
    return path


def _source(kind: str, argument: str, robot: Any, gait: Any, commands: list[Command], watchdog: float) -> Any:
    """The input source (keyboard and gamepad cycle through the bundled gaits that fit the robot's legs)."""
    from shc_cli.hardware.inputs import GamepadInput, KeyboardInput, StdinInput
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
        source = KeyboardInput(gaits) if kind == "keyboard" else GamepadInput(argument or None, gaits)
        names = [g.name for g in gaits]
        source.gait_index = names.index(gait.name) if gait.name in names else 0  # the next gait is the one after
        return source
    return TimelineInput(commands)


class _Loop:
    """The real-time loop and its stop and fault handling."""

    def __init__(self, robot: Any, controller: Controller, bus: Any, log: RunDirectory, dry_run: bool, on_fault: str,
                 on_stop: str, stop_state: RobotState) -> None:
        self.robot, self.controller, self.bus, self.log = robot, controller, bus, log
        self.dry_run, self.on_fault, self.on_stop, self.stop_state = dry_run, on_fault, on_stop, stop_state
        self.stop_requested = False
        self.fault = ""
        self.stopping_since: int | None = None
        self.stop_limit = STOP_TIMEOUT_S
        dt = robot.time_delta
        self.start_limit = round((robot.start_up.time_to_start * 2.5 + 10.0) / dt)
        from shc_cli.model.chains import Chains

        chains = Chains.from_robot(robot)
        self.lower, self.upper = chains.lower, chains.upper
        self.max_step = chains.max_vel * dt * 1.5  # rate limit: 1.5 × the joint speed limit per cycle
        self.legs = list(robot.legs)

    def _request_stop(self, signum: int, frame: Any) -> None:
        self.stop_requested = True

    def _command(self, source: Any, cycle: int, started: bool) -> tuple[Command | None, bool]:
        """This cycle's command and whether the start-up is done; ``None`` ends the loop."""
        controller, dt = self.controller, self.robot.time_delta
        if not started and controller.state == RobotState.RUNNING:
            started = True
        if started and not self.stop_requested:
            command = source.next()
            if command is not None:
                return command, started
            self.stop_requested = True  # the input is over: stop as after Ctrl-C
        if self.stop_requested:
            if self.stopping_since is None:
                self.stopping_since = cycle
                down = controller.state > self.stop_state
                self.stop_limit = STOP_TIMEOUT_S + (2.5 * self.robot.start_up.time_to_start if down else 0.0)
            walker = controller.walker
            stopped = walker is None or walker.state == WalkState.STOPPED
            reached = controller.state <= self.stop_state and not controller.transition_pending
            if (reached and stopped) or (cycle - self.stopping_since) * dt > self.stop_limit:
                return None, started
            return Command(state_request=self.stop_state), started  # zero velocity: stop walking, then shut down
        if cycle > self.start_limit:
            self._fault(f"did not reach RUNNING within {self.start_limit} cycles")
            return None, started
        return Command(state_request=RobotState.RUNNING), started

    def run(self, source: Any, state: Any) -> dict[str, Any]:
        robot, controller, bus = self.robot, self.controller, self.bus
        dt = robot.time_delta
        columns = (joint_columns(robot, "_cmd") + joint_columns(robot) + joint_columns(robot, "_torque")
                   + joint_columns(robot, "_power") + [f"{leg}_force" for leg in self.legs]
                   + [f"{leg}_contact" for leg in self.legs] + LOG_COLUMNS_ZERO
                   + ["cmd_vx", "cmd_vy", "cmd_wz", "vel_x", "vel_y", "vel_wz", "robot_state", "walk_state"])
        handle, row = self.log.table("log.csv", columns, ["%.6g"] * (len(columns) - 2) + ["%s", "%s"])
        timing, timing_row = self.log.table("timing.csv", ["cycle_time_ms", "overrun"], ["%.4f", "%d"])
        previous_handlers = {sig: signal.signal(sig, self._request_stop) for sig in (signal.SIGINT, signal.SIGTERM)}
        rows, cols = bus._rows, bus._cols
        torque_on = started = False
        goals = state.positions.copy()
        cycle_times: list[float] = []
        overruns = cycle = 0
        deadline = time.perf_counter()
        try:
            if not self.dry_run:
                bus.torque(True)
                torque_on = True
            while True:
                began = time.perf_counter()
                if cycle:  # the first cycle uses the start-up read
                    state = bus.read_state()
                if not state.answered.all():  # the first servo that failed and why; the rest of its bus unread
                    missing = [bus.slots[i].key for i in np.flatnonzero(~state.answered)]
                    reasons = [f"{reason} from {bus.slots[i].key}" for i, reason in state.failures.items()]
                    self._fault(f"{'; '.join(reasons) or 'no reply'} (unread: {', '.join(missing)})")
                    break
                if state.alerts.any():  # a status packet's alert bit: name the hardware errors and stop
                    errors = bus.hardware_errors()
                    flagged = [bus.slots[i].key for i in np.flatnonzero(state.alerts)]
                    self._fault("; ".join(f"{key}: {', '.join(names)}" for key, names in errors.items())
                                or f"hardware error alert from {', '.join(flagged)}")
                    break
                command, started = self._command(source, cycle, started)
                if command is None:
                    break
                out = controller.step(command, Sensors(joints=state.positions))
                target = np.clip(out.joints, self.lower, self.upper)
                goals = goals + np.clip(target - goals, -self.max_step, self.max_step)
                if not self.dry_run:
                    bus.write_goals(goals, dt)
                currents = state.currents[rows, cols]
                values = np.concatenate((goals[rows, cols], state.positions[rows, cols], currents / 1000.0,
                                         np.zeros(len(rows)), np.zeros(2 * len(self.legs)),
                                         np.zeros(len(LOG_COLUMNS_ZERO)), command.velocity, out.velocity))
                handle.write(row % (cycle, cycle * dt, *values.tolist(), out.robot_state.name, out.walk_state.name))
                cycle += 1
                deadline += dt
                now = time.perf_counter()
                cycle_times.append(now - began)
                late = now > deadline
                overruns += late
                timing.write(timing_row % (cycle - 1, (cycle - 1) * dt, cycle_times[-1] * 1e3, late))
                if late:
                    deadline = now  # drift-free while on time; after an overrun, restart from now
                else:
                    time.sleep(deadline - now)
                if cycle % 100 == 0:
                    self.log.flush()
        finally:
            for sig, previous in previous_handlers.items():
                signal.signal(sig, previous)
            release = self.on_fault if self.fault else self.on_stop
            if torque_on and release == "torque-off":
                bus.torque(False)
        times = np.array(cycle_times) * 1e3 if cycle_times else np.zeros(1)
        if len(cycle_times) > 20 and np.mean(np.array(cycle_times) > dt) > 0.05:
            typer.echo(f"warning: the loop missed its {dt * 1e3:.0f} ms period in {overruns} of {cycle} cycles",
                       err=True)
        return {
            "robot": robot.name, "gait": controller.gait.name, "scenario": "hardware", "port": bus.port_name,
            "baud": bus.baud, "dry_run": self.dry_run, "cycles": cycle, "sim_time_s": cycle * dt,
            "cycle_time_mean_ms": float(times.mean()), "cycle_time_p99_ms": float(np.percentile(times, 99)),
            "cycle_time_max_ms": float(times.max()), "overruns": int(overruns),
            "wire_time_ms": bus.wire_time() * 1e3, "read_retries": bus.retries, "fault": self.fault or None,
            "stopped_by_request": bool(self.stop_requested and not self.fault),
            "final_state": controller.state.name, "stop_state": self.stop_state.name,
            "step_frequency_hz": controller.parameters["step_frequency"],
            "step_period_cycles": controller.cycle.period, "duty_factor": controller.cycle.duty_factor,
        }

    def _fault(self, text: str) -> None:
        """Stop commanding motion now: no further goal is written; the torque is held or turned off on exit."""
        self.fault = text
        typer.echo(f"fault: {text} — {'holding' if self.on_fault == 'hold' else 'torque off'}", err=True)
