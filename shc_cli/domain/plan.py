"""One kinematic run (``shc plan``): the controller through start-up and a command timeline on the kinematic
backend (commanded joints fed back), logged and summarised in a run directory. Never prints."""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

from shc_cli.domain.live import live_observer, wall_clock
from shc_cli.domain.result import RunResult

if TYPE_CHECKING:
    from shc_cli.loop.assembly import Assembly, Finished, RunSpec
    from shc_cli.record.summary import RunSummary


def plan(robot: str = "bullet", gait: str | None = None, velocity: str = "1,0,0", duration: float | None = None,
         commands: Path | None = None, out: Path | None = None, plots: bool = True,
         overwrite: bool = False, live: bool = False, live_port: int = 8765, realtime: bool = False,
         path: Path | None = None, fail_leg: str | None = None) -> RunResult:
    """Load, run through the one loop on the kinematic backend, log; returns the run directory and its summary
    (``complete`` false when a signal stopped it).

    Args:
        robot: robot file or bundled name.
        gait: gait file or name (None: the robot's).
        velocity: constant velocity input ``"VX,VY,WZ"`` in the robot's input mode.
        duration: seconds to run after start-up (None: a timeline's length + 1 s, or 10 s) [s].
        commands: command timeline (CSV or TOML plan script).
        out: run directory (None: ``runs/<timestamp>-plan``).
        plots: write gait.png, tips.png and joints.png.
        overwrite: replace an existing run directory at ``out`` when the run finishes.
        live: stream the run while it happens on a Foxglove server on 127.0.0.1:``live_port`` (0: any free port).
        realtime: pace the run to the wall clock.
        path: a path file the follower walks (instead of ``velocity`` or ``commands``), steering by the odometry.
        fail_leg: failed legs, ``LEG[:MODE]`` comma-separated (:func:`shc_cli.domain.simulate.failed_legs`).
    """
    from shc_cli.loop.assembly import assemble
    from shc_cli.loop.run_inputs import load_inputs

    inputs = load_inputs(robot, gait, velocity, duration, commands, default_s=10.0, check_fit=True, path=path)

    def build(parts: Assembly) -> RunSpec[None]:
        from shc_cli.backends.kinematic import KinematicBackend
        from shc_cli.control.controller import Controller
        from shc_cli.domain.simulate import failed_legs, speed_source
        from shc_cli.loop.assembly import RunSpec
        from shc_cli.loop.path_input import keep_path
        from shc_cli.loop.plan_summary import PlanRecord, plan_summary
        from shc_cli.loop.run_loop import Observer, StartUp
        from shc_cli.record.runlog import RunWriter, default_run_directory

        model, walked_gait, failure = failed_legs(inputs.robot, inputs.gait, fail_leg, velocity)
        directory = out or default_run_directory("plan")
        controller = Controller(model, walked_gait, pose_sets=inputs.pose_sets, failure=failure,
                                speed_shares=speed_source(model, failure))
        writer = RunWriter(directory, model, overwrite)
        parts.enter(writer)  # its tables closed and its signals restored also when the run raises
        writer.write_robot(model)
        source = inputs.source(controller)
        path_fields = keep_path(source, writer.partial)
        record = PlanRecord(controller)
        observers: list[Observer[None]] = [record]
        if failure is not None and failure.at_s is not None:
            from shc_cli.loop.leg_fault import FailureEvents

            observers.append(FailureEvents(controller))
        stream = live_observer(parts, live, live_port, model, controller, sensors=False)
        started = time.perf_counter()

        def plot(folder: Path) -> None:
            from shc_cli.plots import plot_plan

            plot_plan(model, record.outputs, folder, gait=" → ".join(record.gaits) or inputs.gait.name)

        def summarise(finished: Finished) -> RunSummary:
            return plan_summary(model, controller, record, time.perf_counter() - started, finished.directory,
                                finished.shared)

        return RunSpec(controller, KinematicBackend(), source, writer, StartUp.of(model), writer, summarise,
                       observers=observers, live=stream, pacing=wall_clock(model) if realtime else None,
                       path_fields=path_fields, plot=plot if plots else None, flush_every=500)

    return RunResult(*assemble(build).pair)
