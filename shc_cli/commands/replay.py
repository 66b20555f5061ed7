"""``shc replay``: does shc command the same joints as OpenSHC did? A recorded run (the recorder's CSVs or a ROS
bag) is replayed through the controller and every recorded output compared, cycle by cycle."""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from shc_cli.errors import Issue, SpecError


def run_replay(source: Path, robot_name: str, gait_name: str | None, as_json: bool, out: Path | None,
               tolerance_joints: float | None, overwrite: bool = False) -> int:
    """Replay, print, write ``--out``; returns the exit code (1 only when ``--tolerance-joints`` is exceeded)."""
    from shc_cli.loop.run_inputs import pose_sets_for
    from shc_cli.outputs import ensure_dir, refuse_existing, write_text
    from shc_cli.replay.opening import open_source
    from shc_cli.replay.report import differences_csv, plot_differences, summary, text
    from shc_cli.replay.run import replay
    from shc_cli.spec.timeline import constant
    from shc_cli.validation import load_checked

    if tolerance_joints is not None and not (math.isfinite(tolerance_joints) and tolerance_joints >= 0.0):
        raise SpecError([Issue(None, None, "--tolerance-joints", f"{tolerance_joints:g} is not a non-negative "
                               "number of radians", "e.g. --tolerance-joints 0.001")])
    if out is not None:
        refuse_existing([out / "differences.csv", out / "differences.png"], overwrite)
    robot, gait, loaded = load_checked(robot_name, gait_name)
    gait_file, _ = loaded.where(("walker", "gait"))
    recorded = open_source(source)
    result = replay(recorded, robot, gait, pose_sets_for(robot, gait, constant((0.0, 0.0, 0.0)), gait_file.parent))
    if as_json:
        typer.echo(json.dumps(summary(result, robot.name, gait.name), indent=2))
    else:
        typer.echo(text(result, robot.name, gait.name))
    if out is not None:
        ensure_dir(out)
        write_text(out / "differences.csv", differences_csv(result))
        plot_differences(result, f"shc replay {source.name} on {robot.name} / {gait.name}", out / "differences.png")
        typer.echo(f"wrote {out / 'differences.csv'} and {out / 'differences.png'}", err=as_json)
    worst = result.comparison.worst.get("joints_rad")
    if tolerance_joints is not None and worst is not None and worst > tolerance_joints:
        cycle = result.comparison.at_cycle["joints_rad"]
        typer.echo(f"joints differ by {worst:.3g} rad at cycle {cycle}: more than --tolerance-joints "
                   f"{tolerance_joints:g}", err=True)
        return 1
    return 0
