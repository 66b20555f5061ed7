"""``shc simulate``: the one controller driving the robot in physics (PyBullet or MuJoCo), logged and summarised."""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from datetime import datetime
from pathlib import Path
from typing import Any

import typer

from shc_cli.backends.simulated import SCENARIOS
from shc_cli.errors import Issue, SpecError
from shc_cli.loop.physics_summary import FALL_HEIGHT_SHARE, FALL_TILT
from shc_cli.spec.robot import Robot

__all__ = ["FALL_HEIGHT_SHARE", "FALL_TILT", "SCENARIOS", "Feedback", "SimulateOptions", "parse_posture",
           "run_simulate", "simulate_to"]


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


@dataclass(frozen=True)
class SimulateOptions:
    """Every option of ``shc simulate`` (the same names, the same defaults).

    Attributes:
        robot: robot file or bundled name.
        gait: gait file or name (None: the robot's).
        velocity: constant velocity input ``"VX,VY,WZ"`` in the robot's input mode.
        duration: seconds to run after start-up (None: a timeline's length + 1 s, or 20 s).
        commands: command timeline (CSV or TOML plan script).
        out: run directory (None: ``runs/<timestamp>-simulate``).
        plots: write trajectory.png, power.png and contacts.png.
        terrain: ``flat``, ``ramp:DEG``, ``blocks[...]``, ``stairs:RISE,RUN`` or ``heightfield:FILE[,SCALE]``.
        scenario: WG, SG, WA or SA.
        physics_rate: physics steps per second [Hz] (a whole multiple of the control rate).
        friction: lateral friction of feet and terrain.
        restitution: restitution of feet and terrain.
        seed: seed of every random thing.
        imu_noise: IMU noise standard deviation (rad/s, m/s²).
        start: spawn pose, ``unpacked`` or ``packed``.
        gui: open the physics GUI (needs a display).
        stand: start up on a stand (True), on the ground (False), or as ``start_up.simulation`` says (None).
        feedback: per-run switches of the sensor-driven features.
        fail_on_fall: the command exits 4 when the robot fell.
        overwrite: replace an existing run directory at ``out`` when the run finishes.
        engine: the physics engine, ``pybullet`` or ``mujoco``.
    """

    robot: str = "bullet"
    gait: str | None = None
    velocity: str = "1,0,0"
    duration: float | None = None
    commands: Path | None = None
    out: Path | None = None
    plots: bool = True
    terrain: str = "flat"
    scenario: str = "WG"
    physics_rate: float = 400.0
    friction: float = 0.9
    restitution: float = 0.0
    seed: int = 0
    imu_noise: float = 0.0
    start: str = "unpacked"
    gui: bool = False
    stand: bool | None = None
    feedback: Feedback = field(default_factory=lambda: Feedback())
    fail_on_fall: bool = False
    overwrite: bool = False
    engine: str = "pybullet"


def run_simulate(options: SimulateOptions, after: Callable[[Path], None] | None = None) -> Path:
    """Load, simulate, log, print one line, then ``after(run directory)``; returns the run directory. Exits 130/143
    when a signal stopped the run, 4 when it fell and ``fail_on_fall`` is set."""
    from shc_cli.analysis.progress import progress_note
    from shc_cli.commands.outcome import EXIT_FELL, exit_if_interrupted, interrupted_note

    path, summary = simulate_to(options)
    typer.echo(f"{summary['robot']} / {summary['gait']} / {summary['scenario']} on {options.terrain}: "
               f"{summary['sim_time_s']:.1f} s simulated in {summary['wall_time_s']:.1f} s, distance "
               f"{summary['distance_m']:.3f} m, path speed {summary['path_speed_mps']:.4f} m/s, displacement speed "
               f"{summary['displacement_speed_mps']:.4f} m/s, mean power "
               f"{summary['mean_power_w']:.1f} W, "
               f"CoT {summary['cot'] if summary['cot'] is None else round(summary['cot'], 3)}"
               f"{', FELL' if summary['fell'] else progress_note(summary)}{interrupted_note(summary)} → {path}")
    for warning in summary.get("engine_warnings", []):
        hint = "" if "--physics-rate" in warning else " (try a higher --physics-rate)"
        typer.echo(f"note: {summary['engine']}: {warning}{hint}", err=True)
    if after is not None:
        after(path)
    exit_if_interrupted(summary)
    if summary["fell"] and options.fail_on_fall:
        raise typer.Exit(EXIT_FELL)
    return path


def check_display(gui: bool) -> None:
    """``--gui`` needs a display: on Linux without ``DISPLAY`` (or ``WAYLAND_DISPLAY``) a one-line error, exit 2."""
    display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    if gui and sys.platform.startswith("linux") and not display:
        raise SpecError([Issue(None, None, "--gui", "no display (DISPLAY is not set)",
                               "drop --gui, or set DISPLAY / run under a virtual display: xvfb-run shc simulate ...")])


def simulate_to(options: SimulateOptions | None = None, **changes: Any) -> tuple[Path, dict[str, Any]]:
    """Load, simulate through the one loop, log (silently); returns the run directory and its summary.

    ``simulate_to(SimulateOptions(duration=2))`` or ``simulate_to(duration=2)`` (keywords change the defaults or
    the given options).
    """
    from shc_cli import __version__
    from shc_cli.backends.engine import ENGINES
    from shc_cli.backends.simulated import SimulatedBackend, WorldOptions, open_world
    from shc_cli.backends.terrain import parse_terrain
    from shc_cli.control.controller import Controller
    from shc_cli.loop.input_sources import TimelineInput
    from shc_cli.loop.physics_summary import PhysicsRecord
    from shc_cli.loop.run_inputs import load_inputs
    from shc_cli.loop.run_loop import START_UP_MARGIN_S, Observer, RunLoop, StartUp
    from shc_cli.loop.runlog import LogRecorder, RunDirectory
    from shc_cli.loop.session import execute

    o = replace(options or SimulateOptions(), **changes)
    check_display(o.gui)
    if o.engine not in ENGINES:
        raise SpecError([Issue(None, None, "--engine", f"'{o.engine}' is not a physics engine",
                               f"use {' or '.join(ENGINES)}")])
    scenario = o.scenario.upper()
    if scenario not in SCENARIOS:
        raise SpecError([Issue(None, None, "--scenario", f"'{scenario}' is not a scenario",
                               "use SA (stance air), WA (walk air), SG (stance ground) or WG (walk ground)")])
    airborne, walking = SCENARIOS[scenario]
    inputs = load_inputs(o.robot, o.gait, o.velocity, o.duration, o.commands, default_s=20.0, walking=walking,
                         robot_change=o.feedback.apply)
    robot = inputs.robot
    terrain = parse_terrain(o.terrain)
    substeps = round(o.physics_rate * robot.time_delta)
    if substeps < 1 or abs(substeps - o.physics_rate * robot.time_delta) > 1e-6:
        raise SpecError([Issue(None, None, "--physics-rate", f"{o.physics_rate:g} Hz is not a whole multiple of the "
                               f"control rate {1 / robot.time_delta:g} Hz",
                               f"e.g. {4 / robot.time_delta:g} Hz")])
    if o.start not in ("unpacked", "packed"):
        raise SpecError([Issue(None, None, "--start", f"'{o.start}' is not a start pose", "use unpacked or packed")])
    directory = o.out or Path("runs") / f"{datetime.now():%Y%m%d-%H%M%S}-simulate"
    stand = robot.start_up.simulation == "stand" if o.stand is None else o.stand
    with RunDirectory(directory, o.overwrite) as run:  # refuses an existing --out before the physics opens
        world = open_world(robot, WorldOptions(terrain, substeps, airborne, o.friction, o.restitution, o.seed,
                                               o.imu_noise, o.start, o.gui, stand, o.engine))
        with SimulatedBackend(robot, world) as backend:
            controller = Controller(robot, inputs.gait, joints=backend.start(), pose_sets=inputs.pose_sets)
            run.write_robot(robot)
            record = PhysicsRecord(robot, backend, airborne)
            progress = _progress(inputs.cycles)
            observers: list[Observer] = [record] if progress is None else [record, progress]
            loop = RunLoop(controller, backend, TimelineInput(inputs.timeline.commands(inputs.cycles)),
                           LogRecorder(run, robot, backend),
                           StartUp(round((robot.start_up.time_to_start + START_UP_MARGIN_S) / robot.time_delta)),
                           observers=observers, flush_every=200)

            def summarise(_: Any) -> dict[str, Any]:
                import numpy as np

                if progress is not None:
                    progress.stop()
                return {**record.summary(scenario, controller.gait.name, controller), "seed": o.seed,
                        "terrain": str(world.terrain.spec), "engine": world.name, "engine_version": world.version,
                        "engine_warnings": world.warnings,
                        "versions": {"shc": __version__, world.name: world.version, "numpy": np.__version__}}

            def plot(folder: Path) -> None:
                from shc_cli.plots import plot_simulation

                plot_simulation(robot, record.series, folder, gait=controller.gait.name)

            path, summary, _ = execute(loop, run, summarise, plot if o.plots else None)
    return path, summary


class _Progress:
    """The progress bar over the walking cycles (an observer of the loop)."""

    def __init__(self, bar: Any) -> None:
        self.bar, self.walked = bar, 0

    def __call__(self, cycle: int, command: Any, out: Any, reading: Any) -> str | None:
        if command.state_request is None or out.robot_state.name == "RUNNING":
            self.walked += 1
            if self.walked % 50 == 0:
                self.bar.update(self.walked)
        return None

    def stop(self) -> None:
        self.bar.stop()


def _progress(total: int) -> _Progress | None:
    """A progress bar on a terminal; None in pipes and CI (quiet)."""
    from shc_cli.progress import progress_bar

    bar = progress_bar("simulating", total)
    return None if bar is None else _Progress(bar)
