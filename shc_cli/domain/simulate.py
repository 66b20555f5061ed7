"""One simulation: the controller driving the robot in physics (PyBullet or MuJoCo) through the one run loop,
logged and summarised in a run directory. Never prints; the command prints the summary line."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.domain.config import SimulationConfig
from shc_cli.domain.live import live_observer, wall_clock
from shc_cli.domain.result import RunResult
from shc_cli.loop.assembly import OnProgress as OnProgress

if TYPE_CHECKING:
    from shc_cli.backends.engine import Engine, Reading
    from shc_cli.control.controller import Controller
    from shc_cli.control.leg_failure import LegFailure
    from shc_cli.control.speed_shares import ShareSource
    from shc_cli.loop.assembly import Assembly, Finished, RunSpec
    from shc_cli.loop.physics_summary import PhysicsRecord
    from shc_cli.loop.run_inputs import RunInputs
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
    at = adapted.failure.at_s
    event(log, logging.INFO, "leg_failure", "failed legs %s%s: walking on %s with a generated gait (%s, duty "
          "factor %.3f, static margin %.3f m at a %.3f m stride, body shifted %+.3f, %+.3f m)",
          ", ".join(map(str, failed)), "" if at is None else f" (declared {at:g} s after walking starts)",
          ", ".join(leg for leg in robot.legs if leg not in adapted.failure.legs),
          " → ".join("+".join(group) for group in planned.groups), planned.duty_factor, planned.margin_m,
          adapted.stride_m, planned.body_shift_m[0][0], planned.body_shift_m[0][1], terminal=False)
    if at is not None:  # the intact robot walks until the failure is declared (the controller then re-plans)
        return robot, gait, adapted.failure
    return adapted.robot, adapted.gait, adapted.failure


def speed_source(robot: Robot, failure: LegFailure | None) -> ShareSource | None:
    """The verified speed shares of ``robot`` unless legs have failed from the start (then OpenSHC's limits of
    the walking legs' walkspace; a failure declared mid-walk drops the shares when it is declared)."""
    from shc_cli.control.verified_limits import source_for

    return source_for(robot) if failure is None or failure.at_s is not None else None


def simulate(config: SimulationConfig | None = None, progress: OnProgress | None = None) -> RunResult:
    """Load, simulate through the one loop, log; returns the run directory and its summary (``progress``: told the
    walking cycles done, :data:`OnProgress`).

    Raises:
        ShcError: bad input (one line), before anything is written.
    """
    from shc_cli.errors import Issue, SpecError
    from shc_cli.events import event
    from shc_cli.loop.assembly import assemble
    from shc_cli.loop.input_choice import commands_file
    from shc_cli.loop.run_inputs import load_inputs

    c = config or SimulationConfig()
    check_display(c.gui)
    for warning in c.warnings():  # legal but degenerate values (friction 0)
        event(log, logging.WARNING, "degenerate_option", "warning: %s", warning)
    if c.path is not None and c.input_mode != "timeline":
        raise SpecError([Issue(None, None, "--path", f"--path and --input {c.input_mode} both give the run's input",
                               "drop --input (a path is followed by itself)")])
    inputs = load_inputs(c.robot, c.gait, c.velocity, c.duration, commands_file(c.input_mode, c.commands),
                         default_s=20.0, walking=c.walking, robot_change=c.apply_switches, path=c.path)
    return RunResult(*assemble(lambda parts: _simulation(parts, c, inputs, progress)).pair)


def _simulation(parts: Assembly, c: SimulationConfig, inputs: RunInputs, progress: OnProgress | None
                ) -> RunSpec[Reading]:
    """The simulation's run specification: the world and the backend, the controller from its start joints, the
    log, the fall detector (:class:`~shc_cli.loop.physics_summary.PhysicsRecord`) and its summary."""
    from shc_cli.backends.simulated import SimulatedBackend, open_world
    from shc_cli.control.controller import Controller
    from shc_cli.loop.assembly import Progress, RunSpec
    from shc_cli.loop.input_choice import is_live, open_input
    from shc_cli.loop.path_input import keep_path
    from shc_cli.loop.physics_summary import PhysicsRecord
    from shc_cli.loop.policy.drive import PolicyDrive
    from shc_cli.loop.run_loop import Observer, StartUp
    from shc_cli.record.runlog import LogRecorder, RunDirectory, default_run_directory

    by_hand = is_live(c.input_mode)
    robot, gait, failure = failed_legs(inputs.robot, inputs.gait, c.fail_leg, c.velocity)
    drive = None if c.policy is None else PolicyDrive.load(c.policy, robot)
    options = c.engine_options(robot)
    directory = c.out or default_run_directory("simulate")
    source = parts.closing(open_input(c.input_mode, robot, gait, inputs.commands(), c.watchdog))  # before the rest
    run = parts.enter(RunDirectory(directory, c.overwrite))  # refuses an existing --out before the physics opens
    world = open_world(robot, options)
    backend = parts.enter(SimulatedBackend(robot, world))
    controller = Controller(robot, gait, joints=backend.start(), pose_sets=inputs.pose_sets,
                            failure=failure, speed_shares=speed_source(robot, failure))
    run.write_robot(robot)
    if inputs.path is not None:
        source.close()
        source = inputs.source(controller)
    path_fields = keep_path(source, run.partial)
    record = PhysicsRecord(robot, backend, c.airborne)
    observers: list[Observer[Reading]] = [record]
    if failure is not None and failure.at_s is not None:
        from shc_cli.loop.leg_fault import FailureEvents

        observers.append(FailureEvents(controller))
    if c.perception == "rays":  # the depth sensor: an observer whose map the commands carry
        from shc_cli.errors import Issue, SpecError
        from shc_cli.loop.perception import RayCaster, RayPerception

        if not isinstance(world, RayCaster):
            raise SpecError([Issue(None, None, "--perception", f"the {world.name} engine casts no rays",
                                   "use --engine mujoco or pybullet, or --perception off")])
        eyes = RayPerception(robot, world, c.seed)
        observers.insert(0, eyes)
        source = eyes.wrap(source)

    def summarise(finished: Finished) -> RunSummary:  # from the finished log
        return _summary(record, finished, c, controller, world, by_hand)

    def plot(folder: Path) -> None:
        from shc_cli.plots import plot_simulation

        plot_simulation(robot, record.plot_series(folder), folder, gait=controller.gait.name)

    if drive is not None:
        source = drive.source(source)
    return RunSpec(controller, backend, source, LogRecorder(run, robot, backend), StartUp.of(robot), run, summarise,
                   observers=observers, progress=None if progress is None or by_hand else Progress(progress,
                                                                                                  inputs.cycles),
                   live=live_observer(parts, c.live, c.live_port, robot, controller, sensors=True),
                   pacing=wall_clock(robot) if c.paced else None, path_fields=path_fields,
                   plot=plot if c.plots else None, flush_every=FLUSH_PACED if c.paced else 200,
                   on_loop=None if drive is None else drive.join)


def _summary(record: PhysicsRecord, finished: Finished, c: SimulationConfig, controller: Controller,
             world: Engine, by_hand: bool) -> RunSummary:
    """The simulation's summary, made once from the finished log: the physics record's figures, the world, the
    seed and versions, and the fields every run shares."""
    import numpy as np

    from shc_cli.version import __version__

    return record.summary(finished.directory, c.scenario, controller.gait.name, controller, {
        "seed": c.seed, "terrain": str(world.terrain.spec), "engine": world.name, "engine_version": world.version,
        "engine_warnings": world.warnings,
        "versions": {"shc": __version__, world.name: world.version, "numpy": np.__version__},
        **({"input": c.input_mode} if by_hand else {}),
        **({"perception": c.perception} if c.perception != "off" else {}), **finished.shared})


FLUSH_PACED = 20
"""A run paced to the wall clock flushes its log every this many cycles (0.2 s at 100 Hz): ``shc view --follow``
shows it that fresh."""
