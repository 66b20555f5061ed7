"""The whole fit (:func:`fit`): read the runs, solve, write the override robot file, ``fit.json`` and the figures.

With ``by = "joint"`` each joint name (``coxa``, ``femur``, …, every leg's) gets its own fit in a subdirectory of the
output: the replays give every servo the candidate values (the robot file has one servo model), and only that
group's residuals count — which servo model best explains those joints.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Literal

from shc_cli.errors import Issue, SpecError, check_choice

if TYPE_CHECKING:
    from shc_cli.backends.engine_registry import EngineName
    from shc_cli.domain.fit.params import Parameter
    from shc_cli.domain.fit.solve import Problem, Solution
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

Grouping = Literal["model", "joint"]


@dataclass(frozen=True)
class FitConfig:
    """Every option of ``shc fit`` (the same names and defaults).

    Attributes:
        runs: run directories (``run-hw`` or ``simulate``) of the robot.
        robot: the robot file or bundled name whose ``[servo]`` values are the start.
        params: the ``[servo]`` fields to fit, comma-separated (short names accepted:
            :data:`~shc_cli.domain.fit.params.ALIASES`); None: :data:`~shc_cli.domain.fit.params.DEFAULT_PARAMS`.
        engine: the physics engine of the replays.
        out: the output directory (None: ``fits/<robot name>``).
        scenario: where the runs of a real robot were recorded (SA, WA, SG, WG; BENCH: servos turning only their
            rotors, e.g. the servo emulator's); a simulated run's own is used.
        by: ``"model"`` (one fit of every servo) or ``"joint"`` (one fit per joint name).
        max_evaluations: the solver's budget of residual evaluations.
        seconds: use only the first this many seconds of each run (None: all).
        plots: write the figures.
        overwrite: replace an existing output directory (only one ``shc fit`` wrote).
    """

    runs: list[Path]
    robot: str = "bullet"
    params: str | None = None
    engine: EngineName = "mujoco"
    out: Path | None = None
    scenario: str = "WG"
    by: Grouping = "model"
    max_evaluations: int = 30
    seconds: float | None = None
    plots: bool = True
    overwrite: bool = False


@dataclass(frozen=True)
class GroupFit:
    """One fit's result.

    Attributes:
        group: ``"all"`` or the joint name.
        parameters: the fitted parameters (initial values and bounds).
        solution: what the solver found.
        values: the fitted values by ``[servo]`` field.
        before, after: RMS of each measured channel before and after (its unit).
        folder: where its files are.
    """

    group: str
    parameters: list[Parameter]
    solution: Solution
    values: dict[str, float]
    before: dict[str, float]
    after: dict[str, float]
    folder: Path


@dataclass(frozen=True)
class FitResult:
    """A finished ``shc fit``.

    Attributes:
        path: the output directory.
        fits: one per group (one with ``by = "model"``).
        elapsed_s: wall time [s].
    """

    path: Path
    fits: list[GroupFit] = field(default_factory=list)
    elapsed_s: float = 0.0


def fit(config: FitConfig) -> FitResult:
    """Fit the servo model to the runs (module docstring); nothing is written before the input is checked.

    Raises:
        ShcError: bad input (one line): an unknown parameter, a run without measured joints or of another robot.
    """
    import numpy as np

    from shc_cli.backends.engine_registry import ENGINES
    from shc_cli.domain.fit.params import parameters, parse_params
    from shc_cli.domain.fit.recording import SCENARIOS, load_recording
    from shc_cli.domain.fit.solve import Problem
    from shc_cli.validation import load_checked

    started = time.perf_counter()
    check_choice("--engine", config.engine, ENGINES, "a physics engine")
    check_choice("--scenario", config.scenario, SCENARIOS, "a scenario")
    check_choice("--by", config.by, ("model", "joint"), "a grouping")
    if not config.runs:
        raise SpecError([Issue(None, None, "RUN", "no run given", "give one or more run directories")])
    names = parse_params(config.params)
    robot = load_checked(config.robot, None)[0]
    recordings = [load_recording(run, robot, config.scenario) for run in config.runs]
    if config.seconds is not None:
        recordings = [r.cut(config.seconds) for r in recordings]
    out = config.out or Path("fits") / robot.name
    _prepare(out, config.overwrite)
    groups: list[tuple[str, np.ndarray | None]] = [("all", None)]
    if config.by == "joint":
        joint_names = [joint for leg in robot.legs.values() for joint in leg.joints]
        groups = [(name, np.array([i for i, j in enumerate(joint_names) if j == name]))
                  for name in dict.fromkeys(joint_names)]
    fits = []
    for group, joints in groups:
        problem = Problem(recordings, robot.servo, parameters(robot.servo, names), config.engine, joints)
        folder = out if joints is None else out / group
        fits.append(_fit_group(problem, group, config, robot, folder))
    return FitResult(out, fits, time.perf_counter() - started)


def _fit_group(problem: Problem, group: str, config: FitConfig, robot: Robot, folder: Path) -> GroupFit:
    """Solve one problem and write its files into ``folder``."""
    import numpy as np

    from shc_cli.domain.fit import outputs
    from shc_cli.domain.fit.solve import solve

    x0 = np.array([p.initial for p in problem.parameters])
    before = problem.channel_errors(x0)
    solution = solve(problem, config.max_evaluations)
    after = problem.channel_errors(solution.x)
    values = {p.name: float(v) for p, v in zip(problem.parameters, solution.x, strict=True)}
    folder.mkdir(parents=True, exist_ok=True)
    note = f"{len(problem.recordings)} run{'s' if len(problem.recordings) != 1 else ''}, {config.engine}" + (
        "" if group == "all" else f", the {group} joints")
    (folder / outputs.ROBOT_FILE).write_text(outputs.override_text(config.robot, folder, robot.name, values, note),
                                             encoding="utf-8")
    outputs.write_json(folder / outputs.FIT_FILE, outputs.fit_json(problem.parameters, solution, before, after))
    if config.plots:
        from shc_cli.record.runlog import joint_columns

        names = joint_columns(robot)
        for index, recording in enumerate(problem.recordings):
            first, last = problem.simulated(x0)[index], problem.simulated(solution.x)[index]
            outputs.plot_fit(recording, first, last, names, folder, f"{index + 1:02d}_{recording.path.name}")
    return GroupFit(group, problem.parameters, solution, values, before, after, folder)


def _prepare(out: Path, overwrite: bool) -> None:
    """Refuse an existing non-empty ``out`` unless ``overwrite`` (and then only one ``shc fit`` wrote)."""
    import shutil

    from shc_cli.domain.fit.outputs import FIT_FILE
    from shc_cli.errors import OutputError

    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise OutputError(f"{out}: already exists (add --overwrite to replace it, or choose another --out)")
        if not (out / FIT_FILE).exists() and not any((child / FIT_FILE).exists() for child in out.iterdir()):
            raise OutputError(f"{out}: not written by shc fit, so --overwrite leaves it alone (choose another --out)")
        shutil.rmtree(out)
