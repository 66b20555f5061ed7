"""One simulation: the controller driving the robot in physics (PyBullet or MuJoCo) through the one run loop,
logged and summarised in a run directory. Never prints; the command prints the summary line."""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.domain.config import SimulationConfig
from shc_cli.domain.live import open_live, wall_clock
from shc_cli.domain.result import RunResult

if TYPE_CHECKING:
    from shc_cli.backends.engine import Reading
    from shc_cli.control.controller import Command, CycleOutput
    from shc_cli.control.leg_failure import LegFailure
    from shc_cli.loop.run_loop import LoopResult
    from shc_cli.record.summary import RunSummary
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot


log = logging.getLogger(__name__)


def check_display(gui: bool) -> None:
    """``--gui`` needs a display: on Linux without ``DISPLAY`` (or ``WAYLAND_DISPLAY``) a one-line error."""
    import os
    import sys

    from shc_cli.errors import Issue, SpecError

    display = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    if gui and sys.platform.startswith("linux") and not display:
        raise SpecError([Issue(None, None, "--gui", "no display (DISPLAY is not set)",
                               "drop --gui, or set DISPLAY / run under a virtual display: xvfb-run shc simulate ...")])


def failed_legs(robot: Robot, gait: Gait, fail_leg: str | None, velocity: str = "1,0,0"
                ) -> tuple[Robot, Gait, LegFailure | None]:
    """The robot and gait re-planned for the legs left after ``fail_leg`` (``LEG[:MODE]``, comma-separated;
    :mod:`shc_cli.control.leg_failure`) and the controller's collaborator; unchanged without failures. The
    walking heading is the velocity input's (``VX,VY,WZ``; forward when it has none).

    Raises:
        SpecError: an unknown leg or mode, or no gait for the legs left (one line).
    """
    import math

    from shc_cli.control.leg_failure import adapt, parse_failures
    from shc_cli.events import event

    if not fail_leg:
        return robot, gait, None
    failed = parse_failures([fail_leg], list(robot.legs))
    try:
        vx, vy = (float(part) for part in velocity.split(",")[:2])
    except ValueError:
        vx, vy = 1.0, 0.0
    adapted = adapt(robot, failed, math.atan2(vy, vx) if (vx or vy) else 0.0)
    planned = adapted.planned
    event(log, logging.INFO, "leg_failure", "failed legs %s: walking on %s with a generated gait (%s, duty "
          "factor %.3f, static margin %.3f m at a %.3f m stride, body shifted %+.3f, %+.3f m)",
          ", ".join(map(str, failed)), ", ".join(leg for leg in robot.legs if leg not in adapted.failure.legs),
          " → ".join("+".join(group) for group in planned.groups), planned.duty_factor, planned.margin_m,
          adapted.stride_m, planned.body_shift_m[0][0], planned.body_shift_m[0][1], terminal=False)
    return adapted.robot, adapted.gait, adapted.failure


def simulate(config: SimulationConfig | None = None, progress: OnProgress | None = None) -> RunResult:
    """Load, simulate through the one loop, log; returns the run directory and its summary (``progress``: told the
    walking cycles done, :data:`OnProgress`).

    Raises:
        ShcError: bad input (one line), before anything is written.
    """
    from shc_cli.backends.simulated import SimulatedBackend, open_world
    from shc_cli.control.controller import Controller
    from shc_cli.control.verified_limits import source_for
    from shc_cli.errors import Issue, SpecError
    from shc_cli.events import event
    from shc_cli.loop.input_choice import commands_file, is_live, open_input
    from shc_cli.loop.path_input import keep_path
    from shc_cli.loop.physics_summary import PhysicsRecord
    from shc_cli.loop.run_inputs import load_inputs
    from shc_cli.loop.run_loop import Observer, RunLoop, StartUp
    from shc_cli.loop.session import execute
    from shc_cli.record.runlog import LogRecorder, RunDirectory, default_run_directory
    from shc_cli.version import __version__

    o = config or SimulationConfig()
    check_display(o.gui)
    for warning in o.warnings():  # legal but degenerate values (friction 0)
        event(log, logging.WARNING, "degenerate_option", "warning: %s", warning)
    if o.path is not None and o.input_mode != "timeline":
        raise SpecError([Issue(None, None, "--path", f"--path and --input {o.input_mode} both give the run's input",
                               "drop --input (a path is followed by itself)")])
    inputs = load_inputs(o.robot, o.gait, o.velocity, o.duration, commands_file(o.input_mode, o.commands),
                         default_s=20.0, walking=o.walking, robot_change=o.apply_switches, path=o.path)
    by_hand = is_live(o.input_mode)
    robot, gait, failure = failed_legs(inputs.robot, inputs.gait, o.fail_leg, o.velocity)
    options = o.engine_options(robot)
    directory = o.out or default_run_directory("simulate")
    source = open_input(o.input_mode, robot, gait, inputs.commands(), o.watchdog)  # before anything opens
    try:
        with RunDirectory(directory, o.overwrite) as run:  # refuses an existing --out before the physics opens
            world = open_world(robot, options)
            with SimulatedBackend(robot, world) as backend:
                controller = Controller(robot, gait, joints=backend.start(), pose_sets=inputs.pose_sets,
                                        failure=failure, speed_shares=None if failure else source_for(robot))
                run.write_robot(robot)
                if inputs.path is not None:
                    source.close()
                    source = inputs.source(controller)
                path_fields = keep_path(source, run.partial)
                record = PhysicsRecord(robot, backend, o.airborne)
                counter = None if progress is None or by_hand else _Progress(progress, inputs.cycles)
                observers: list[Observer[Reading]] = [record] if counter is None else [record, counter]
                live = open_live(o.live_port, robot, controller, sensors=True) if o.live else None
                if live is not None:
                    observers.append(live[1])
                clock = wall_clock(robot) if o.paced else None
                if clock is not None:
                    observers.append(clock)
                if o.perception == "rays":  # the depth sensor: an observer whose map the commands carry
                    from shc_cli.loop.perception import RayCaster, RayPerception

                    if not isinstance(world, RayCaster):
                        raise SpecError([Issue(None, None, "--perception", f"the {world.name} engine casts no rays",
                                               "use --engine mujoco or pybullet, or --perception off")])
                    eyes = RayPerception(robot, world, o.seed)
                    observers.insert(0, eyes)
                    source = eyes.wrap(source)
                loop = RunLoop(controller, backend, source, LogRecorder(run, robot, backend),
                               StartUp.of(robot),
                               observers=observers, flush_every=FLUSH_PACED if o.paced else 200)

                def summarise(_: LoopResult) -> RunSummary:  # from the finished log (run.partial)
                    import numpy as np

                    if counter is not None:
                        counter.stop()
                    return record.summary(run.partial, o.scenario, controller.gait.name, controller).updated(
                        seed=o.seed, terrain=str(world.terrain.spec), engine=world.name, engine_version=world.version,
                        engine_warnings=world.warnings,
                        versions={"shc": __version__, world.name: world.version, "numpy": np.__version__},
                        **(clock.statistics() if clock is not None else {}), **path_fields(),
                        **({"input": o.input_mode} if by_hand else {}),
                        **({"perception": o.perception} if o.perception != "off" else {}))

                def plot(folder: Path) -> None:
                    from shc_cli.plots import plot_simulation

                    plot_simulation(robot, record.plot_series(folder), folder, gait=controller.gait.name)

                try:
                    path, summary, _ = execute(loop, run, summarise, plot if o.plots else None)
                finally:
                    if live is not None:
                        live[0].close()
    finally:
        source.close()  # a keyboard's terminal leaves cbreak mode
    return RunResult(path, summary)


FLUSH_PACED = 20
"""A run paced to the wall clock flushes its log every this many cycles (0.2 s at 100 Hz): ``shc view --follow``
shows it that fresh."""
OnProgress = Callable[[int, int], None]
"""Told ``(walked cycles, cycles to walk)`` before the run, every :data:`PROGRESS_EVERY` walking cycles and
``(total, total)`` when the run ends (e.g. a progress bar)."""
PROGRESS_EVERY = 50




class _Progress:
    """Counts the walking cycles for an :data:`OnProgress` (an observer of the loop)."""

    def __init__(self, on_progress: OnProgress, total: int) -> None:
        self.on_progress, self.total, self.walked = on_progress, total, 0
        on_progress(0, total)

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        if command.state_request is None or out.robot_state.name == "RUNNING":
            self.walked += 1
            if self.walked % PROGRESS_EVERY == 0:
                self.on_progress(self.walked, self.total)
        return None

    def stop(self) -> None:
        self.on_progress(self.total, self.total)
