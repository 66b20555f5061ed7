"""``shc analyze``: cost of transport, power, speed, duty factor, slip and stability of one or more runs."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import typer

from shc_cli.analysis.metrics import Window

COLUMNS = (
    ("scenario", "scen", "{}"),
    ("step_frequency_hz", "f_s Hz", "{:.2f}"),
    ("window_s", "window s", "{:.1f}"),
    ("path_speed_mps", "path m/s", "{:.4f}"),
    ("displacement_speed_mps", "disp. m/s", "{:.4f}"),
    ("speed_ratio", "÷cmd", "{:.2f}"),
    ("mean_power_w", "power W", "{:.1f}"),
    ("cot", "CoT", "{:.2f}"),
    ("duty_factor", "duty", "{:.3f}"),
    ("foot_slip_m", "slip m", "{:.3f}"),
    ("stability_margin_median_m", "margin m", "{:.3f}"),
    ("zmp_margin_median_m", "ZMP m", "{:.3f}"),
    ("height_median_m", "height m", "{:.3f}"),
    ("roll_rate_median_rps", "roll r/s", "{:.3f}"),
    ("pitch_rate_median_rps", "pitch r/s", "{:.3f}"),
)
"""Terminal table columns: result key, header, format."""
PATH_COLUMNS = (
    ("waypoints_reached", "reached", "{}"),
    ("waypoints_total", "of", "{}"),
    ("cross_track_rms_m", "x-track m", "{:.3f}"),
    ("time_to_goal_s", "goal s", "{:.1f}"),
)
"""Columns added when a run walked a path (``--path``): its measures against the ground truth."""
REFERENCE_COLUMNS = (
    ("heading_speed_mps", "heading m/s", "{:.4f}"),
    ("speed_retained", "retained", "{:.0%}"),
    ("fell", "fell", "{}"),
)
"""Columns added with ``--reference``: the speed along the commanded heading, its share of the reference's."""


def _cell(value: Any, fmt: str) -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    return fmt.format(value)


def table(results: list[dict[str, Any]]) -> str:
    """One row per run, aligned columns."""
    columns = COLUMNS + (PATH_COLUMNS if any(r.get("waypoints_total") for r in results) else ())
    columns += REFERENCE_COLUMNS if any("speed_retained" in r for r in results) else ()
    header = ["run", *[h for _, h, _ in columns]]
    rows = [[Path(str(r["run"])).name, *[_cell(r.get(k), f) for k, _, f in columns]] for r in results]
    widths = [max(len(row[i]) for row in [header, *rows]) for i in range(len(header))]
    lines = ["  ".join(cell.ljust(w) if i == 0 else cell.rjust(w) for i, (cell, w) in enumerate(zip(row, widths,
                                                                                                       strict=True)))
             for row in [header, *rows]]
    return "\n".join(lines)


def run_analyze(runs: list[Path], as_json: bool, out: Path | None, skip: float, steady: bool,
                overwrite: bool = False, reference: Path | None = None) -> None:
    from shc_cli.analysis.metrics import analyze_log, public
    from shc_cli.api import open_run
    from shc_cli.outputs import ensure_dir, refuse_existing, write_text

    if out is not None:  # analysis.json marks an analysis output: its plots are replaced with it or not at all
        refuse_existing([out / "analysis.json"], overwrite)
    logs = [open_run(path) for path in runs]
    window = Window(skip_s=skip, steady=steady)
    results = []
    for path, log in zip(runs, logs, strict=True):
        try:
            results.append(analyze_log(log, window))
        except (ValueError, ArithmeticError) as error:  # numbers the readers let through that no metric can use
            from shc_cli.errors import Issue, SpecError

            raise SpecError([Issue(Path(path), None, "log", f"cannot be analysed: {error}",
                                   "the run's files are damaged: run it again")]) from None
    if reference is not None:
        from shc_cli.analysis.retained import heading_speed, retained

        intact = heading_speed(open_run(reference), window)
        results = [retained(r, log, window, intact) for r, log in zip(results, logs, strict=True)]
    for log in logs:
        note = log.partial_note()
        if note is not None:
            typer.echo(f"note: {note}", err=True)
    if as_json:
        data: Any = public(results[0]) if len(results) == 1 else [public(r) for r in results]
        typer.echo(json.dumps(data, indent=2))
    else:
        typer.echo(table(results))
    if out is not None:
        from shc_cli.plots import plot_analysis

        ensure_dir(out)
        write_text(out / "analysis.json", json.dumps([public(r) for r in results], indent=2) + "\n")
        written = plot_analysis(results, logs, out)
        typer.echo(f"wrote {out / 'analysis.json'} and {len(written)} plots in {out}", err=as_json)
