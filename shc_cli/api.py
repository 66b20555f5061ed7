"""The public Python API: the CLI's commands as functions, for notebooks and scripts.

The same names and options as the command line (``shc simulate --terrain ramp:10`` is
``shc_cli.simulate(terrain="ramp:10")``), the same defaults, the same one-line errors
(:class:`~shc_cli.errors.ShcError`, never ``SystemExit``). Runs return a :class:`Run`: its directory, its summary
and its log as arrays. Exported lazily from :mod:`shc_cli`; see docs/python-api.md.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from typing import Unpack

    from shc_cli.domain.config import SimulationConfig, SimulationOptions
    from shc_cli.loop.runread import RunLog
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

Velocity = str | tuple[float, float, float]
"""A velocity input ``"VX,VY,WZ"`` or ``(vx, vy, wz)`` in the robot's input mode (throttle −1..1 or m/s, rad/s)
(as :data:`shc_cli.domain.config.Velocity`)."""


@dataclass
class Run:
    """A finished run (also an interrupted one: ``complete`` is False).

    Attributes:
        path: the run directory.
        summary: its ``summary.json`` (e.g. ``summary["cot"]``, ``summary["mean_speed_mps"]``).
    """

    path: Path
    summary: dict[str, Any]
    _log: RunLog | None = field(default=None, repr=False)

    @property
    def log(self) -> RunLog:
        """The log as arrays (:class:`~shc_cli.loop.runread.RunLog`: ``t``, ``position``, ``joints``, ``power``, …),
        read on first use."""
        if self._log is None:
            from shc_cli.loop.opening import open_run as read

            self._log = read(self.path)
        return self._log

    @property
    def complete(self) -> bool:
        """The run played its input to the end (not stopped by a signal, a fall or a fault)."""
        return bool(self.summary.get("complete", True))

    def analyze(self, skip: float = 0.0, steady: bool = False) -> dict[str, Any]:
        """``shc analyze`` of this run: CoT, power, speeds, duty factor, slip, stability (keys as ``--json``)."""
        return analyze(self, skip=skip, steady=steady)


@dataclass
class SweepResult:
    """A finished sweep: its output directory and the rows of ``results.csv`` (strings, as in the file)."""

    path: Path
    rows: list[dict[str, str]]


def load_robot(robot: str | Path = "bullet") -> Robot:
    """A robot file or bundled name, fully expanded and validated (``shc validate``'s checks)."""
    from shc_cli.spec.checks import load_checked

    return load_checked(str(robot), None)[0]


def load_gait(gait: str | Path) -> Gait:
    """A gait file or bundled name."""
    from shc_cli.spec.loading import load_gait as load

    loaded = load(str(gait)).gait
    assert loaded is not None  # load_gait raises a SpecError on a bad file
    return loaded


def _velocity(value: Velocity) -> str:
    return value if isinstance(value, str) else ",".join(repr(float(v)) for v in value)


def plan(robot: str | Path = "bullet", *, gait: str | None = None, velocity: Velocity = "1,0,0",
         duration: float | None = None, commands: Path | str | None = None, out: Path | str | None = None,
         plots: bool = True, overwrite: bool = False) -> Run:
    """``shc plan``: the controller run kinematically; returns the run (joints, tips and body tables)."""
    from shc_cli.commands.plan import plan_to

    path, summary = plan_to(str(robot), gait, _velocity(velocity), duration, _path(commands), _path(out), plots,
                            overwrite)
    return Run(path, summary)


def simulate(robot: str | Path | None = None, *, config: SimulationConfig | None = None,
             **options: Unpack[SimulationOptions]) -> Run:
    """``shc simulate``: the controller on the robot in physics; keywords are ``shc simulate``'s options
    (:class:`~shc_cli.domain.config.SimulationConfig`: ``gait``, ``velocity``, ``duration``, ``terrain``,
    ``scenario``, ``seed``, ``out``, ``plots``, ``posture``, ``imu_posing``, ``inclination``, ``admittance``, …),
    over ``config`` when given (``robot`` over its robot)."""
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.simulate import simulate as run

    changes: dict[str, object] = dict(options)
    if robot is not None:
        changes["robot"] = str(robot)
    result = run((config or SimulationConfig()).replace(**changes))
    return Run(result.path, result.summary)


def analyze(run: Run | Path | str, *, skip: float = 0.0, steady: bool = False) -> dict[str, Any]:
    """``shc analyze --json`` of a run directory, a bag or a :class:`Run`."""
    from shc_cli.analysis.metrics import Window, analyze_run
    from shc_cli.commands.analyze import public

    log = run.log if isinstance(run, Run) else open_run(run)
    result = public(analyze_run(log, Window(skip_s=skip, steady=steady)))
    result.update(complete=log.complete, stop_reason=log.summary.get("stop_reason", "end"))
    return result


def open_run(path: Path | str) -> RunLog:
    """Any run (a directory or a bag from ``shc export bag``) as arrays."""
    from shc_cli.loop.opening import open_run as read

    return read(path)


def sweep(file: Path | str, *, workers: int | None = None, executor: str = "local", scheduler: str | None = None,
          out: Path | str | None = None, resume: bool = False, overwrite: bool = False) -> SweepResult:
    """``shc sweep``: a grid of simulations; returns the output directory and the results table's rows."""
    import csv

    from shc_cli.commands.sweep import run_sweep

    path = run_sweep(Path(file), workers, executor, scheduler, _path(out), resume, overwrite)
    with (path / "results.csv").open(encoding="utf-8", newline="") as handle:
        rows = list(csv.DictReader(handle))
    return SweepResult(path, rows)


def _path(value: Path | str | None) -> Path | None:
    return None if value is None else Path(value)
