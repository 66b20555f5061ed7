"""``shc workspace``: per-leg workspaces, walkspace and speed limits of a robot and gait."""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

import typer

from shc_cli.analysis.workspace import WorkspaceReport, analyse_workspace
from shc_cli.errors import Issue, SpecError
from shc_cli.outputs import atomic_path, write_text


def run_workspace(
    robot_name: str,
    gait_name: str | None,
    step_frequency: float | None,
    bearing_count: int,
    volumetric: bool,
    out: Path | None,
    json_output: bool,
    overwrite: bool = False,
) -> None:
    from shc_cli.outputs import refuse_existing
    from shc_cli.validation import load_checked

    if out is not None:
        refuse_existing([out / "workspace.csv", out / "limits.csv", out / "workspace.png"], overwrite)
    robot, gait, _ = load_checked(robot_name, gait_name)
    if bearing_count < 1 or 360 % bearing_count:
        raise SpecError([_option_issue("--bearings", f"{bearing_count} does not divide 360",
                                       "use 8, 12, 24, 36 or 72")])
    if step_frequency is not None and step_frequency <= 0:
        raise SpecError([_option_issue("--step-frequency", f"{step_frequency:g} must be > 0",
                                       "give a frequency in Hz")])
    report = analyse_workspace(robot, gait, step_frequency, bearing_count, volumetric)
    if out is not None:
        write_outputs(report, out)
    if json_output:
        typer.echo(json.dumps(report.to_json(), indent=1))
    else:
        typer.echo(render_table(report, terminal_width()))
        if out is not None:
            typer.echo(f"wrote {out}/workspace.csv, {out}/limits.csv, {out}/workspace.png")


def _option_issue(option: str, problem: str, fix: str) -> Issue:
    return Issue(None, None, option, problem, fix)


def terminal_width() -> int:
    """Columns of the terminal (or ``$COLUMNS``); :data:`PIPE_WIDTH` when printing to a pipe or file (a 5° grid
    was one 770-character line per row)."""
    import shutil

    columns = shutil.get_terminal_size((0, 0)).columns
    return columns if columns > 0 else PIPE_WIDTH


LABEL_WIDTH = 49
"""Characters before the first per-bearing column of the workspace table."""
CELL_WIDTH = 9
PIPE_WIDTH = LABEL_WIDTH + 8 * CELL_WIDTH
"""The table's width in a pipe: blocks of eight bearings, OpenSHC's 45° grid (the default table, unwrapped)."""


def render_table(report: WorkspaceReport, width: int | None = None) -> str:
    """The terminal table: legs (area, stride, radii), walkspace and limits per bearing. Wider than ``width``
    characters (many bearings), the bearings are split into blocks that fit, one under the other."""
    import math
    import textwrap

    bearings = [b for b in report.walkspace if b != 360]
    header = (f"{report.robot.name} / {report.gait.name}: step frequency {report.step_frequency:g} Hz, "
              f"cycle {report.cycle.period} cycles ({report.cycle.period * report.robot.time_delta:.2f} s, "
              f"{report.cycle.frequency:.4f} Hz), swing {report.cycle.swing_period}, stance "
              f"{report.cycle.stance_period}, duty factor {report.cycle.duty_factor:.3f}")
    per_block = len(bearings)
    if width is not None and LABEL_WIDTH + CELL_WIDTH * len(bearings) > width:
        fit = max(1, (width - LABEL_WIDTH) // CELL_WIDTH)
        blocks = math.ceil(len(bearings) / fit)
        per_block = math.ceil(len(bearings) / blocks)
    lines = textwrap.wrap(header, width) if width is not None else [header]
    for first in range(0, len(bearings), per_block):
        lines += ["", *_block(report, bearings[first:first + per_block])]
    lines.append(f"walkspace area {report.walkspace_area():.4f} m², stride {report.walkspace_stride():.4f} m "
                 "(measured as the OpenSHC paper's Table II does for Bullet)")
    lines.append(f"time to max stride {report.limits.time_to_max_stride:.3f} s, "
                 f"stance radius {report.limits.stance_radius:.4f} m")
    return "\n".join(lines)


def _block(report: WorkspaceReport, bearings: list[int]) -> list[str]:
    """The table's rows for some bearings."""
    head = "".join(f"{b:>8}°" for b in bearings)
    lines = [f"{'leg':<6}{'area m²':>9}{'stride m':>10}   radius [m] at bearing{head}"]
    pad = " " * 24
    for leg, plane in report.planes.items():
        radii = "".join(f"{plane[b]:>9.4f}" for b in bearings)
        lines.append(f"{leg:<6}{report.area(leg):>9.4f}{report.forward_stride(leg):>10.4f}{pad}{radii}")
    walk = "".join(f"{report.walkspace[b]:>9.4f}" for b in bearings)
    lines.append(f"{'walkspace':<25}{pad}{walk}")
    rows = [
        ("max linear speed m/s", "linear_speed"),
        ("max linear acc m/s²", "linear_acceleration"),
        ("max angular speed rad/s", "angular_speed"),
        ("max angular acc rad/s²", "angular_acceleration"),
    ]
    for label, field in rows:
        values = "".join(f"{getattr(report.limits.bearings[b], field):>9.4f}" for b in bearings)
        lines.append(f"{label:<49}{values}")
    if report.verified is not None:  # shc: the limits trial walks verified (the ones the controller walks)
        for label, field in (("verified linear speed m/s", "linear_speed"), ("verified angular speed rad/s",
                                                                            "angular_speed")):
            values = "".join(f"{getattr(report.verified.bearings[b], field):>9.4f}" for b in bearings)
            lines.append(f"{label:<49}{values}")
    return lines


def write_outputs(report: WorkspaceReport, out: Path) -> None:
    """workspace.csv (radius per leg, height, bearing), limits.csv and workspace.png, atomically."""
    table = io.StringIO()
    writer = csv.writer(table, lineterminator="\n")
    writer.writerow(["leg", "height_m", "bearing_deg", "radius_m"])
    stacks = report.layers or {leg: {0.0: plane} for leg, plane in report.planes.items()}
    for leg, stack in stacks.items():
        for height, plane in stack.items():
            for bearing, radius in plane.items():
                writer.writerow([leg, f"{height:.9f}", bearing, f"{radius:.9f}"])
    for bearing, radius in report.walkspace.items():
        writer.writerow(["walkspace", f"{0.0:.9f}", bearing, f"{radius:.9f}"])
    write_text(out / "workspace.csv", table.getvalue())

    limits = io.StringIO()
    writer = csv.writer(limits, lineterminator="\n")
    writer.writerow(["bearing_deg", "walkspace_radius_m", "scaled_radius_m", "stance_overshoot_m", "swing_overshoot_m",
                     "max_linear_speed_mps", "max_linear_acceleration_mps2", "max_angular_speed_radps",
                     "max_angular_acceleration_radps2"])
    for bearing, lim in report.limits.bearings.items():
        writer.writerow([bearing] + [f"{v:.9f}" for v in (
            lim.walkspace_radius, lim.scaled_radius, lim.stance_overshoot, lim.swing_overshoot, lim.linear_speed,
            lim.linear_acceleration, lim.angular_speed, lim.angular_acceleration)])
    write_text(out / "limits.csv", limits.getvalue())
    from shc_cli.plots import plot_workspace

    with atomic_path(out / "workspace.png") as temporary:
        plot_workspace(report, temporary)
