"""Checks of a study before any run: robots and gaits load, robot-file paths exist and lie in their ranges."""

from __future__ import annotations

from shc_cli.domain.sweeps.checks import check_runs, field
from shc_cli.domain.sweeps.options import check_study as check_options
from shc_cli.errors import Issue, SpecError
from shc_cli.spec.study import Study


def check_study(study: Study) -> None:
    """Before any run: every simulation option is one ``shc simulate`` takes, the robot loads, every robot-file path
    exists (and lies inside an adjustable parameter's [min, max]), every gait choice fits — one line with the study
    file's line, exit 2."""
    check_options(study)
    from shc_cli.spec.loading import load_robot, resolve
    from shc_cli.spec.robot import Adjustable

    base = {d.key: (d.choices[0] if d.kind == "categorical" else d.low) for d in study.space}
    points = study.points(0, base)[:1]
    for dimension in study.space:
        if dimension.kind == "categorical" and dimension.key in ("gait", "robot"):
            points += [study.points(0, {**base, dimension.key: c})[0] for c in dimension.choices[1:]]
    check_runs(study.path, points, study.lines)
    robot = load_robot(resolve("robots", study.robot)).robot
    for dimension in study.space:
        value = field(robot, dimension.key)
        if isinstance(value, Adjustable) and dimension.kind != "categorical" and not (
                value.min <= dimension.low and dimension.high <= value.max):
            raise SpecError([Issue(study.path, dimension.line, f"space.{dimension.key}",
                                   f"[{dimension.low:g}, {dimension.high:g}] leaves the robot's range "
                                   f"[{value.min:g}, {value.max:g}]", "search inside it")])
