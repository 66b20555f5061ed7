"""The run assembler (shc_cli/loop/assembly.py): what a build opens is closed in reverse order whatever happens, the
observers are told in the documented order, the summariser is given the fields every run shares once (nothing
patched in afterwards), a SIGTERM mid-run leaves a finished run directory, a spec without a run directory (a
replay) only runs the loop."""

from __future__ import annotations

import json
import os
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from shc_cli.backends.kinematic import KinematicBackend
from shc_cli.control.controller import Command, Controller, CycleOutput, RobotState
from shc_cli.errors import ShcError
from shc_cli.loop.assembly import Assembly, Finished, Outcome, Progress, RunSpec, assemble
from shc_cli.loop.pacing import WallClock
from shc_cli.loop.run_loop import NullRecorder, Observer, SequenceInput, StartUp
from shc_cli.record.runlog import RunWriter
from shc_cli.record.summary import RunSummary
from shc_cli.spec.loading import load_gait, load_robot
from shc_cli.spec.robot import Robot

WALK = [Command(velocity=(0.5, 0.0, 0.0))] * 30
"""Thirty walking cycles after the start-up."""


def _robot() -> Robot:
    robot = load_robot("bullet").robot
    assert robot is not None
    return robot


def _controller(robot: Robot) -> Controller:
    gait = load_gait("tripod").gait
    assert gait is not None
    return Controller(robot, gait)


def test_what_a_build_opens_is_closed_in_reverse_order_when_the_build_fails() -> None:
    closed: list[str] = []

    @contextmanager
    def part(name: str) -> Iterator[str]:
        try:
            yield name
        finally:
            closed.append(name)

    class Bus:
        def close(self) -> None:
            closed.append("bus")

    def build(parts: Assembly) -> RunSpec[None]:
        parts.enter(part("directory"))
        parts.closing(Bus())
        parts.callback(lambda: closed.append("torque off"))
        parts.enter(part("backend"))
        raise ShcError("robot.toml: bad input")

    with pytest.raises(ShcError, match="bad input"):
        assemble(build)
    assert closed == ["backend", "torque off", "bus", "directory"]


def test_a_recorded_run_is_summarised_once_with_the_shared_fields_and_observers_in_order(tmp_path: Path) -> None:
    robot = _robot()
    told: list[str] = []
    given: list[Finished] = []
    progress: list[tuple[int, int]] = []

    def named(name: str) -> Observer[None]:
        def observer(cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
            if cycle == 0:
                told.append(name)
            return None
        return observer

    class Clock(WallClock):
        def __call__(self, cycle: int, command: object, out: object, reading: object) -> str | None:
            if cycle == 0:
                told.append("pacing")
            return None  # not paced: the test does not wait

        def statistics(self) -> dict[str, float | int]:
            return {"realtime_ratio": 1.0}

    def build(parts: Assembly) -> RunSpec[None]:
        controller = _controller(robot)
        writer = RunWriter(tmp_path / "run", robot)
        parts.enter(writer)

        def summarise(finished: Finished) -> RunSummary:
            given.append(finished)
            assert (finished.directory / "joints.csv").read_text().count("\n") == finished.result.cycles + 1
            return RunSummary.model_validate({"robot": robot.name, "cycles": finished.result.cycles,
                                              **finished.shared})

        return RunSpec(controller, KinematicBackend(), SequenceInput(WALK), writer, StartUp.of(robot), writer,
                       summarise, observers=[named("kind")], progress=Progress(lambda *a: progress.append(a), 30),
                       live=named("live"), pacing=Clock(robot.time_delta), late_observers=[named("late")],
                       path_fields=lambda: {"path_file": "path.csv"})

    outcome = assemble(build)
    path, summary = outcome.pair
    assert told == ["kind", "live", "pacing", "late"] and len(given) == 1
    shared = given[0].shared
    assert shared["complete"] is True and shared["stop_reason"] == "end" and shared["realtime_ratio"] == 1.0
    assert shared["path_file"] == "path.csv" and "joint_speed_limited_cycles" in shared
    assert progress[0] == (0, 30) and progress[-1] == (30, 30)
    written = json.loads((path / "summary.json").read_text())
    assert written == json.loads(summary.to_json()) and written["complete"] is True
    assert path == tmp_path / "run" and not (tmp_path / "run.partial").exists()
    assert written["cycles"] == outcome.result.cycles > len(WALK)  # the start-up, then the walk


def test_a_sigterm_mid_run_leaves_a_finished_run_directory(tmp_path: Path) -> None:
    robot = _robot()

    def terminate(cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        if cycle == 5:
            os.kill(os.getpid(), signal.SIGTERM)  # the run's handler turns it into a stop request
        return None

    def build(parts: Assembly) -> RunSpec[None]:
        writer = RunWriter(tmp_path / "run", robot)
        parts.enter(writer)
        return RunSpec(_controller(robot), KinematicBackend(), SequenceInput(WALK), writer, StartUp.of(robot), writer,
                       lambda finished: RunSummary.model_validate(finished.shared), observers=[terminate])

    before = signal.getsignal(signal.SIGTERM)
    path, summary = assemble(build).pair
    written = json.loads((path / "summary.json").read_text())
    assert written["complete"] is False and written["stop_reason"] == "SIGTERM" and summary.stop_reason == "SIGTERM"
    assert (path / "joints.csv").read_text().count("\n") == 6 + 1  # cycles 0–5, then the header
    assert signal.getsignal(signal.SIGTERM) == before  # restored once the run is finished


def test_a_spec_without_a_run_directory_only_runs_the_loop() -> None:
    robot = _robot()
    states: list[RobotState] = []

    def observe(cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        states.append(out.robot_state)
        return None

    outcome: Outcome = assemble(lambda _: RunSpec(_controller(robot), KinematicBackend(), SequenceInput(WALK[:7]),
                                                  NullRecorder(), None, observers=[observe]))
    assert outcome.result.cycles == 7 == len(states) and outcome.path is None and outcome.summary is None
    with pytest.raises(AssertionError, match="without a run directory"):
        _ = outcome.pair
