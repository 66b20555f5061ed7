"""Options several ``shc`` commands share (one definition each: the same name, help and type everywhere)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

RobotArgument = Annotated[str, typer.Argument(help="Robot file or bundled robot name.")]
GaitOption = Annotated[str | None, typer.Option(help="Gait name or file (default: the robot's gait).")]
CommandsOption = Annotated[Path | None, typer.Option(help="Command timeline: CSV 'cycle,vx,vy,wz' or a TOML plan "
                                                          "script.")]
PathOption = Annotated[Path | None, typer.Option("--path", help="Walk the waypoints of a path file (CSV 'x,y[,yaw]' "
                                                               "or TOML [[waypoint]]; metres, radians, from the "
                                                               "robot's start pose) by the odometry, then stop.")]
BagOption = Annotated[str | None, typer.Option(help="Also write the run as a bag in it: mcap, sqlite3 or ros1.")]
OVERWRITE_HELP = "Replace an existing run directory at --out (when the new run finishes; only shc's own outputs)."
LiveOption = Annotated[bool, typer.Option(help="Stream the run while it happens to a Foxglove WebSocket server on "
                                               "127.0.0.1 (the topics of shc export bag).")]
LivePortOption = Annotated[int, typer.Option(help="Port of the --live server (0: any free port).")]
VELOCITY_HELP = ("Constant velocity input VX,VY,WZ: throttle fractions −1..1 of the robot's maximum linear and "
                 "angular speed, unless the robot file's walker.velocity_input_mode is 'real' (then m/s, m/s, rad/s).")
