"""One kinematic run (``shc plan``): the controller through start-up and a command timeline on the kinematic
backend (commanded joints fed back), logged and summarised in a run directory. Never prints."""

from __future__ import annotations

import time
from pathlib import Path

from shc_cli.domain.result import RunResult


def plan(robot: str = "bullet", gait: str | None = None, velocity: str = "1,0,0", duration: float | None = None,
         commands: Path | None = None, out: Path | None = None, plots: bool = True,
         overwrite: bool = False) -> RunResult:
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
    """
    from shc_cli.backends.kinematic import KinematicBackend
    from shc_cli.control.controller import Controller
    from shc_cli.loop.input_sources import TimelineInput
    from shc_cli.loop.plan_summary import PlanRecord, plan_summary
    from shc_cli.loop.run_inputs import load_inputs
    from shc_cli.loop.run_loop import RunLoop, StartUp
    from shc_cli.loop.runlog import RunWriter, default_run_directory
    from shc_cli.loop.session import execute

    inputs = load_inputs(robot, gait, velocity, duration, commands, default_s=10.0, check_fit=True)
    model = inputs.robot
    directory = out or default_run_directory("plan")
    controller = Controller(model, inputs.gait, pose_sets=inputs.pose_sets)
    writer = RunWriter(directory, model, overwrite)
    writer.write_robot(model)
    record = PlanRecord(controller)
    start_up = StartUp.of(model)
    loop = RunLoop(controller, KinematicBackend(), TimelineInput(inputs.commands()), writer,
                   start_up, observers=[record], flush_every=500)
    started = time.perf_counter()

    def plot(folder: Path) -> None:
        from shc_cli.plots import plot_plan

        plot_plan(model, record.outputs, folder, gait=" → ".join(record.gaits) or inputs.gait.name)

    path, summary, _ = execute(loop, writer, lambda _: plan_summary(model, controller, record,
                                                                     time.perf_counter() - started, writer.partial),
                               plot if plots else None)
    return RunResult(path, summary)
