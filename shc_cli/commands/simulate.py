"""``shc simulate``: the one controller driving the robot in physics (PyBullet or MuJoCo), logged and summarised."""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

import numpy as np
import typer

from shc_cli.commands.plan import parse_velocity, pose_sets_for, walk_cycles
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.sensing import Sensors
from shc_cli.errors import Issue, ShcError, SpecError
from shc_cli.runlog import RunDirectory, joint_columns
from shc_cli.spec.robot import Robot
from shc_cli.spec.timeline import Timeline, constant, load_timeline

SCENARIOS = {"SA": (True, False), "WA": (True, True), "SG": (False, False), "WG": (False, True)}
"""Paper §VII-A scenarios: (body held in the air, walking)."""
FALL_TILT = 0.8
"""Body tilt above which the robot has fallen [rad] (≈ 46°)."""
FALL_HEIGHT_SHARE = 0.3
"""The robot has fallen when its body is lower than this share of the body clearance above the terrain."""
START_UP_MARGIN_S = 2.0


@dataclass(frozen=True)
class Feedback:
    """Per-run switches of the sensor-driven features, over the robot file (``None`` = as the file says).

    Attributes:
        posture: ATHENA gains, e.g. ``"kz=0.8,ka=0.6,kb=0"`` (also ``plane=least_squares``); enables it.
        imu_posing: OpenSHC IMU posing on or off.
        inclination: ``"off"``, ``"openshc"`` or ``"support_centroid"``.
        admittance: admittance control on or off.
    """

    posture: str | None = None
    imu_posing: bool | None = None
    inclination: str | None = None
    admittance: bool | None = None

    def apply(self, robot: Robot) -> Robot:
        """The robot with these switches applied (one-line SpecError on a bad value)."""
        pose, posture = robot.pose, robot.posture
        if self.imu_posing is not None:
            pose = pose.model_copy(update={"imu": self.imu_posing})
        if self.inclination is not None:
            if self.inclination not in ("off", "openshc", "support_centroid"):
                raise SpecError([Issue(None, None, "--inclination", f"'{self.inclination}' is not a mode",
                                       "use off, openshc or support_centroid")])
            on = self.inclination != "off"
            pose = pose.model_copy(update={"inclination": on, **({"inclination_mode": self.inclination} if on
                                                                   else {})})
        if self.posture is not None:
            posture = posture.model_copy(update={"enabled": True, **parse_posture(self.posture)})
        admittance = robot.admittance
        if self.admittance is not None:
            admittance = admittance.model_copy(update={"enabled": self.admittance})
        return robot.model_copy(update={"pose": pose, "posture": posture, "admittance": admittance})


def parse_posture(text: str) -> dict[str, Any]:
    """``kz=0.8,ka=0.6,kb=0[,plane=least_squares]`` → fields of ``[posture]``; one-line SpecError if bad."""
    out: dict[str, Any] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, _, value = part.partition("=")
        key = key.strip()
        if key in ("kz", "ka", "kb"):
            try:
                number = float(value)
            except ValueError:
                number = math.nan
            if not 0.0 <= number <= 1.0:
                raise SpecError([Issue(None, None, "--posture", f"{key}={value!r} is not a gain in [0, 1]",
                                       "e.g. --posture kz=0.8,ka=0.6,kb=0")])
            out[key] = number
        elif key == "plane" and value in ("random_three", "least_squares"):
            out[key] = value
        else:
            raise SpecError([Issue(None, None, "--posture", f"'{part}' is not kz=, ka=, kb= or plane=",
                                   "e.g. --posture kz=0.8,ka=0.6,kb=0 (plane=random_three|least_squares)")])
    return out


def run_simulate(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
                 commands: Path | None, out: Path | None, plots: bool, terrain_text: str, scenario: str,
                 physics_rate: float, friction: float, restitution: float, seed: int, imu_noise: float,
                 start_pose: str, gui: bool, stand: bool | None = None, feedback: Feedback | None = None,
                 overwrite: bool = False, engine: str = "pybullet") -> Path:
    """Load, simulate, log, print one line; returns the run directory."""
    from shc_cli.analysis.progress import progress_note

    path, summary = simulate_to(robot_name, gait_name, velocity, duration, commands, out, plots, terrain_text,
                                scenario, physics_rate, friction, restitution, seed, imu_noise, start_pose, gui,
                                stand, feedback, overwrite, engine)
    typer.echo(f"{summary['robot']} / {summary['gait']} / {summary['scenario']} on {terrain_text}: "
               f"{summary['sim_time_s']:.1f} s simulated in {summary['wall_time_s']:.1f} s, distance "
               f"{summary['distance_m']:.3f} m, path speed {summary['path_speed_mps']:.4f} m/s, displacement speed "
               f"{summary['displacement_speed_mps']:.4f} m/s, mean power "
               f"{summary['mean_power_w']:.1f} W, "
               f"CoT {summary['cot'] if summary['cot'] is None else round(summary['cot'], 3)}"
               f"{', FELL' if summary['fell'] else progress_note(summary)} → {path}")
    return path


def simulate_to(robot_name: str, gait_name: str | None, velocity: str, duration: float | None,
                commands: Path | None, out: Path | None, plots: bool, terrain_text: str, scenario: str,
                physics_rate: float, friction: float, restitution: float, seed: int, imu_noise: float,
                start_pose: str, gui: bool = False, stand: bool | None = None,
                feedback: Feedback | None = None, overwrite: bool = False,
                engine: str = "pybullet") -> tuple[Path, dict[str, Any]]:
    """Load, simulate, log (silently); returns the run directory and its summary (``overwrite``: replace an
    existing run directory when the run finishes)."""
    from shc_cli.backends.engine import ENGINES
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.spec.checks import load_checked

    robot, gait, loaded = load_checked(robot_name, gait_name)
    if feedback is not None:
        robot = feedback.apply(robot)
    terrain = parse_terrain(terrain_text)
    scenario = scenario.upper()
    if scenario not in SCENARIOS:
        raise SpecError([Issue(None, None, "--scenario", f"'{scenario}' is not a scenario",
                               "use SA (stance air), WA (walk air), SG (stance ground) or WG (walk ground)")])
    substeps = round(physics_rate * robot.time_delta)
    if substeps < 1 or abs(substeps - physics_rate * robot.time_delta) > 1e-6:
        raise SpecError([Issue(None, None, "--physics-rate", f"{physics_rate:g} Hz is not a whole multiple of the "
                               f"control rate {1 / robot.time_delta:g} Hz",
                               f"e.g. {4 / robot.time_delta:g} Hz")])
    if engine not in ENGINES:
        raise SpecError([Issue(None, None, "--engine", f"'{engine}' is not a physics engine",
                               f"use {' or '.join(ENGINES)}")])
    if start_pose not in ("unpacked", "packed"):
        raise SpecError([Issue(None, None, "--start", f"'{start_pose}' is not a start pose", "use unpacked or packed")])
    walking = SCENARIOS[scenario][1]
    timeline = load_timeline(commands, robot.time_delta) if commands else constant(
        parse_velocity(velocity) if walking else (0.0, 0.0, 0.0))
    cycles = walk_cycles(timeline, duration, robot.time_delta, commands is not None, default_s=20.0)
    gait_file, _ = loaded.where(("walker", "gait"))
    pose_sets = pose_sets_for(robot, gait, timeline, gait_file.parent)
    directory = out or Path("runs") / f"{datetime.now():%Y%m%d-%H%M%S}-simulate"
    if stand is None:
        stand = robot.start_up.simulation == "stand"
    run = Simulation(robot, gait, pose_sets, terrain, scenario, substeps, friction, restitution, seed, imu_noise,
                     start_pose, gui, stand, engine)
    log = RunDirectory(directory, overwrite)
    log.write_robot(robot)
    try:
        summary, series = run.execute(timeline, cycles, log)
    except KeyboardInterrupt:
        log.close()
        raise ShcError(f"interrupted: the cycles completed so far are in {log.partial}") from None
    finally:
        run.world.close()
    if plots:
        from shc_cli.plots import plot_simulation

        plot_simulation(robot, series, log.partial, gait=summary["gait"])
    return log.finish(summary), summary


class Simulation:
    """One simulated run: a physics :class:`~shc_cli.backends.engine.Engine` and the controller."""

    def __init__(self, robot: Robot, gait: Any, pose_sets: dict[str, Any], terrain: Any, scenario: str,
                 substeps: int, friction: float, restitution: float, seed: int, imu_noise: float,
                 start_pose: str, gui: bool, stand: bool = False, engine: str = "pybullet") -> None:
        from shc_cli.backends.engine import open_engine
        from shc_cli.control.sequence import joint_configurations
        from shc_cli.model.chains import Chains

        self.robot, self.gait, self.scenario, self.seed = robot, gait, scenario, seed
        chains = Chains.from_robot(robot)
        packed, unpacked = joint_configurations(robot, chains.joints)
        initial = np.clip(packed[-1] if start_pose == "packed" and len(packed) else unpacked, chains.lower,
                          chains.upper)
        airborne, _ = SCENARIOS[scenario]
        self.world = open_engine(engine, robot, terrain, robot.time_delta, substeps, airborne, initial, friction,
                                 restitution, seed, imu_noise, gui, stand)
        self.controller = Controller(robot, gait, joints=self.world.read().joints, pose_sets=pose_sets)
        self.airborne = airborne

    def execute(self, timeline: Timeline, walk_cycles: int, log: RunDirectory) -> tuple[dict[str, Any], dict[str, Any]]:
        """Start up, play the timeline, log every control cycle; returns (summary, series for the plots)."""
        from shc_cli.backends.engine import tilt

        robot, world, controller = self.robot, self.world, self.controller
        dt = robot.time_delta
        legs = list(robot.legs)
        columns = (joint_columns(robot, "_cmd") + joint_columns(robot) + joint_columns(robot, "_torque")
                   + joint_columns(robot, "_power")
                   + [f"{leg}_force" for leg in legs] + [f"{leg}_contact" for leg in legs]
                   + ["x", "y", "z", "roll", "pitch", "yaw", "vx", "vy", "vz", "wx", "wy", "wz",
                      "imu_qx", "imu_qy", "imu_qz", "imu_qw", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z",
                      "height", "power_w", "cmd_vx", "cmd_vy", "cmd_wz", "vel_x", "vel_y", "vel_wz",
                      "robot_state", "walk_state"])
        handle, row = log.table("log.csv", columns, ["%.6g"] * (len(columns) - 2) + ["%s", "%s"])
        rows, cols = world.slot_rows, world.slot_cols  # padded (L, n) arrays → the log's joint columns
        limit = round((robot.start_up.time_to_start + START_UP_MARGIN_S) / dt)
        series: dict[str, list[Any]] = {"t": [], "position": [], "power": [], "contact": [], "running": [],
                                        "desired": []}
        commands = iter(timeline.commands(walk_cycles))
        started = time.perf_counter()
        cycle, walked, fell, max_tilt = 0, 0, False, 0.0
        window_start: np.ndarray | None = None
        progress = _progress(walk_cycles)
        sensors: Sensors | None = None
        feedback_on = controller.uses_sensors
        while walked < walk_cycles:
            if controller.state != RobotState.RUNNING:
                if cycle > limit:
                    raise ShcError(f"{robot.name}: did not reach RUNNING within {limit} cycles of start-up")
                command = Command(state_request=RobotState.RUNNING)
            else:
                command = next(commands)
                walked += 1
                if progress is not None and walked % 50 == 0:
                    progress(walked)
            out = controller.step(command, sensors)
            world.command(out.joints)
            world.step()
            reading = world.read()
            if feedback_on:  # what the controller sees next cycle
                sensors = Sensors(reading.orientation, reading.angular_rate, reading.joints, reading.joint_efforts,
                                  reading.foot_forces, reading.foot_contact, reading.body_height)
            power = reading.servo_power[rows, cols]
            total = float(power.sum())
            running = out.robot_state == RobotState.RUNNING
            if running and world.stand is not None:
                world.release_stand()  # started up on the stand: now on its own feet
            values = np.concatenate((out.joints[rows, cols], reading.joints[rows, cols],
                                     reading.joint_efforts[rows, cols], power, reading.foot_forces,
                                     reading.foot_contact, reading.position, reading.rpy, reading.linear_velocity,
                                     reading.angular_velocity, reading.orientation, reading.angular_rate,
                                     reading.linear_acceleration, (reading.body_height, total), command.velocity,
                                     out.velocity))
            handle.write(row % (cycle, cycle * dt, *values.tolist(), out.robot_state.name, out.walk_state.name))
            series["t"].append(cycle * dt)
            series["position"].append(reading.position)
            series["power"].append(total)
            series["contact"].append(reading.foot_contact)
            series["running"].append(running)
            series["desired"].append(out.velocity)
            if running:
                if window_start is None:  # where the body was when the first RUNNING cycle began
                    window_start = series["position"][-2] if len(series["position"]) > 1 else reading.position
                    self._running_since = (time.perf_counter(), world.physics_time)
                max_tilt = max(max_tilt, tilt(reading.rpy))
                low = reading.body_height < FALL_HEIGHT_SHARE * robot.walker.body_clearance
                if max_tilt > FALL_TILT or (low and not self.airborne):
                    fell = True
                    break
            cycle += 1
            if cycle % 200 == 0:
                log.flush()
        wall = time.perf_counter() - started
        since_wall, since_physics = getattr(self, "_running_since", (time.perf_counter(), world.physics_time))
        self.running_times = (time.perf_counter() - since_wall, world.physics_time - since_physics)
        if progress is not None:
            progress(walk_cycles)
        return self._summary(series, window_start, wall, fell, max_tilt), series

    def _summary(self, series: dict[str, list[Any]], window_start: np.ndarray | None, wall: float, fell: bool,
                 max_tilt: float) -> dict[str, Any]:
        """Paper eq. 22 cost of transport over the RUNNING window: mean power / (m·g·v)."""
        from shc_cli import __version__

        robot, dt = self.robot, self.robot.time_delta
        running = np.array(series["running"], dtype=bool)
        power = np.array(series["power"])
        window = float(running.sum()) * dt
        end = series["position"][-1] if series["position"] else np.zeros(3)
        start = window_start if window_start is not None else end
        distance = float(np.linalg.norm((end - start)[:2]))
        speed = distance / window if window > 0 else 0.0
        from shc_cli.analysis.metrics import window_speeds

        xy = np.array(series["position"])[:, :2] if series["position"] else np.zeros((0, 2))
        path_speed, _ = window_speeds(xy, np.flatnonzero(running), dt)
        from shc_cli.analysis.progress import cycle_path_length, progress_fields

        desired = np.array(series["desired"]).reshape(-1, 3)[running[:len(series["desired"])], :2]
        commanded = float(np.linalg.norm(desired, axis=1).mean()) if len(desired) else 0.0
        mean_power = float(power[running].mean()) if running.any() else 0.0
        mass = robot.total_mass()
        walking_on_ground = self.scenario == "WG"
        cot = mean_power / (mass * 9.81 * speed) if walking_on_ground and speed > 1e-3 else None  # eq. 22, WG only
        return {
            "robot": robot.name,
            "gait": self.controller.gait.name,
            "scenario": self.scenario,
            "sim_time_s": len(series["t"]) * dt,
            "analysed_time_s": window,
            "wall_time_s": wall,
            "running_wall_time_s": self.running_times[0],
            "running_physics_time_s": self.running_times[1],
            "physics_time_s": self.world.physics_time,
            "physics_rate_hz": self.world.substeps / dt,
            "engine": self.world.name,
            "engine_version": self.world.version,
            "distance_m": distance,
            "forward_distance_m": float((end - start)[0]),
            "mean_speed_mps": speed,  # = displacement_speed_mps, its first name
            "displacement_speed_mps": speed,
            "path_speed_mps": path_speed,
            "commanded_speed_mps": commanded,
            **progress_fields(cycle_path_length(_window_path(xy, running), self.controller.cycle.period), commanded,
                              window),
            "mean_power_w": mean_power,
            "mass_kg": mass,
            "step_frequency_hz": self.controller.parameters["step_frequency"],
            "step_period_cycles": self.controller.cycle.period,
            "cycle_frequency_hz": self.controller.cycle.frequency,
            "duty_factor": self.controller.cycle.duty_factor,
            "cot": cot,
            "max_tilt_rad": max_tilt,
            "fell": fell,
            "seed": self.seed,
            "terrain": str(self.world.terrain.spec),
            "versions": {"shc": __version__, self.world.name: self.world.version, "numpy": np.__version__},
        }


def _window_path(xy: np.ndarray, running: np.ndarray) -> np.ndarray:
    """The body path over the RUNNING rows, starting where the row before the first of them ended."""
    rows = np.flatnonzero(running)
    if len(rows) == 0:
        return np.zeros((0, 2))
    return np.vstack([xy[max(rows[0] - 1, 0)], xy[rows[0]:rows[-1] + 1]])


def _progress(total: int) -> Any:
    """A rich progress bar on a terminal; None in pipes and CI (quiet)."""
    if not sys.stderr.isatty() or os.environ.get("CI"):
        return None
    from rich.progress import Progress

    bar = Progress(transient=True)
    task = bar.add_task("simulating", total=total)
    bar.start()

    def update(done: int) -> None:
        bar.update(task, completed=done)
        if done >= total:
            bar.stop()

    return update
