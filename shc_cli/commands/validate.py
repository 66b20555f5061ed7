"""``shc validate``: check any shc file as what it is (robot, gait, auto-pose set, sweep, study, plan script,
timeline; :mod:`shc_cli.spec.kinds`, :mod:`shc_cli.domain.file_checks`) and summarise the robots."""

from __future__ import annotations

import logging

import typer

from shc_cli.domain.file_checks import validate_file
from shc_cli.errors import Issue, NotFoundError, ShcError, SpecError
from shc_cli.spec.kinds import file_kind
from shc_cli.spec.loading import LoadedGait, LoadedRobot, bundled, load_gait, load_robot
from shc_cli.spec.robot import Robot
from shc_cli.spec.toml_out import dump_toml

log = logging.getLogger(__name__)


def run_validate(files: list[str], *, show: bool) -> None:
    """Validate every file; print a summary per robot; raise one SpecError listing every problem."""
    from shc_cli.validation import check_robot, leg_position_warnings

    issues: list[Issue] = []
    robots: list[LoadedRobot] = []
    gaits: list[LoadedGait] = []
    others: list[str] = []
    for name in files:
        try:
            kind = file_kind(name)
            if kind == "gait":
                gaits.append(load_gait(name))
            elif kind != "robot":
                line, found = validate_file(name, kind)
                issues += found
                others.append(line)
            else:
                loaded = load_robot(name)
                found = check_robot(loaded)
                issues += found
                if not found:
                    issues += _check_own_gait(loaded)
                    robots.append(loaded)
        except SpecError as error:
            issues += error.issues
        except NotFoundError as error:
            issues.append(Issue(None, None, "", str(error)))
    for gait in gaits:
        issues += _check_gait_against(gait, [r.robot for r in robots])
    if issues:
        raise SpecError(issues)
    for loaded in robots:
        for warning in leg_position_warnings(loaded.robot):
            log.warning("warning: %s: %s", loaded.path, warning)
        if show:  # the TOML alone on stdout, so `--show > expanded.toml` gives a valid robot file
            typer.echo(f"# {loaded.path}, expanded by shc validate --show")
            typer.echo(dump_toml(loaded.robot.model_dump(mode="json")))
        typer.echo(summary(loaded.robot, [g for g in gaits if g.gait], _own_gait(loaded)), err=show)
    for gait in gaits:
        typer.echo(f"{gait.path}: gait '{gait.gait.name}' ok (duty factor {gait.gait.duty_factor:.3f})", err=show)
    for line in others:
        typer.echo(line, err=show)


def _check_gait_against(gait: LoadedGait, robots: list[Robot]) -> list[Issue]:
    """Check a gait against the robots of the same invocation whose legs it names; if it fits none, say so."""
    from shc_cli.validation import check_gait, check_gait_pattern

    if not robots:
        return check_gait_pattern(gait)
    fitting = [robot for robot in robots if set(robot.legs) == set(gait.gait.offset_multiplier)]
    if not fitting:
        return check_gait(gait, robots[0]) if len(robots) == 1 else [gait.issue(
            ("offset_multiplier",),
            f"gait '{gait.gait.name}' fits none of the robots given ({', '.join(r.name for r in robots)})",
            "name exactly the leg ids of one of them")]
    return [issue for robot in fitting for issue in check_gait(gait, robot)]


def _check_own_gait(loaded: LoadedRobot) -> list[Issue]:
    """The gait named in walker.gait must exist and fit the robot.

    Problems are reported at walker.gait in the robot file: choosing that gait is the robot's doing,
    and the gait file may be a bundled one the user never edits.
    """
    from shc_cli.validation import check_gait

    file, _ = loaded.where(("walker", "gait"))
    try:
        gait = load_gait(loaded.robot.walker.gait, relative_to=file.parent)
    except ShcError as error:
        return [loaded.issue(("walker", "gait"), str(error).splitlines()[0], "name a bundled gait or a gait file")]
    return [loaded.issue(("walker", "gait"), issue.problem, issue.fix) for issue in check_gait(gait, loaded.robot)]


def _own_gait(loaded: LoadedRobot) -> LoadedGait | None:
    """The robot's walker.gait, loaded as the validator found it (None if it cannot be loaded)."""
    try:
        return load_gait(loaded.robot.walker.gait, relative_to=loaded.where(("walker", "gait"))[0].parent)
    except ShcError:
        return None


def summary(robot: Robot, extra_gaits: list[LoadedGait], own: LoadedGait | None = None) -> str:
    """A short table: legs, DOF, mass, stance and the duty factor and period of each fitting gait."""
    from shc_cli.control.gait import step_cycle

    dof = sorted({len(leg.joints) for leg in robot.legs.values()})
    lines = [
        f"{robot.name}: {len(robot.legs)} legs, {'/'.join(map(str, dof))} DOF per leg, "
        f"{sum(len(leg.joints) for leg in robot.legs.values())} joints, mass {robot.total_mass():.2f} kg, "
        f"body clearance {robot.walker.body_clearance:g} m, control period {robot.time_delta * 1000:g} ms",
        f"  {'leg':<5}{'joints':<36}{'stance x':>9}{'stance y':>9}",
    ]
    for leg_id, leg in robot.legs.items():
        lines.append(f"  {leg_id:<5}{', '.join(leg.joints):<36}{leg.stance.x:>9.3f}{leg.stance.y:>9.3f}")
    gaits = {}
    for name in bundled("gaits"):
        try:
            gait = load_gait(name).gait
        except ShcError:
            continue
        if set(gait.offset_multiplier) == set(robot.legs):
            gaits[gait.name] = gait
    for loaded in [*extra_gaits, *([own] if own else [])]:
        if set(loaded.gait.offset_multiplier) == set(robot.legs):
            gaits[loaded.gait.name] = loaded.gait
    frequency = robot.walker.step_frequency.default
    lines.append(f"  {'gait':<18}{'duty':>6}{'period':>9}{'period':>9}   (step frequency {frequency:g} Hz)")
    for name, gait in gaits.items():
        try:
            cycle = step_cycle(gait, frequency, robot.time_delta)
        except ZeroDivisionError:  # no whole cycle at this frequency and control period: not usable
            continue
        default = " (default)" if own is not None and own.gait is gait else ""
        lines.append(f"  {name:<18}{cycle.duty_factor:>6.3f}{cycle.period:>6} cyc"
                     f"{cycle.period * robot.time_delta:>8.2f} s{default}")
    return "\n".join(lines)


__all__ = ["NotFoundError", "run_validate", "summary"]
