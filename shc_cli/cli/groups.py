"""The ``shc`` command groups: ``shc export …``, ``shc import …`` and ``shc hw …`` (each a thin command over
:mod:`shc_cli.commands`, imported when it runs so ``shc --help`` starts fast)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from shc_cli.cli.options import RobotArgument

export_app = typer.Typer(help="Export robots and runs to other formats.", no_args_is_help=True)


@export_app.command("urdf")
def export_urdf(
    robot: RobotArgument = "bullet",
    out: Annotated[Path | None, typer.Option(help="Write the URDF here (default: print it).")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing file at --out.")] = False,
) -> None:
    """The physics model generated from the robot file, as URDF (what `simulate` loads)."""
    from shc_cli.commands.export import export_urdf as run

    run(robot, out, overwrite)


@export_app.command("bag")
def export_bag(
    run_dir: Annotated[Path, typer.Argument(help="Run directory from plan or simulate.", metavar="RUN")],
    format: Annotated[str, typer.Option("--format", help="mcap, sqlite3 (ROS 2) or ros1.")] = "mcap",
    out: Annotated[Path | None, typer.Option(help="Bag folder (mcap, sqlite3) or NAME.bag file (ros1) (default: "
                                                  "RUN_bag, RUN_bag_sqlite3 or RUN.bag).")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing bag at --out.")] = False,
) -> None:
    """Write a run as a ROS bag: joint states, tf, URDF, IMU, odometry, foot forces, OpenSHC LegState."""
    from shc_cli.commands.export import export_bag as run

    run(run_dir, format, out, overwrite)


import_app = typer.Typer(help="Import files of other tools.", no_args_is_help=True)


@import_app.command("openshc")
def import_openshc(
    robot: Annotated[Path, typer.Argument(help="OpenSHC robot parameters (e.g. bullet_insectoid.yaml).")],
    gait: Annotated[Path | None, typer.Argument(help="OpenSHC gait.yaml.")] = None,
    auto_pose: Annotated[Path | None, typer.Argument(help="OpenSHC auto_pose.yaml.")] = None,
    out: Annotated[Path, typer.Option(help="Folder for robots/, gaits/ and poses/.")] = Path("imported"),
    urdf: Annotated[Path | None, typer.Option(help="The robot's URDF or xacro: the body's and links' masses "
                                                   "(OpenSHC's parameters have none).", metavar="FILE")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace existing robot, gait and pose files in --out.")] = False,
) -> None:
    """Turn OpenSHC YAML parameter files into shc robot, gait and auto-pose TOML files."""
    from shc_cli.commands.importing import import_openshc as run

    run(robot, gait, auto_pose, out, urdf, overwrite)


@import_app.command("urdf")
def import_urdf(
    file: Annotated[Path, typer.Argument(help="URDF or xacro file of a legged robot.", metavar="FILE.urdf|FILE.xacro")],
    out: Annotated[Path | None, typer.Option(help="Folder for robots/NAME.toml "
                                                  "[default: imported/NAME].")] = None,
    name: Annotated[str | None, typer.Option(help="Robot name [default: the URDF's robot name].")] = None,
    legs: Annotated[str, typer.Option(help="'auto' (every chain to a leaf link) or the tip links LINK,… or "
                                           "ID=LINK,… in leg order.")] = "auto",
    tip: Annotated[list[str] | None, typer.Option(help="Tip link (glob pattern), optionally with the tip point in "
                                                       "its frame: LINK@X,Y,Z [m]. Repeatable.")] = None,
    clearance: Annotated[float | None, typer.Option(help="Body clearance [m] [default: from the zero pose].")] = None,
    reach: Annotated[float | None, typer.Option(help="Stance distance from the hip, as a share of the leg's "
                                                     "length [default: from the zero pose].")] = None,
    snap: Annotated[float, typer.Option(help="Snap rpy values this close to a multiple of pi/2 [rad] (for "
                                             "axes meant to be parallel that are not quite).")] = 0.0,
    arg: Annotated[list[str] | None, typer.Option(help="xacro argument NAME=VALUE. Repeatable.")] = None,
    forward: Annotated[str | None, typer.Option(help="base_link axis the robot walks along: +x, +y, -x or -y "
                                                     "[default: +x, or +y if a leg is straight ahead].")] = None,
    base: Annotated[str | None, typer.Option(help="Body link that is shc's base_link [default: base_link, else the "
                                                  "root, else (a massless root) where the legs meet].")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing robot (and pose) file in --out.")] = False,
) -> None:
    """Turn a legged robot's URDF or xacro into an shc robot file (legs, limits, masses, a standing pose and the
    servo map of [hardware.servos])."""
    from shc_cli.commands.importing import import_urdf as run

    run(file, out, name, legs, tip, clearance, reach, snap, arg, forward, base, overwrite)


@import_app.command("mjcf")
def import_mjcf(
    file: Annotated[Path, typer.Argument(help="MJCF (MuJoCo XML) file of a legged robot.", metavar="FILE.xml")],
    out: Annotated[Path | None, typer.Option(help="Folder for robots/NAME.toml "
                                                  "[default: imported/NAME].")] = None,
    name: Annotated[str | None, typer.Option(help="Robot name [default: the file's name].")] = None,
    legs: Annotated[str, typer.Option(help="'auto' (every chain to a leaf body) or the tip bodies BODY,… or "
                                           "ID=BODY,… in leg order.")] = "auto",
    tip: Annotated[list[str] | None, typer.Option(help="Tip body (glob pattern), optionally with the tip point in "
                                                       "its frame: BODY@X,Y,Z [m]. Repeatable.")] = None,
    clearance: Annotated[float | None, typer.Option(help="Body clearance [m] [default: from the zero pose].")] = None,
    reach: Annotated[float | None, typer.Option(help="Stance distance from the hip, as a share of the leg's "
                                                     "length [default: from the zero pose].")] = None,
    snap: Annotated[float, typer.Option(help="Snap angles this close to a multiple of pi/2 [rad].")] = 0.0,
    forward: Annotated[str | None, typer.Option(help="Body axis the robot walks along: +x, +y, -x or -y "
                                                     "[default: +x, or +y if a leg is straight ahead].")] = None,
    base: Annotated[str | None, typer.Option(help="Body that is shc's base_link [default: the robot's root "
                                                  "body].")] = None,
    overwrite: Annotated[bool, typer.Option(help="Replace an existing robot (and pose) file in --out.")] = False,
) -> None:
    """Turn a legged robot's MJCF into an shc robot file, read by MuJoCo's own loader (the same rules, checks and
    servo map as import urdf)."""
    from shc_cli.commands.importing import import_mjcf as run

    run(file, out, name, legs, tip, clearance, reach, snap, forward, base, overwrite)


hw_app = typer.Typer(help="Bring a robot's servos up: find them, check where they stand, jog each joint to confirm "
                     "its direction and zero, emulate a robot's buses.", no_args_is_help=True)
PortsOption = Annotated[list[str], typer.Option("--port", metavar="DEV", help="Serial device of a servo bus, e.g. "
                                                "/dev/ttyUSB0; once per bus, bus 0 first.")]
HwBaudOption = Annotated[int | None, typer.Option(help="Baud rate [default: hardware.baud].")]


@hw_app.command("scan")
def hw_scan(
    port: Annotated[list[str] | None, typer.Option(metavar="DEV", help="Serial device to scan; repeatable "
                                                   "[default: every /dev/ttyUSB* and /dev/ttyACM*].")] = None,
    baud: Annotated[list[int] | None, typer.Option(help="Baud rate to try; repeatable [default: 1000000 and "
                                                   "57600, the servos' factory rates].")] = None,
    protocol: Annotated[list[str] | None, typer.Option(help="2.0, 1.0 (Dynamixel) or feetech; repeatable "
                                                       "[default: all].")] = None,
    ids: Annotated[str, typer.Option(help="Ids to look for, FIRST-LAST.")] = "0-252",
    timeout_ms: Annotated[float | None, typer.Option(help="Reply timeout of a Protocol 1.0/Feetech ping [ms] "
                                                     "[default: 2 x the adapter's latency timer + 6].")] = None,
) -> None:
    """Find the servos: for each port, baud rate and protocol, the ids that answer, their model and firmware."""
    from shc_cli.commands.hw import run_scan

    run_scan(port or [], baud or [], protocol or [], ids, timeout_ms)


@hw_app.command("check")
def hw_check(robot: RobotArgument, port: PortsOption, baud: HwBaudOption = None) -> None:
    """Read every joint's position (no motion, no torque) against its limits and the standing pose; exit 1 when a
    joint is outside its limits."""
    from shc_cli.commands.hw import run_check

    run_check(robot, port, baud)


@hw_app.command("jog")
def hw_jog(
    robot: Annotated[str, typer.Argument(help="Robot file (its [hardware.servos] is written back).")],
    port: PortsOption,
    joint: Annotated[list[str] | None, typer.Option(help="Joint to jog, e.g. AR_coxa; repeatable [default: "
                                                    "every joint, in order].")] = None,
    angle: Annotated[float, typer.Option(help="Jog size [rad].")] = 0.1,
    torque: Annotated[float, typer.Option(help="Torque limit while jogging, a share of the maximum (0-1].")] = 0.3,
    answers: Annotated[str | None, typer.Option(help="Answers in order instead of asking, e.g. y,k,n,h: "
                                                "direction y(es)/n(o, reversed)/s(kip), then zero h(ere)/k(eep).")]
    = None,
    baud: HwBaudOption = None,
) -> None:
    """Move one joint at a time by a small angle, torque limited, and back; confirm its direction and zero, which
    are written to the robot file's [hardware.servos]."""
    from shc_cli.commands.hw_jog import run_jog

    run_jog(robot, port, joint or [], angle, torque, answers, baud)


@hw_app.command("emulate")
def hw_emulate(
    robot: RobotArgument,
    link: Annotated[list[Path] | None, typer.Option(help="Make a symbolic link to each bus's port here (bus 0 "
                                                    "first); repeatable.")] = None,
    baud: HwBaudOption = None,
    duration: Annotated[float | None, typer.Option(help="Stop after this many seconds [default: at Ctrl-C].")]
    = None,
    dynamics: Annotated[bool, typer.Option(help="Move the servos as the robot file's [servo] model: load-free "
                                           "joints (gain, friction, armature) whose present current follows; "
                                           "default a plain first-order lag.")] = False,
) -> None:
    """Emulate the robot's servo buses on pseudo-terminals (their ports are printed), to try the hw commands and
    run-hw without hardware."""
    from shc_cli.commands.hw import run_emulate

    run_emulate(robot, link or [], baud, duration, dynamics)
