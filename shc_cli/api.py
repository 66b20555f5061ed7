"""The public Python API: the CLI's commands as functions, for notebooks and scripts.

The same names and options as the command line (``shc simulate --terrain ramp:10`` is
``shc_cli.simulate(terrain="ramp:10")``), the same defaults, the same one-line errors
(:class:`~shc_cli.errors.ShcError`, never ``SystemExit``). Runs return a :class:`Run`: its directory, its summary
and its log as arrays. Exported lazily from :mod:`shc_cli`; see docs/python-api.md.
"""

from __future__ import annotations

import functools
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, ParamSpec, TypeVar

from shc_cli.errors import OutputError

if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import Unpack

    from shc_cli.domain.bringup.check import CheckReport
    from shc_cli.domain.bringup.jog import JogReport, Question
    from shc_cli.domain.config import SimulationConfig, SimulationOptions
    from shc_cli.domain.fit.run import FitResult
    from shc_cli.domain.hardware import HardwareConfig
    from shc_cli.domain.optimize.loop import StudyReport
    from shc_cli.domain.result import RunResult
    from shc_cli.domain.ros_node import NodeConfig
    from shc_cli.domain.simulate import OnProgress
    from shc_cli.domain.sweeps.run import OnRow, SweepReport
    from shc_cli.hardware.scan import Found, Protocol
    from shc_cli.record.runread import RunLog
    from shc_cli.record.summary import RunSummary
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

P = ParamSpec("P")
T = TypeVar("T")

_API_WORDS = ((r"add --overwrite\b", "pass overwrite=True"), (r"--overwrite\b", "overwrite=True"),
              (r"another --out\b", "another out"), (r"--out\b", "out"), (r"--resume\b", "resume=True"))
"""The CLI's option names in an output error, as the API's arguments (``add --overwrite`` → ``pass
overwrite=True``)."""


def api_words(text: str) -> str:
    """An error message's CLI options (``--overwrite``, ``--out``, ``--resume``) as this API's arguments."""
    for option, argument in _API_WORDS:
        text = re.sub(option, argument, text)
    return text


def _api_errors(function: Callable[P, T]) -> Callable[P, T]:
    """``function`` with its output errors naming the API's arguments, not the CLI's options — when a user's code
    calls it; shc's own commands call the same functions and keep the CLI's words (``--overwrite``)."""

    @functools.wraps(function)
    def wrapped(*args: P.args, **kwargs: P.kwargs) -> T:
        try:
            return function(*args, **kwargs)
        except OutputError as error:
            caller = str(sys._getframe(1).f_globals.get("__name__", ""))
            if caller == "shc_cli" or caller.startswith("shc_cli."):
                raise
            raise OutputError(api_words(str(error))) from None

    return wrapped


Velocity = str | tuple[float, float, float]
"""A velocity input ``"VX,VY,WZ"`` or ``(vx, vy, wz)`` in the robot's input mode (throttle −1..1 or m/s, rad/s)
(as :data:`shc_cli.domain.config.Velocity`)."""


@dataclass
class Run:
    """A finished run (also an interrupted one: ``complete`` is False).

    Attributes:
        path: the run directory.
        summary: its ``summary.json`` (:class:`~shc_cli.record.summary.RunSummary`: e.g. ``summary.cot``,
            ``summary.mean_speed_mps``).
    """

    path: Path
    summary: RunSummary
    _log: RunLog | None = field(default=None, repr=False)

    @property
    def log(self) -> RunLog:
        """The log as arrays (:class:`~shc_cli.record.runread.RunLog`: ``t``, ``position``, ``joints``, ``power``, …),
        read on first use."""
        if self._log is None:
            from shc_cli.domain.stored_run import open_run as read

            self._log = read(self.path)
        return self._log

    @property
    def complete(self) -> bool:
        """The run played its input to the end (not stopped by a signal, a fall or a fault)."""
        return self.summary.complete

    def analyze(self, skip: float = 0.0, steady: bool = False) -> dict[str, Any]:
        """``shc analyze`` of this run: CoT, power, speeds, duty factor, slip, stability (keys as ``--json``)."""
        return analyze(self, skip=skip, steady=steady)


@dataclass
class SweepResult:
    """A finished sweep: its output directory and the rows of ``results.csv`` (strings, as in the file).

    Attributes:
        path: the output directory.
        rows: the rows of ``results.csv``, grid order.
        report: what the sweep computed (:class:`~shc_cli.domain.sweeps.run.SweepReport`: workers, wall time,
            ok / failed / fell counts, the rows as values).
    """

    path: Path
    rows: list[dict[str, str]]
    report: SweepReport = field(repr=False)


@dataclass
class StudyResult:
    """A finished study: its output directory and the rows of ``trials.csv`` and ``pareto.csv`` (strings, as in
    the files).

    Attributes:
        path: the output directory (``study.db``, ``pareto/tNNNN.toml``, the plots).
        trials: the rows of ``trials.csv``, one per trial of the study in number order.
        pareto: the rows of ``pareto.csv``: the complete, feasible, non-dominated trials.
        report: what the search computed (:class:`~shc_cli.domain.optimize.loop.StudyReport`: trials run by this
            call, workers, wall time, search overhead).
    """

    path: Path
    trials: list[dict[str, str]]
    pareto: list[dict[str, str]]
    report: StudyReport = field(repr=False)


def load_robot(robot: str | Path = "bullet") -> Robot:
    """A robot file or bundled name, fully expanded and validated (``shc validate``'s checks)."""
    from shc_cli.validation import load_checked

    return load_checked(str(robot), None)[0]


def load_gait(gait: str | Path) -> Gait:
    """A gait file or bundled name."""
    from shc_cli.spec.loading import load_gait as load

    return load(str(gait)).gait


def _velocity(value: Velocity) -> str:
    return value if isinstance(value, str) else ",".join(repr(float(v)) for v in value)


@_api_errors
def plan(robot: str | Path = "bullet", *, gait: str | None = None, velocity: Velocity = "1,0,0",
         duration: float | None = None, commands: Path | str | None = None, out: Path | str | None = None,
         plots: bool = True, overwrite: bool = False, live: bool = False, live_port: int = 8765,
         realtime: bool = False, path: Path | str | None = None, fail_leg: str | None = None) -> Run:
    """``shc plan``: the controller run kinematically; returns the run (joints, tips and body tables). ``live``:
    streamed on a Foxglove server while it runs; ``realtime``: paced to the wall clock; ``path``: a path file the
    follower walks (docs/path-following.md); ``fail_leg``: failed legs, ``LEG[:MODE]`` comma-separated
    (docs/leg-failures.md)."""
    from shc_cli.domain.plan import plan as run

    result = run(str(robot), gait, _velocity(velocity), duration, _path(commands), _path(out), plots, overwrite,
                 live, live_port, realtime, _path(path), fail_leg)
    return Run(result.path, result.summary)


@_api_errors
def simulate(robot: str | Path | None = None, *, config: SimulationConfig | None = None,
             progress: OnProgress | None = None, **options: Unpack[SimulationOptions]) -> Run:
    """``shc simulate``: the controller on the robot in physics; keywords are ``shc simulate``'s options
    (:class:`~shc_cli.domain.config.SimulationConfig`: ``gait``, ``velocity``, ``duration``, ``terrain``,
    ``scenario``, ``seed``, ``out``, ``plots``, ``posture``, ``imu_posing``, ``inclination``, ``admittance``, …),
    over ``config`` when given (``robot`` over its robot); ``progress`` is told the walking cycles done and to do
    (:data:`~shc_cli.domain.simulate.OnProgress`)."""
    from shc_cli.domain.config import SimulationConfig
    from shc_cli.domain.simulate import simulate as run

    changes: dict[str, object] = dict(options)
    if robot is not None:
        changes["robot"] = str(robot)
    result = run((config or SimulationConfig()).replace(**changes), progress)
    return Run(result.path, result.summary)


def run_hardware(config: HardwareConfig) -> Run:
    """``shc run-hw``: the controller on the robot's Dynamixel servos, started, stopped and shut down safely
    (:class:`~shc_cli.domain.hardware.HardwareConfig`); ``summary["fault"]`` names a servo fault. The bus set-up,
    warnings and faults are events (:mod:`shc_cli.events`)."""
    from shc_cli.domain.hardware import run_hardware as run

    result = run(config)
    return Run(result.path, result.summary)


def analyze(run: Run | Path | str, *, skip: float = 0.0, steady: bool = False) -> dict[str, Any]:
    """``shc analyze --json`` of a run directory, a bag or a :class:`Run`."""
    from shc_cli.analysis.metrics import Window, analyze_log, public

    log = run.log if isinstance(run, Run) else open_run(run)
    return public(analyze_log(log, Window(skip_s=skip, steady=steady)))


def open_run(path: Path | str) -> RunLog:
    """Any run (a directory or a bag from ``shc export bag``) as arrays."""
    from shc_cli.domain.stored_run import open_run as read

    return read(path)


@_api_errors
def sweep(file: Path | str, *, workers: int | None = None, executor: str = "local", scheduler: str | None = None,
          out: Path | str | None = None, resume: bool = False, overwrite: bool = False, engine: str | None = None,
          progress: OnRow | None = None) -> SweepResult:
    """``shc sweep``: a grid of simulations; returns the output directory and the results table's rows.

    ``engine`` is the physics engine of the runs whose sweep file does not choose one; ``progress`` is called
    before the first run and as each run finishes (:data:`~shc_cli.domain.sweeps.run.OnRow`).
    """
    from shc_cli.domain.sweeps.run import run_sweep

    report = run_sweep(Path(file), workers, executor, scheduler, _path(out), resume, overwrite, engine, progress)
    return SweepResult(report.path, _table(report.path / "results.csv"), report)


@_api_errors
def optimize(file: Path | str, *, trials: int | None = None, workers: int | None = None, executor: str = "local",
             scheduler: str | None = None, out: Path | str | None = None, resume: bool = False,
             overwrite: bool = False) -> StudyResult:
    """``shc optimize``: a multi-objective search over simulated runs; returns the output directory, the trials
    and the Pareto front."""
    from shc_cli.domain.optimize.loop import run_optimize

    report = run_optimize(Path(file), trials, workers, executor, scheduler, _path(out), resume, overwrite)
    return StudyResult(report.path, _table(report.path / "trials.csv"), _table(report.path / "pareto.csv"), report)


@_api_errors
def fit(runs: Sequence[Path | str] | Path | str, *, robot: str | Path = "bullet", params: str | list[str] | None = None,
        engine: str = "mujoco", out: Path | str | None = None, scenario: str = "WG", by: str = "model",
        max_evaluations: int = 30, seconds: float | None = None, plots: bool = True,
        overwrite: bool = False) -> FitResult:
    """``shc fit``: the robot's ``[servo]`` parameters fitted to run logs (``run-hw`` or ``simulate``) by replaying
    their joint commands in the engine (:func:`shc_cli.domain.fit.run.fit`); returns the output directory and each
    fit (:class:`~shc_cli.domain.fit.run.FitResult`: ``fits[0].values``, ``.solution.uncertainty``,
    ``.solution.identifiable``). ``params``: ``[servo]`` names or short names (``"gain,coulomb"`` or a list);
    ``scenario``: where a real robot's runs were recorded (SA, WA, SG, WG); ``by``: ``"model"`` or ``"joint"``."""
    from shc_cli.domain.fit.run import FitConfig
    from shc_cli.domain.fit.run import fit as run

    paths = [Path(runs)] if isinstance(runs, (str, Path)) else [Path(r) for r in runs]
    names = ",".join(params) if isinstance(params, list) else params
    config = FitConfig(paths, str(robot), names, engine, _path(out), scenario.upper(), by,  # type: ignore[arg-type]
                       max_evaluations, seconds, plots, overwrite)
    return run(config)


@_api_errors
def fit_plan(robot: str | Path = "bullet", *, out: Path | str | None = None, overwrite: bool = False) -> Path:
    """``shc fit --plan``: write the recommended excitation for a fit of ``robot``'s servos, a plan script for
    ``run-hw --commands`` (:func:`shc_cli.domain.excitation.write_plan`), to ``out`` (default ``fit-plan.toml``;
    an existing file only with ``overwrite``); returns its path."""
    from shc_cli.domain.excitation import write_plan
    from shc_cli.outputs import refuse_existing

    path = Path(out) if out is not None else Path("fit-plan.toml")
    refuse_existing([path], overwrite)
    return write_plan(str(robot), path)


def _table(path: Path) -> list[dict[str, str]]:
    import csv

    with path.open(encoding="utf-8", newline="") as handle:
        return list(csv.DictReader(handle))


def _path(value: Path | str | None) -> Path | None:
    return None if value is None else Path(value)


def hw_scan(ports: list[str] | None = None, *, bauds: list[int] | None = None,
            protocols: list[Protocol] | None = None, ids: range = range(253), timeout_s: float | None = None,
            on_step: Callable[[str], None] | None = None) -> list[Found]:
    """``shc hw scan``: the servos answering on ``ports`` (default every USB serial adapter) at ``bauds``
    [bit/s] in ``protocols`` (``2.0``, ``1.0``, ``feetech``) with ids in ``ids``."""
    from shc_cli.hardware.scan import DEFAULT_BAUDS, PROTOCOLS, check_ports, scan

    return scan(check_ports(list(ports or [])), bauds or DEFAULT_BAUDS, protocols or PROTOCOLS, ids, timeout_s,
                on_step)


def hw_check(robot: str | Path, ports: list[str], baud: int | None = None) -> CheckReport:
    """``shc hw check``: every joint's present position against its limits and the standing pose (no motion, no
    torque)."""
    from shc_cli.domain.bringup.check import check

    return check(load_robot(robot), ports, baud)


def hw_jog(robot: str | Path, ports: list[str], ask: Callable[[Question], str], *, joints: list[str] | None = None,
           angle: float = 0.1, torque: float = 0.3, baud: int | None = None) -> JogReport:
    """``shc hw jog``: each joint moved by ``angle`` [rad] and back, torque limited to ``torque`` of the maximum;
    ``ask`` answers the direction and zero questions; the answers are written to the robot file."""
    from shc_cli.domain.bringup.jog import check_jog_options, jog
    from shc_cli.errors import Issue, SpecError

    path = Path(robot)
    if not path.is_file():
        raise SpecError([Issue(None, None, "ROBOT", f"{robot}: not a robot file (jog writes the servo map back)",
                               "give the robot file's path; copy a bundled robot first")])
    loaded = load_robot(path)
    check_jog_options(loaded, joints, angle, torque)
    return jog(loaded, path, ports, ask, joints, angle, torque, baud)


def hw_emulate(robot: str | Path, on_ready: Callable[[list[str]], None], *, links: list[Path] | None = None,
               baud: int | None = None, duration: float | None = None, dynamics: bool = False) -> None:
    """``shc hw emulate``: the robot's servo buses emulated on pseudo-terminals until a signal (or ``duration``
    [s]); ``on_ready`` gets their ports. ``dynamics``: the servos move as the robot's ``[servo]`` model (load-free
    joints, :mod:`shc_cli.backends.servo_joint`)."""
    from shc_cli.domain.bringup.emulate import emulate

    emulate(load_robot(robot), on_ready, links, baud, duration, dynamics)


def warm_up() -> float:
    """Compile shc's numba kernels into their cache (``shc warmup``); returns the seconds it took."""
    from shc_cli.domain.warmup import warm_up as compile_kernels

    return compile_kernels()


def ros_node(config: NodeConfig, on_ready: Callable[[str], None] | None = None) -> RunResult:
    """``shc ros``: OpenSHC's ROS 1 node until its duration, a signal or ``rosnode kill``; the finished run."""
    from shc_cli.domain.ros_node import run_node

    return run_node(config, on_ready)


def ros2_node(config: NodeConfig, params_file: Path | None = None,
              on_ready: Callable[[str], None] | None = None) -> RunResult:
    """``shc ros2``: OpenSHC's node on ROS 2 (``shc ros``'s session on an rclpy node) until its duration or a
    signal; the finished run."""
    from shc_cli.domain.ros2_node import run_node2

    return run_node2(config, params_file, on_ready)
