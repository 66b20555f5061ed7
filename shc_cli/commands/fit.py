"""``shc fit``: the robot's servo model fitted to run logs (:func:`shc_cli.api.fit`); prints each parameter and
where the files went."""

from __future__ import annotations

import math
from pathlib import Path

import typer


def run_fit(runs: list[Path], robot: str, params: str | None, engine: str, out: Path | None, scenario: str, by: str,
            max_evaluations: int, seconds: float | None, plots: bool, overwrite: bool) -> None:
    """Fit and print: per group, one line per parameter (initial → fitted ± uncertainty, identifiable or not) and
    the channels' RMS before → after."""
    from shc_cli.api import fit

    result = fit(runs, robot=robot, params=params, engine=engine, out=out, scenario=scenario, by=by,
                 max_evaluations=max_evaluations, seconds=seconds, plots=plots, overwrite=overwrite)
    for group in result.fits:
        solution = group.solution
        if group.group != "all":
            typer.echo(f"[{group.group}]")
        for index, parameter in enumerate(group.parameters):
            sigma = float(solution.uncertainty[index])
            spread = f"± {sigma:.3g}" if math.isfinite(sigma) else "± inf"
            partners = [group.parameters[k].name for k in solution.correlated[index]]
            flag = "" if solution.identifiable[index] else \
                f"  (not identifiable from these runs{_why(partners, bool(solution.unsettled[index]))})"
            typer.echo(f"  {parameter.name:24s} {parameter.initial:9.4g} → {solution.x[index]:9.4g} {spread}{flag}")
        errors = ", ".join(f"{name} {group.before[name]:.3g} → {group.after[name]:.3g}" for name in group.after)
        typer.echo(f"  RMS error: {errors}")
        if not solution.converged:
            typer.echo(f"warning: {group.group}: the solver stopped at its budget of {max_evaluations} evaluations "
                       "before converging: the values and uncertainties are where it stopped (raise "
                       "--max-evaluations, or fit runs on a stand and standing rather than walking)", err=True)
    first = result.fits[0]
    typer.echo(f"{len(runs)} run{'s' if len(runs) != 1 else ''}, {first.solution.replays} replays, "
               f"{result.elapsed_s:.1f} s → {result.path / 'robot.toml' if by == 'model' else result.path}")


def _why(partners: list[str], unsettled: bool) -> str:
    """Why a parameter is not identifiable, when it is more than its uncertainty: ``": trades with a, b"``."""
    reasons = ([f"trades with {', '.join(partners)}"] if partners else []) + (
        ["its probes still lowered the cost"] if unsettled else [])
    return f": {'; '.join(reasons)}" if reasons else ""


def write_fit_plan(runs: list[Path], robot: str, out: Path | None, overwrite: bool) -> None:
    """``shc fit --plan``: write the excitation plan script and say where and how to record it."""
    from shc_cli.api import fit_plan
    from shc_cli.errors import Issue, SpecError

    if runs:
        raise SpecError([Issue(None, None, "--plan", "writes a plan, it fits no runs",
                               f"drop the run directories ({runs[0]}) or --plan")])
    path = fit_plan(robot, out=out, overwrite=overwrite)
    typer.echo(f"{path}: record it with shc run-hw {robot} --commands {path} on a stand, then on the ground "
               "(docs/fitting-servos.md)")
