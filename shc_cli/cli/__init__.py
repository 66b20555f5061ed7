"""The ``shc`` command line: thin commands over spec → model → control → outputs.

Each command reads its files, builds the objects it needs and writes its outputs; heavy imports
(numpy, numba, matplotlib, pybullet) happen inside the commands so ``shc --help`` starts fast.
User errors (:class:`~shc_cli.errors.ShcError`) print one line per problem and exit with code 2.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated

import typer

from shc_cli import __version__
from shc_cli.cli.groups import export_app, hw_app, import_app
from shc_cli.cli.options import (
    OVERWRITE_HELP,
    VELOCITY_HELP,
    BagOption,
    CommandsOption,
    GaitOption,
    LiveOption,
    LivePortOption,
    PathOption,
    RobotArgument,
)
from shc_cli.domain.options import SIMULATE

app = typer.Typer(
    name="shc",
    help="OpenSHC's multilegged gait controller in Python: check robots, see workspaces, plan gaits, simulate, "
    "analyse, sweep.",
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)
app.add_typer(export_app, name="export")
app.add_typer(import_app, name="import")
app.add_typer(hw_app, name="hw", short_help="Bring a robot's servos up: find them (scan), check where they stand, "
              "jog each joint to confirm its direction and zero, emulate a bus.")


def _version(value: bool) -> None:
    if value:
        typer.echo(f"shc {__version__}")
        raise typer.Exit()


@app.callback()
def _main(
    debug: Annotated[bool, typer.Option("--debug", help="Show tracebacks instead of one-line errors.")] = False,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Also show info messages (state changes, "
                                                                   "set-up steps) on stderr.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="Show only errors on stderr (no notices or "
                                                               "warnings).")] = False,
    version: Annotated[
        bool, typer.Option("--version", callback=_version, is_eager=True, help="Print the version and exit.")
    ] = False,
) -> None:
    """OpenSHC's multilegged gait controller in Python (``--debug`` is read by :func:`main`)."""
    from shc_cli.events import configure_terminal

    del debug  # read by main() before the command runs (tracebacks are its business)
    configure_terminal("quiet" if quiet else "verbose" if verbose else "normal")


@app.command()
def validate(
    files: Annotated[
        list[str], typer.Argument(help="Robot, gait, auto-pose, sweep, study or plan-script files (paths or bundled "
                                       "names); each is checked as what it is.", metavar="FILE...")
    ],
    show: Annotated[bool, typer.Option("--show", help="Print each robot fully expanded, as TOML.")] = False,
) -> None:
    """Check shc files: robots (schema, limits, reachability, gait fit), gaits, auto-pose sets, plan scripts, and
    sweeps and studies with every robot variant they would run. One line per problem."""
    from shc_cli.commands.validate import run_validate

    run_validate(files, show=show)


@app.command()
def workspace(
    robot: RobotArgument = "bullet",
    gait: GaitOption = None,
    step_frequency: Annotated[
        float | None, typer.Option(help="Step frequency [Hz] (default: the robot's).")
    ] = None,
    bearings: Annotated[int, typer.Option(help="Search directions; 8 = OpenSHC's 45° steps.")] = 8,
    volumetric: Annotated[bool, typer.Option(help="Search a stack of planes (rough-terrain mode).")] = False,
    out: Annotated[Path | None, typer.Option(help="Write workspace.csv, limits.csv and workspace.png here.")] = None,
    json_output: Annotated[bool, typer.Option("--json", help="Print one JSON object and nothing else.")] = False,
    overwrite: Annotated[bool, typer.Option(help="Replace existing output files at --out.")] = False,
) -> None:
    """Per-leg workspaces, the common walkspace and speed/acceleration limits (paper Table II, Fig. 13)."""
    from shc_cli.commands.workspace import run_workspace

    run_workspace(robot, gait, step_frequency, bearings, volumetric, out, json_output, overwrite)


@app.command()
def plan(
    robot: RobotArgument = "bullet",
    gait: GaitOption = None,
    velocity: Annotated[
        str, typer.Option(help=VELOCITY_HELP)
    ] = "1,0,0",
    duration: Annotated[float | None, typer.Option(help="Seconds to run after start-up (default 10).")] = None,
    commands: CommandsOption = None,
    path: PathOption = None,
    out: Annotated[Path | None, typer.Option(help="Run directory (default runs/<timestamp>-plan).")] = None,
    plots: Annotated[bool, typer.Option(help="Write gait.png, tips.png and joints.png.")] = True,
    bag: BagOption = None,
    video: Annotated[Path | None, typer.Option(help="Also render the finished run to FILE.mp4 or FILE.gif (as shc "
                                                    "render with its defaults).", metavar="FILE")] = None,
    overwrite: Annotated[bool, typer.Option(help=OVERWRITE_HELP)] = False,
    live: LiveOption = False,
    live_port: LivePortOption = 8765,
    realtime: Annotated[bool, typer.Option(help="Pace the run to the wall clock.")] = False,
    fail_leg: Annotated[list[str] | None, typer.Option(metavar="LEG[:MODE][@T]", help=SIMULATE["fail_leg"].help)]
    = None,
) -> None:
    """Run the controller kinematically through start-up and a command timeline; log joints, tips, body."""
    from shc_cli.loop.gc_pause import paused

    with paused():  # no garbage collection in the set-up's imports and the figures (the run loop collects)
        from shc_cli.commands.plan import run_plan
        from shc_cli.commands.run_outputs import check_outputs, finish_outputs

        check_outputs(bag, video, overwrite)
        run_plan(robot, gait, velocity, duration, commands, out, plots,
                 after=lambda run: finish_outputs(run, bag, video), overwrite=overwrite, live=live,
                 live_port=live_port, realtime=realtime, path=path,
                 fail_leg=",".join(fail_leg) if fail_leg else None)


@app.command()
def simulate(
    robot: RobotArgument = "bullet",
    gait: GaitOption = None,
    velocity: Annotated[str, typer.Option(help=VELOCITY_HELP)] = "1,0,0",
    duration: Annotated[float | None, typer.Option(help=SIMULATE["duration"].cli_help)] = None,
    commands: CommandsOption = None,
    path: PathOption = None,
    terrain: Annotated[
        str, typer.Option(help="flat, ramp:DEG, blocks[:LOW,HIGH[,SIZE]], stairs[-down]:RISE,RUN, "
                               "heightfield:FILE[,SCALE] or slope|steps|obstacles|stones|gaps:D (docs/terrains.md)")
    ] = "flat",
    scenario: Annotated[str, typer.Option(help="WG walk ground, SG stance ground, WA walk air, SA stance air.")] = "WG",
    physics_rate: Annotated[float, typer.Option(help=SIMULATE["physics_rate"].cli_help)] = 400.0,
    friction: Annotated[float, typer.Option(help=SIMULATE["friction"].cli_help)] = 0.9,
    restitution: Annotated[float, typer.Option(help=SIMULATE["restitution"].cli_help)] = 0.0,
    seed: Annotated[int, typer.Option(help=SIMULATE["seed"].cli_help)] = 0,
    imu_noise: Annotated[float, typer.Option(help=SIMULATE["imu_noise"].cli_help)] = 0.0,
    imu_yaw_bias: Annotated[float, typer.Option(help=SIMULATE["imu_yaw_bias"].cli_help)] = 0.0,
    start: Annotated[str, typer.Option(help="Spawn pose: unpacked or packed.")] = "unpacked",
    stand: Annotated[
        bool | None,
        typer.Option("--stand/--ground", help="Start up held at standing height on a stand (as OpenSHC's Gazebo "
                     "launch) that is removed when the robot runs, or on the ground [default: start_up.simulation].",
                     show_default=False),
    ] = None,
    posture: Annotated[
        str | None, typer.Option(help="ATHENA posture control with gains, e.g. kz=0.8,ka=0.6,kb=0 (plane=...).")
    ] = None,
    imu_posing: Annotated[
        bool | None, typer.Option("--imu-posing/--no-imu-posing", help="OpenSHC IMU levelling [default: robot file].",
                                  show_default=False)
    ] = None,
    inclination: Annotated[
        str | None, typer.Option(help="Inclination posing: off, openshc or support_centroid [default: robot file].")
    ] = None,
    admittance: Annotated[
        bool | None, typer.Option("--admittance/--no-admittance", help="Admittance control [default: robot file].",
                                  show_default=False)
    ] = None,
    out: Annotated[Path | None, typer.Option(help="Run directory (default runs/<timestamp>-simulate).")] = None,
    plots: Annotated[bool, typer.Option(help="Write trajectory.png, power.png and contacts.png.")] = True,
    gui: Annotated[bool, typer.Option(help="Open the PyBullet GUI (needs a display).")] = False,
    bag: BagOption = None,
    fail_leg: Annotated[list[str] | None, typer.Option(metavar="LEG[:MODE][@T]", help=SIMULATE["fail_leg"].help)]
    = None,
    fail_on_fall: Annotated[bool, typer.Option(help="Exit with code 4 when the robot fell.")] = False,
    engine: Annotated[str, typer.Option(help="Physics engine: mujoco or pybullet.")] = "mujoco",
    video: Annotated[Path | None, typer.Option(help="Also render the finished run to FILE.mp4 or FILE.gif (as shc "
                                                    "render with its defaults).", metavar="FILE")] = None,
    overwrite: Annotated[bool, typer.Option(help=OVERWRITE_HELP)] = False,
    live: LiveOption = False,
    live_port: LivePortOption = 8765,
    realtime: Annotated[bool, typer.Option(help="Pace the simulation to the wall clock.")] = False,
    input_mode: Annotated[str, typer.Option("--input", help="timeline (--velocity/--commands), commands:FILE, or "
                                                            "driven by hand in real time (implies --realtime): stdin "
                                                            "(JSON lines), keyboard, gamepad[:DEVICE].")]
    = "timeline",
    watchdog: Annotated[float, typer.Option(help=SIMULATE["watchdog"].cli_help)] = 0.5,
    policy: Annotated[Path | None, typer.Option(help=SIMULATE["policy"].cli_help, metavar="FILE")] = None,
    perception: Annotated[str, typer.Option(help=SIMULATE["perception"].help)] = "off",
) -> None:
    """Run the controller on the robot in physics (MuJoCo; PyBullet with --engine): terrains, servos, power, CoT."""
    from shc_cli.loop.gc_pause import paused

    with paused():  # no garbage collection in the set-up's imports and the figures (the run loop collects)
        from shc_cli.commands.run_outputs import check_outputs, finish_outputs
        from shc_cli.commands.simulate import run_simulate
        from shc_cli.domain.config import SimulationConfig

        check_outputs(bag, video, overwrite)
        options = SimulationConfig(robot=robot, gait=gait, velocity=velocity, duration=duration, commands=commands,
                                   path=path, out=out, plots=plots, terrain=terrain, scenario=scenario,
                                   physics_rate=physics_rate,
                                   friction=friction, restitution=restitution, seed=seed, imu_noise=imu_noise,
                                   imu_yaw_bias=imu_yaw_bias,
                                   start=start, gui=gui, stand=stand, posture=posture, imu_posing=imu_posing,
                                   inclination=inclination, admittance=admittance,
                                   fail_leg=",".join(fail_leg) if fail_leg else None, fail_on_fall=fail_on_fall,
                                   overwrite=overwrite, engine=engine, live=live, live_port=live_port,
                                   realtime=realtime, input_mode=input_mode, watchdog=watchdog, policy=policy,
                                   perception=perception)
        run_simulate(options, after=lambda run: finish_outputs(run, bag, video))


@app.command("run-hw")
def run_hw(
    robot: Annotated[str, typer.Argument(help="Robot file or bundled robot name (its [hardware] servo table).")],
    port: Annotated[list[str], typer.Option(metavar="DEV", help="Serial device of a servo bus, e.g. /dev/ttyUSB0; "
                                                                "once per bus, bus 0 first.")],
    baud: Annotated[int | None, typer.Option(help="Baud rate [default: hardware.baud].")] = None,
    gait: GaitOption = None,
    input_mode: Annotated[str, typer.Option("--input", help="timeline (--velocity/--commands), commands:FILE, "
                                                            "stdin (JSON lines), keyboard, gamepad[:DEVICE].")]
    = "timeline",
    velocity: Annotated[str, typer.Option(help=VELOCITY_HELP)] = "0,0,0",
    duration: Annotated[float | None, typer.Option(help="Seconds to run after start-up (default 20).")] = None,
    commands: CommandsOption = None,
    path: PathOption = None,
    out: Annotated[Path | None, typer.Option(help="Run directory (default runs/<timestamp>-run-hw).")] = None,
    dry_run: Annotated[bool, typer.Option(help="Everything except current-limit, torque-enable and goal writes.")]
    = False,
    stop_state: Annotated[str, typer.Option(help="State to shut down to after Ctrl-C or the input's end: packed, "
                                                 "ready or running (just stop walking).")] = "packed",
    on_fault: Annotated[str, typer.Option(help="On a servo fault: hold, torque-off, or adapt (fail its leg, walk on "
                                               "on the others; exit 5).")] = "torque-off",
    on_stop: Annotated[str, typer.Option(help="After the controlled stop and shut-down: hold or torque-off.")]
    = "torque-off",
    profile_velocity: Annotated[bool, typer.Option(help="Also write Profile Velocity: the servos interpolate "
                                                        "between goals.")] = False,
    watchdog: Annotated[float, typer.Option(help="stdin: seconds without a line before the velocity goes to 0.")]
    = 0.5,
    overwrite: Annotated[bool, typer.Option(help=OVERWRITE_HELP)] = False,
    live: LiveOption = False,
    live_port: LivePortOption = 8765,
    missed_reads_fault: Annotated[int | None, typer.Option(
        metavar="N", help="Consecutive cycles a servo may miss its reading (its last one stands in) before that is "
                          "a fault [default: hardware.missed_reads_fault, 3].")] = None,
    policy: Annotated[Path | None, typer.Option(
        metavar="FILE", help="A gait or residual policy file (.npz) acting on the controller while it walks; the "
                             "start-up, the stop, the clamps and the fault checks are unchanged (docs/gym.md).")]
    = None,
    fail_leg: Annotated[list[str] | None, typer.Option(metavar="LEG[:MODE][@T]", help=SIMULATE["fail_leg"].help)]
    = None,
) -> None:
    """Run the controller on the robot's servos (Dynamixel Protocol 2.0 or 1.0, Feetech STS), safely."""
    from shc_cli.commands.run_hw import run_hw as run
    from shc_cli.domain.hardware import HardwareConfig

    run(HardwareConfig(robot=robot, ports=port, baud=baud, gait=gait, on_fault=on_fault, on_stop=on_stop,
                       stop_state=stop_state, input_mode=input_mode, velocity=velocity, duration=duration,
                       commands=commands, path=path, out=out, dry_run=dry_run, profile_velocity=profile_velocity,
                       watchdog=watchdog, overwrite=overwrite, live=live, live_port=live_port,
                       missed_reads_fault=missed_reads_fault, policy=policy,
                       fail_leg=",".join(fail_leg) if fail_leg else None))


@app.command()
def ros(
    robot: Annotated[str, typer.Argument(help="Robot file or bundled robot name, or 'server': OpenSHC's parameters "
                                              "from the parameter server (/syropod, as its launch files load them).")]
    = "bullet",
    backend: Annotated[str, typer.Option(help="none: outputs only, as OpenSHC (a hardware node of yours reads "
                                              "them); mujoco or pybullet: the robot simulated in real time, its "
                                              "sensors published (/joint_states, /imu/data); bus: the robot's "
                                              "servos (--port), with run-hw's checks and safe stop.")] = "none",
    name: Annotated[str, typer.Option(help="Node name.")] = "/shc",
    master: Annotated[str | None, typer.Option(help="ROS master URI (default: $ROS_MASTER_URI).")] = None,
    duration: Annotated[float | None, typer.Option(help="Stop after this many seconds (default: until Ctrl-C).")]
    = None,
    individual: Annotated[bool, typer.Option(help="Publish /<LEG>_<joint>_joint/command (Float64, + offset).")]
    = True,
    combined: Annotated[bool, typer.Option(help="Publish /desired_joint_states.")] = True,
    out: Annotated[Path | None, typer.Option(help="Run directory (default runs/<timestamp>-ros).")] = None,
    namespace: Annotated[str, typer.Option(help="Parameter tree read for the robot 'server'.")] = "/syropod",
    overwrite: Annotated[bool, typer.Option(help=OVERWRITE_HELP)] = False,
    live: LiveOption = False,
    live_port: LivePortOption = 8765,
    path: PathOption = None,
    port: Annotated[list[str] | None, typer.Option(metavar="DEV", help="--backend bus: serial device of a servo "
                                                                       "bus; once per bus, bus 0 first.")] = None,
    baud: Annotated[int | None, typer.Option(help="--backend bus: baud rate [default: hardware.baud].")] = None,
    dry_run: Annotated[bool, typer.Option(help="--backend bus: no current-limit, torque-enable or goal writes.")]
    = False,
    stop_state: Annotated[str, typer.Option(help="--backend bus: state to shut down to when the node stops.")]
    = "packed",
    on_fault: Annotated[str, typer.Option(help="--backend bus: on a servo fault, hold or torque-off.")]
    = "torque-off",
    on_stop: Annotated[str, typer.Option(help="--backend bus: after the shut-down, hold or torque-off.")]
    = "torque-off",
    joint_states_timeout: Annotated[float, typer.Option(help="--backend none: seconds to wait at start-up for "
                                                             "/joint_states to give every joint, as OpenSHC (0: do "
                                                             "not wait).")] = 10.0,
) -> None:
    """Run as OpenSHC's ROS 1 node: its topics, messages and parameters, driven by syropod_remote."""
    from shc_cli.commands.ros import run_ros
    from shc_cli.domain.ros_node import NodeConfig

    run_ros(NodeConfig(robot=robot, backend=backend, name=name, master_uri=master, duration=duration, out=out,  # type: ignore[arg-type]
                       individual=individual, combined=combined, overwrite=overwrite, namespace=namespace,
                       live=live, live_port=live_port, path=path, ports=tuple(port or ()), baud=baud,
                       dry_run=dry_run, stop_state=stop_state, on_fault=on_fault, on_stop=on_stop,
                       joint_states_timeout=joint_states_timeout))


@app.command()
def ros2(
    robot: Annotated[str, typer.Argument(help="Robot file or bundled robot name.")] = "bullet",
    backend: Annotated[str, typer.Option(help="none, mujoco, pybullet or bus: as shc ros.")] = "none",
    name: Annotated[str, typer.Option(help="Node name (/NAMESPACE/NAME sets the namespace).")] = "/shc",
    duration: Annotated[float | None, typer.Option(help="Stop after this many seconds (default: until Ctrl-C).")]
    = None,
    params_file: Annotated[Path | None, typer.Option(help="ROS 2 parameter file (NODE: ros__parameters: ...) "
                                                          "with start values of the dynamic parameters.")] = None,
    individual: Annotated[bool, typer.Option(help="Publish /<LEG>_<joint>_joint/command (Float64, + offset).")]
    = True,
    combined: Annotated[bool, typer.Option(help="Publish /desired_joint_states.")] = True,
    out: Annotated[Path | None, typer.Option(help="Run directory (default runs/<timestamp>-ros).")] = None,
    overwrite: Annotated[bool, typer.Option(help=OVERWRITE_HELP)] = False,
    live: LiveOption = False,
    live_port: LivePortOption = 8765,
    path: PathOption = None,
    port: Annotated[list[str] | None, typer.Option(metavar="DEV", help="--backend bus: serial device of a servo "
                                                                       "bus; once per bus, bus 0 first.")] = None,
    baud: Annotated[int | None, typer.Option(help="--backend bus: baud rate [default: hardware.baud].")] = None,
    dry_run: Annotated[bool, typer.Option(help="--backend bus: no current-limit, torque-enable or goal writes.")]
    = False,
    stop_state: Annotated[str, typer.Option(help="--backend bus: state to shut down to when the node stops.")]
    = "packed",
    on_fault: Annotated[str, typer.Option(help="--backend bus: on a servo fault, hold or torque-off.")]
    = "torque-off",
    on_stop: Annotated[str, typer.Option(help="--backend bus: after the shut-down, hold or torque-off.")]
    = "torque-off",
    joint_states_timeout: Annotated[float, typer.Option(help="--backend none: seconds to wait at start-up for "
                                                             "/joint_states to give every joint, as OpenSHC (0: do "
                                                             "not wait).")] = 10.0,
) -> None:
    """Run as OpenSHC's node on ROS 2 (the ros2 extra): shc ros's topics under ROS 2 types, ROS 2 parameters."""
    from shc_cli.commands.ros2 import run_ros2
    from shc_cli.domain.ros_node import NodeConfig

    run_ros2(NodeConfig(robot=robot, backend=backend, name=name, duration=duration, out=out,  # type: ignore[arg-type]
                        individual=individual, combined=combined, overwrite=overwrite, live=live,
                        live_port=live_port, path=path, ports=tuple(port or ()), baud=baud, dry_run=dry_run,
                        stop_state=stop_state, on_fault=on_fault, on_stop=on_stop,
                        joint_states_timeout=joint_states_timeout), params_file)


@app.command()
def analyze(
    runs: Annotated[list[Path], typer.Argument(help="Run directories from plan or simulate.")],
    json_output: Annotated[bool, typer.Option("--json", help="Print JSON only (an object, or a list for several).")]
    = False,
    out: Annotated[Path | None, typer.Option(help="Write analysis.json and the plots here.")] = None,
    skip: Annotated[float, typer.Option(help="Seconds of RUNNING to leave out at the start of the window.")] = 0.0,
    steady: Annotated[bool, typer.Option(help="Only cycles whose desired velocity held for a whole gait cycle.")]
    = False,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing analysis.json and plots at --out.")] = False,
    reference: Annotated[Path | None, typer.Option(help="An intact run: report each run's speed along the "
                                                        "commanded heading retained vs its, and falls.")] = None,
) -> None:
    """Cost of transport, power, speed, duty factor, slip, stability margins and per-cycle posture of runs."""
    from shc_cli.commands.analyze import run_analyze

    run_analyze(runs, json_output, out, skip, steady, overwrite, reference)


@app.command()
def sweep(
    file: Annotated[Path, typer.Argument(help="Sweep file (TOML): a grid of simulations.")],
    workers: Annotated[int | None, typer.Option(help="Parallel runs (default: all cores).")] = None,
    executor: Annotated[str, typer.Option(help="local (worker processes) or dask.")] = "local",
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address (default: a LocalCluster).")] = None,
    out: Annotated[Path | None, typer.Option(help="Output directory (default runs/<sweep name>).")] = None,
    resume: Annotated[bool, typer.Option(help="Continue a sweep: finished runs are read, not re-run.")] = False,
    overwrite: Annotated[bool, typer.Option(help="Delete an existing sweep output at --out first and run it all "
                                                 "again (only shc's own outputs).")] = False,
    engine: Annotated[
        str | None, typer.Option(help="Physics engine (mujoco or pybullet) of runs the sweep file does not set.")
    ] = None,
) -> None:
    """Run a grid of simulations in parallel and tabulate CoT, power, speed and stability per run."""
    from shc_cli.commands.sweep import run_sweep

    run_sweep(file, workers, executor, scheduler, out, resume, overwrite, engine)


@app.command()
def render(
    run: Annotated[Path, typer.Argument(help="Run directory (plan, simulate, run-hw) or a bag from export bag.")],
    out: Annotated[Path, typer.Option(help="Video file: FILE.mp4 (H.264) or FILE.gif.")],
    fps: Annotated[float, typer.Option(help="Frames per second of the video.")] = 25.0,
    size: Annotated[str, typer.Option(help="Frame size WIDTHxHEIGHT in pixels.")] = "960x540",
    camera: Annotated[str, typer.Option(help="follow (the body, from behind and above), fixed (the whole path) "
                                             "or top (from above, following).")] = "follow",
    speed: Annotated[float, typer.Option(help="Playback speed: 2 = twice real time.")] = 1.0,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing video at --out.")] = False,
) -> None:
    """Render a run headless to video: the robot, terrain and feet, with time, speeds and walk state over it."""
    from shc_cli.commands.render import run_render

    run_render(run, out, fps, size, camera, speed, overwrite)


@app.command()
def view(
    target: Annotated[str, typer.Argument(help="Robot file or bundled robot name, a run directory, or a bag.")],
    host: Annotated[str, typer.Option(help="Address to listen on. The default 127.0.0.1 serves this computer "
                                           "only; 0.0.0.0 serves anyone who can reach it on the network.")]
    = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Port to listen on.")] = 8080,
    follow: Annotated[bool, typer.Option(help="A run in progress (its --out, written as OUT.partial): follow it "
                                              "live as it is written, until it has finished.")] = False,
) -> None:
    """See a robot (joint sliders, body pose, workspaces) or replay a run in the browser; Ctrl-C stops it."""
    from shc_cli.commands.view import run_view

    run_view(target, host, port, follow)


@app.command()
def optimize(
    file: Annotated[Path, typer.Argument(help="Study file (TOML): search space, objectives, constraints.")],
    trials: Annotated[int | None, typer.Option(help="Trials to finish, earlier ones included (default: the "
                                               "study's `trials`, else 20).")] = None,
    workers: Annotated[int | None, typer.Option(help="Parallel runs (default: all cores).")] = None,
    executor: Annotated[str, typer.Option(help="local (worker processes) or dask.")] = "local",
    scheduler: Annotated[str | None, typer.Option(help="Dask scheduler address (default: a LocalCluster).")] = None,
    out: Annotated[Path | None, typer.Option(help="Output directory (default runs/<study name>).")] = None,
    resume: Annotated[bool, typer.Option(help="Continue a study from its storage: finished trials are kept.")] = False,
    overwrite: Annotated[bool, typer.Option(help="Delete an existing study output (shc's only) and start again.")]
    = False,
) -> None:
    """Multi-objective search (Optuna) of gait and robot parameters over simulated runs: Pareto front and robot
    files."""
    from shc_cli.commands.optimize import run_optimize

    run_optimize(file, trials, workers, executor, scheduler, out, resume, overwrite)


@app.command()
def fit(
    runs: Annotated[list[Path] | None, typer.Argument(
        help="Run directories (shc run-hw or shc simulate) of the robot.", metavar="RUN...", show_default=False)]
    = None,
    robot: Annotated[str, typer.Option(help="Robot file or bundled name whose [servo] values are the start.")]
    = "bullet",
    params: Annotated[str | None, typer.Option(help="[servo] parameters to fit, comma-separated (short names: gain, "
                                               "coulomb, viscous, holding, idle, kt, armature, …); default: "
                                               "position_p_gain, coulomb_friction, viscous_friction, holding_ratio, "
                                               "armature, idle_power, torque_constant.")] = None,
    engine: Annotated[str, typer.Option(help="Physics engine of the replays: mujoco or pybullet.")] = "mujoco",
    out: Annotated[Path | None, typer.Option(help="Output directory (default fits/<robot name>).")] = None,
    scenario: Annotated[str, typer.Option(help="Where a real robot's runs were recorded: SA, WA (body held in the "
                                          "air), SG, WG (on the ground), BENCH (servos turning only their rotors: "
                                          "off the robot, or the servo emulator); a simulated run's own is used.")]
    = "WG",
    by: Annotated[str, typer.Option(help="model: one fit of every servo; joint: one fit per joint name.")] = "model",
    max_evaluations: Annotated[int, typer.Option(help="The solver's budget of residual evaluations.")] = 30,
    seconds: Annotated[float | None, typer.Option(help="Use only the first this many seconds of each run.")] = None,
    plots: Annotated[bool, typer.Option(help="Write the measured-against-simulated figures.")] = True,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing fit output directory.")] = False,
    plan: Annotated[bool, typer.Option("--plan", help="Instead of fitting, write the recommended excitation: a plan "
                                       "script for run-hw --commands (stand, sway, walk at several step "
                                       "frequencies) to --out (default fit-plan.toml).")] = False,
) -> None:
    """Fit the robot's servo model ([servo]: gain, friction, holding ratio, armature, idle power, torque constant)
    to run logs by replaying their joint commands in the engine: robot.toml, fit.json and figures."""
    from shc_cli.commands.fit import run_fit, write_fit_plan

    if plan:
        write_fit_plan(runs or [], robot, out, overwrite)
        return
    run_fit(runs or [], robot, params, engine, out, scenario.upper(), by, max_evaluations, seconds, plots, overwrite)


@app.command()
def replay(
    source: Annotated[Path, typer.Argument(help="A recording prefix DIR/NAME (NAME_joints.csv.gz, NAME_tips.csv.gz, "
                                                "NAME_body.csv.gz), a ROS 1 .bag or a ROS 2 bag directory.")],
    robot: Annotated[str, typer.Option(help="Robot file or bundled robot name: the robot that was recorded.")],
    gait: GaitOption = None,
    json_output: Annotated[bool, typer.Option("--json", help="Print one JSON object and nothing else.")] = False,
    out: Annotated[Path | None, typer.Option(help="Write differences.csv (per cycle) and differences.png here.")]
    = None,
    tolerance_joints: Annotated[
        float | None, typer.Option(metavar="RAD", help="Exit 1 if the joints differ by more than this [rad].")
    ] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace existing differences files at --out.")] = False,
) -> None:
    """Replay a recorded OpenSHC run through shc's controller; the worst difference of joints, tips, velocity."""
    from shc_cli.commands.replay import run_replay

    code = run_replay(source, robot, gait, json_output, out, tolerance_joints, overwrite)
    if code:
        raise typer.Exit(code)


@app.command()
def schema(
    kind: Annotated[str, typer.Argument(help="'robot', 'gait' or 'summary'.")],
) -> None:
    """Print the JSON Schema of robot or gait files (for editor completion) or of a run's summary.json."""
    from shc_cli.commands.schema import print_schema

    print_schema(kind)


@app.command()
def warmup() -> None:
    """Compile the kinematics and walk kernels into numba's cache now (the set-up command runs it once)."""
    from shc_cli.commands.warmup import run_warmup

    run_warmup()


def _whole_short_help(typer_app: typer.Typer) -> None:
    """``shc --help`` lists each command with the whole first paragraph of its docstring, wrapped, instead of
    click's 45-character cut ending in "…" (a command's own ``--help`` is unchanged)."""
    for info in typer_app.registered_commands:
        doc = info.help or (info.callback.__doc__ if info.callback is not None else None)
        if info.short_help is None and doc:
            info.short_help = " ".join(doc.strip().split("\n\n")[0].split())
    for group in typer_app.registered_groups:
        if group.typer_instance is not None:
            _whole_short_help(group.typer_instance)


_whole_short_help(app)


def _app_for(args: list[str]) -> typer.Typer:
    """The app that runs ``args``: when they name one of the top-level commands, the app with that command alone
    (typer builds the options of every command an app holds before it parses: 0.02 s of each run); otherwise — the
    list of commands, a group (``shc export …``), an unknown name — the whole app. The options before a command
    (``--debug``) are flags, so the command is the first argument that is not one."""
    import copy

    name = next((arg for arg in args if not arg.startswith("-")), None)
    commands = [info for info in app.registered_commands if info.callback is not None
                and (info.name or info.callback.__name__.lower().replace("_", "-")) == name]
    if not commands:
        return app
    alone = copy.copy(app)
    alone.registered_commands, alone.registered_groups = commands, []
    return alone


def main() -> None:
    """Console entry point: user errors become one line and exit code 2, an interrupted command one line and 130 or
    143 (:mod:`shc_cli.commands.exits`); no traceback unless --debug."""
    from shc_cli.commands.exits import run_command
    from shc_cli.loop.gc_pause import no_collection_at_exit

    no_collection_at_exit()  # the interpreter's last garbage collection was 0.17 s of a simulation's command
    run_command(_app_for(sys.argv[1:]), debug="--debug" in sys.argv[1:])

