"""A run's recorded joint commands and what its servos measured, as the fit needs them.

Two kinds of run directory have ``log.csv`` (:mod:`shc_cli.record.runlog`): ``run-hw`` (and a servo emulator's bus)
logs each servo's present current [A] in the ``_torque`` column — a servo does not measure its torque — and lists
what it does not measure in the summary's ``unmeasured`` (the per-servo and total power, unless a supply meter
filled ``power_w``); ``simulate`` logs the output torque [N·m] and the total power [W]. Velocities are not logged:
the fit takes them as differences of the logged positions over one control period, which is also the mean speed
the simulator turns into power. Where the run was (on the ground, held in the air, started on a stand) comes from
the summary's ``scenario`` for a simulated run; a real run's (``scenario = "hardware"``) is the fit's
``scenario`` option, and its replay starts from the first logged positions.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.robot import Robot

SCENARIOS = ("SA", "WA", "SG", "WG", "BENCH")
"""Where a run was (paper §VII-A): stance or walk, in the air (body held) or on the ground; or BENCH: servos that
turn nothing but their own rotors (off the robot, or the servo emulator's load-free joints,
:mod:`shc_cli.backends.servo_joint`)."""


@dataclass(frozen=True)
class Recording:
    """One run's commands and measurements, servo order (legs in id order, joints body to tip).

    Attributes:
        path: the run directory.
        robot: the robot the run used (its ``robot.toml``).
        scenario: SA, WA, SG or WG (where the replay puts the robot).
        terrain: the terrain as ``--terrain`` gives it.
        seed: the run's seed (terrain blocks).
        measured_start: the replay starts from the first logged positions (a real robot) instead of the simulator's
            spawn pose.
        running: the robot state was RUNNING ``(N,)`` (a stand is released at the first such cycle).
        commanded: goal positions ``(N, J)`` [rad].
        position: measured positions ``(N, J)`` [rad].
        current: measured motor current ``(N, J)`` [A] (a bus), or ``None``.
        torque: measured output torque ``(N, J)`` [N·m] (a simulated run), or ``None``.
        power: measured total supply power ``(N,)`` [W], or ``None`` (not measured).
    """

    path: Path
    robot: Robot
    scenario: str
    terrain: str
    seed: int
    measured_start: bool
    running: np.ndarray
    commanded: np.ndarray
    position: np.ndarray
    current: np.ndarray | None
    torque: np.ndarray | None
    power: np.ndarray | None

    @property
    def dt(self) -> float:
        """Control period [s]."""
        return float(self.robot.time_delta)

    @property
    def velocity(self) -> np.ndarray:
        """Joint speeds ``(N, J)`` [rad/s]: differences of the positions (the first row 0)."""
        return speeds(self.position, self.dt)

    def cut(self, seconds: float) -> Recording:
        """The first ``seconds`` of the run."""
        from dataclasses import replace

        n = max(2, round(seconds / self.dt))

        def first(values: np.ndarray | None) -> np.ndarray | None:
            return None if values is None else values[:n]

        return replace(self, running=self.running[:n], commanded=self.commanded[:n], position=self.position[:n],
                       current=first(self.current), torque=first(self.torque), power=first(self.power))


def speeds(position: np.ndarray, dt: float) -> np.ndarray:
    """Differences of ``position`` ``(N, J)`` over one period ``dt`` [rad/s], the first row 0."""
    out = np.zeros_like(position)
    out[1:] = np.diff(position, axis=0) / dt
    return out


def load_recording(path: Path, robot: Robot, hardware_scenario: str = "WG") -> Recording:
    """The run at ``path`` for a fit of ``robot``'s servos.

    Raises:
        SpecError: one line: not a run with ``log.csv`` (a plan), no current or torque column, a robot whose body
            or legs differ from ``robot`` (only ``[servo]`` may differ).
    """
    from shc_cli.domain.stored_run import open_run
    from shc_cli.record.runlog import joint_columns

    log = open_run(Path(path))
    if log.kind != "simulate" or log.commanded is None or log.efforts is None:
        raise _bad(path, "has no measured joints (a plan run, or no log.csv)",
                   "give run directories written by shc run-hw or shc simulate")
    _check_robot(path, log.robot, robot)
    rows, cols = _slots(log.robot)
    summary = log.summary
    unmeasured = summary.unmeasured
    bus = unmeasured is not None
    scenario = summary.scenario if summary.scenario in SCENARIOS else hardware_scenario
    efforts = log.efforts[:, rows, cols]
    power_measured = log.power is not None and not (bus and "power_w" in (unmeasured or []))
    if bus and not np.any(efforts):
        raise _bad(path, "its current columns (<LEG>_<joint>_torque, in A on a bus) are all 0",
                   "record with servos that report their present current")
    columns = joint_columns(log.robot)
    if len(columns) != len(rows):
        raise _bad(path, "log.csv's joints do not match its robot.toml", "re-record the run")
    return Recording(
        path=Path(path), robot=log.robot, scenario=str(scenario), terrain=summary.terrain or "flat",
        seed=summary.seed or 0, measured_start=summary.scenario not in SCENARIOS,
        running=np.asarray(log.running, dtype=bool), commanded=log.commanded[:, rows, cols],
        position=log.joints[:, rows, cols], current=efforts if bus else None, torque=None if bus else efforts,
        power=np.asarray(log.power, dtype=float) if power_measured else None)


def _slots(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    from shc_cli.model.chains import joint_slots

    return joint_slots(robot)


def _check_robot(path: Path, run_robot: Robot, robot: Robot) -> None:
    """Refuse a run of another robot: everything but ``[servo]``, ``[hardware]`` and where the simulator started
    it (``start_up.simulation``: a run's ``--stand``/``--ground``) must be the same."""
    skip: dict[str, bool | set[str]] = {"servo": True, "hardware": True, "name": True, "description": True,
                                        "start_up": {"simulation"}}
    mine = robot.model_dump(mode="json", exclude=skip)
    theirs = run_robot.model_dump(mode="json", exclude=skip)
    if mine == theirs:
        return
    field = next((key for key in mine if mine[key] != theirs.get(key)), "?")
    raise _bad(path, f"was recorded with robot '{run_robot.name}', whose [{field}] differs from '{robot.name}'",
               "fit with the robot the run used (--robot), or record the run with it")


def _bad(path: Path, problem: str, fix: str) -> SpecError:
    return SpecError([Issue(Path(path), None, "", problem, fix)])
