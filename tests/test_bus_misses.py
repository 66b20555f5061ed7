"""A missed servo reply is not a dead servo (issue 42, point 2): the bus asks again once in the same cycle, a servo
still unread stands in with its last reading (bridged, counted), and only ``hardware.missed_reads_fault``
consecutive cycles without its reading are a fault — on every servo family.

Deterministic: the run-hw backend (:class:`~shc_cli.backends.dynamixel.DynamixelBackend`) is driven cycle by cycle
on the emulators' virtual clock (:class:`~shc_cli.hardware.emulator.VirtualClock`), and the misses are injected as
a count of status packets the emulated servo leaves unsent (``Faults.drop_replies``): one dropped packet is one
missed reply, answered by the retry; two in a cycle (the read and its retry) leave the servo unread that cycle.
Each drop costs the SDK's packet timeout (≈ 35 ms) of wall time, nothing else waits.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest

from shc_cli.backends.dynamixel import DynamixelBackend, MissedReads
from shc_cli.hardware.bus import BusState
from shc_cli.hardware.emulator import VirtualClock

JOINTS = [f"{leg}_{joint}" for leg in ("AR", "BR", "CR", "CL", "BL", "AL") for joint in ("coxa", "femur", "tibia")]
"""Servo id k + 1 drives JOINTS[k] (openshc_default's legs)."""
MISSED = 5
"""The servo that misses its replies: BR_femur."""
MODELS = {"XM430-W350": 116, "AX-12A": 30, "STS3215": 42}
"""One model of each family (Dynamixel Protocol 2.0 sync read, Protocol 1.0 read per servo, Feetech sync read) →
its Goal Position address."""


def _robot(folder: Path, model: str, extra: str = "") -> Path:
    lines = ['extends = "openshc_default"', 'name = "hexapod_bus"', "[start_up]", "time_to_start = 1.5", "[hardware]",
             f'model = "{model}"', "return_delay_us = 0", extra, "[hardware.servos]",
             *(f"{key} = {{ id = {k + 1} }}" for k, key in enumerate(JOINTS))]
    path = folder / "hexapod_bus.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@contextmanager
def _backend(folder: Path, model: str = "XM430-W350", limit: int | None = None
             ) -> Iterator[tuple[Any, DynamixelBackend, VirtualClock]]:
    """The backend on 18 emulated ``model`` servos (a thread of this process) on a virtual clock, started (the
    first reading taken, torque on)."""
    from shc_cli.hardware.buses import servo_bus
    from shc_cli.hardware.emulator import BusEmulator
    from shc_cli.hardware.emulator_protocol1 import Protocol1Emulator
    from shc_cli.spec.loading import load_robot

    robot = load_robot(str(_robot(folder, model))).robot
    clock = VirtualClock()
    servos = {k + 1: model for k in range(18)}
    emulator: Any = (BusEmulator(servos, clock=clock) if model == "XM430-W350"
                     else Protocol1Emulator(servos, clock=clock))
    with emulator:
        if isinstance(emulator, BusEmulator):
            clock.bus = emulator
        bus = servo_bus(robot, [emulator.port])
        bus.open()
        try:
            backend = DynamixelBackend(robot, bus, dry_run=False, clock=clock, sleep=clock.sleep,
                                       missed_reads_fault=limit)
            backend.start()
            backend.begin()
            yield emulator, backend, clock
        finally:
            bus.close()


def _cycle(backend: DynamixelBackend, goals: np.ndarray) -> tuple[BusState, str | None]:
    """One control cycle as the run loop does it: goals out, the period, the reading, the fault check."""
    backend.apply(SimpleNamespace(joints=goals))  # type: ignore[arg-type]
    backend.advance()
    return backend.read(), backend.fault()


def _slot(backend: DynamixelBackend, servo_id: int) -> int:
    return next(i for i, slot in enumerate(backend.bus.slots) if slot.servo_id == servo_id)


def _goals(backend: DynamixelBackend, cycle: int) -> np.ndarray:
    """Goals that move every joint a little each cycle (so a stale reading differs from a fresh one)."""
    assert backend.goals is not None
    return np.asarray(backend.goals + 0.01 * (1 + cycle % 3))


@pytest.mark.parametrize("model", list(MODELS))
def test_one_missed_reply_is_asked_again_in_the_same_cycle(model: str, tmp_path: Path) -> None:
    with _backend(tmp_path, model) as (emulator, backend, _):
        _cycle(backend, _goals(backend, 0))
        retries = backend.bus.retries
        emulator.faults(MISSED).drop_replies = 1
        reading, fault = _cycle(backend, _goals(backend, 1))
        assert fault is None and reading.answered.all() and reading.bridged is None
        assert backend.bus.retries >= retries + 1  # (more only if the loaded machine missed one too)
        assert emulator.faults(MISSED).drop_replies == 0  # the one reply was dropped
        assert backend.misses.bridged_cycles == 0 and backend.misses.longest == 0


@pytest.mark.parametrize("model", list(MODELS))
def test_n_minus_one_missed_cycles_are_bridged_with_the_last_reading(model: str, tmp_path: Path) -> None:
    """Two cycles (the limit 3 − 1) without BR_femur's reading: its last one stands in, flagged, the run goes on;
    the servos that answered are fresh; its next reply ends the streak."""
    with _backend(tmp_path, model) as (emulator, backend, _):
        slot = _slot(backend, MISSED)
        rows, cols = backend.bus.layout.rows, backend.bus.layout.cols
        before, _ = _cycle(backend, _goals(backend, 0))
        emulator.faults(MISSED).drop_replies = 2 * 2  # the read and its retry, in two cycles
        for cycle in (1, 2):
            reading, fault = _cycle(backend, _goals(backend, cycle))
            assert fault is None
            assert reading.bridged is not None and reading.bridged[slot] and not reading.answered[slot]
            for i in np.flatnonzero(reading.bridged):  # the last good reading, exactly
                assert reading.positions[rows[i], cols[i]] == before.positions[rows[i], cols[i]]
                assert reading.currents[rows[i], cols[i]] == before.currents[rows[i], cols[i]]
            fresh = np.flatnonzero(~reading.bridged)
            assert _slot(backend, 1) in fresh  # servo 1 is read before servo 5 on every family
            assert backend.misses.streak[slot] == cycle
        reading, fault = _cycle(backend, _goals(backend, 3))
        assert fault is None and reading.answered.all() and reading.bridged is None
        assert reading.positions[rows[slot], cols[slot]] != before.positions[rows[slot], cols[slot]]  # fresh again
        stats = backend.bus_statistics()
        assert stats["bridged_cycles"] == 2 and stats["missed_cycles_max"] == 2 and stats["missed_reads_fault"] == 3
        assert stats["bridged_reads"] >= 2 and stats["read_retries"] >= 2


@pytest.mark.parametrize("model", list(MODELS))
def test_n_consecutive_missed_cycles_are_a_fault_naming_the_servo(model: str, tmp_path: Path) -> None:
    with _backend(tmp_path, model) as (emulator, backend, _):
        _cycle(backend, _goals(backend, 0))
        emulator.faults(MISSED).drop_replies = 2 * 3
        faults = [_cycle(backend, _goals(backend, cycle))[1] for cycle in (1, 2, 3)]
        assert faults[:2] == [None, None]
        assert faults[2] is not None and faults[2].startswith("no reply from BR_femur in 3 consecutive cycles")


@pytest.mark.parametrize("model", ["XM430-W350", "AX-12A"])
def test_a_start_setting_whose_status_was_missed_is_written_again(model: str, tmp_path: Path) -> None:
    """The start's Return Delay Time writes (the emulated servos ship with 500 µs, the robot file says 0): a missed
    status is written once more, not a refusal to start; two missed are."""
    from shc_cli.hardware.bus import HardwareError

    with _backend(tmp_path, model) as (emulator, backend, _):
        bus, servo = backend.bus, emulator.servos[3]
        delay = servo.model.return_delay_time if model == "XM430-W350" else servo.addr["delay"]
        retries = bus.retries
        bus.return_delays = [500e-6] * 18  # as the start check reads them
        emulator.faults(3).drop_replies = 1
        assert bus.configure() == ["return delay time 0 µs written to 18 servos"]
        assert servo.table[delay] == 0 and bus.retries == retries + 1
        bus.return_delays = [500e-6] * 18
        emulator.faults(3).drop_replies = 2
        with pytest.raises(HardwareError, match="servo 3 refused Return Delay Time"):
            bus.configure()


def test_the_count_is_the_robot_files_and_one_faults_at_once(tmp_path: Path) -> None:
    from shc_cli.hardware.buses import servo_bus
    from shc_cli.spec.loading import load_robot

    for extra, limit in (("", 3), ("missed_reads_fault = 5", 5)):  # the default 3, or the robot file's
        robot = load_robot(str(_robot(tmp_path, "XM430-W350", extra))).robot
        assert DynamixelBackend(robot, servo_bus(robot, ["/dev/null"]), dry_run=True).misses.limit == limit
    with _backend(tmp_path, limit=1) as (emulator, backend, _):
        _cycle(backend, _goals(backend, 0))
        emulator.faults(MISSED).drop_replies = 2
        _, fault = _cycle(backend, _goals(backend, 1))
        assert fault is not None and fault.startswith("no reply from BR_femur in 1 consecutive cycle (")


def test_the_rule_on_made_up_readings() -> None:
    """:class:`MissedReads` alone: a servo that misses ``limit`` − 1 cycles, answers once, then misses again
    starts a new streak; a second servo's streak is its own; no reading before the first is a fault at once."""
    keys = ["a", "b"]
    rule = MissedReads(keys, np.array([0, 0]), np.array([0, 1]), 3)

    def state(value: float, answered: list[bool]) -> BusState:
        missing = {i: "no reply" for i, ok in enumerate(answered) if not ok}
        return BusState(np.full((1, 2), value), np.zeros((1, 2)), np.zeros((1, 2)), np.array(answered),
                        np.zeros(2, dtype=bool), missing)

    first = MissedReads(keys, np.array([0, 0]), np.array([0, 1]), 3)
    first.update(state(0.0, [False, True]))
    assert first.fault == "no reply from a at the first reading (unread: a)"
    rule.update(state(1.0, [True, True]))
    for value in (2.0, 3.0):
        out = rule.update(state(value, [False, True]))
        assert rule.fault is None and out.positions.tolist() == [[1.0, value]]
    rule.update(state(4.0, [True, True]))
    for value, answered in ((5.0, [False, True]), (6.0, [False, False]), (7.0, [True, False])):
        out = rule.update(state(value, answered))
        assert rule.fault is None
    assert out.positions.tolist() == [[7.0, 5.0]]
    rule.update(state(8.0, [True, False]))
    assert rule.fault == "no reply from b in 3 consecutive cycles (unread: b)"
    assert rule.statistics() == {"bridged_cycles": 5, "bridged_reads": 6, "missed_cycles_max": 3,
                                 "missed_reads_fault": 3}


class _Unplugging(VirtualClock):
    """The virtual clock of a run that unplugs a servo at virtual time ``at`` (the emulator's ``vanish``), or with
    ``drops`` makes it leave that many replies unsent from then on."""

    def __init__(self, at: float, drops: int | None = None) -> None:
        super().__init__()
        self.at, self.marker, self.wall, self.drops = self.now + at, -1, 0.0, drops
        self.cycles_after = 0

    def sleep(self, seconds: float) -> None:
        super().sleep(seconds)
        if self.marker >= 0:
            self.cycles_after += 1
        elif self.now >= self.at and self.bus is not None:
            servo = self.bus.servos[MISSED]
            if self.drops is None:
                servo.faults.vanish_after_packets = servo.packets_seen
            else:
                servo.faults.drop_replies = self.drops
            self.marker, self.wall = len(self.bus.packets), time.monotonic()


def test_a_run_that_bridged_two_cycles_ends_normally_and_says_so(tmp_path: Path) -> None:
    """run-hw's domain: BR_femur misses its replies in two consecutive cycles mid-walk; the run goes on to its end
    (no fault), the summary counts the two bridged cycles and a warning says it."""
    from shc_cli.domain.hardware import HardwareConfig, run_hardware
    from shc_cli.hardware.emulator import BusEmulator

    clock = _Unplugging(at=2.5, drops=2 * 2)
    with BusEmulator({k + 1: "XM430-W350" for k in range(18)}, clock=clock) as bus:
        clock.bus = bus
        result = run_hardware(HardwareConfig(robot=str(_robot(tmp_path, "XM430-W350")), ports=[bus.port],
                                             velocity="1,0,0", duration=3.0, out=tmp_path / "run",
                                             stop_state="running"), clock=clock, sleep=clock.sleep)
    summary = result.summary
    assert summary.fault is None and summary.stopped_by_request
    assert summary.bridged_cycles is not None and summary.bridged_cycles >= 2  # (+ any the loaded machine made)
    assert summary.missed_cycles_max is not None and summary.missed_cycles_max >= 2
    assert summary.read_retries is not None and summary.read_retries >= 2
    events = [json.loads(line) for line in (tmp_path / "run" / "events.log").read_text().splitlines()]
    [warning] = [e for e in events if e["event"] == "reads_bridged"]
    assert warning["level"] == "warning" and "cycles missed a servo's reading" in warning["message"]


def test_an_unplugged_servo_faults_within_the_stated_time_and_the_torque_goes_off(tmp_path: Path) -> None:
    """run-hw's domain on 18 emulated XM430-W350: BR_femur unplugged mid-run is a fault at the 3rd cycle without
    its reading (docs/commands.md: within 3 × (period + 2 packet timeouts), 0.24 s at 100 Hz), naming it; at most
    the two bridged cycles' goals go out after it went, and every other servo's torque is off."""
    from shc_cli.domain.hardware import HardwareConfig, run_hardware
    from shc_cli.hardware.emulator import BusEmulator

    clock = _Unplugging(at=2.5)
    stamped: list[tuple[str, float]] = []

    class Stamp(logging.Handler):
        def emit(self, record: logging.LogRecord) -> None:
            stamped.append((str(getattr(record, "event", "")), time.monotonic()))

    handler = Stamp()
    logging.getLogger("shc_cli").addHandler(handler)
    try:
        with BusEmulator({k + 1: "XM430-W350" for k in range(18)}, clock=clock) as bus:
            clock.bus = bus
            result = run_hardware(HardwareConfig(robot=str(_robot(tmp_path, "XM430-W350")), ports=[bus.port],
                                                 velocity="1,0,0", duration=5.0, out=tmp_path / "run"),
                                  clock=clock, sleep=clock.sleep)
            goal_writes = [p for p in bus.packets[clock.marker:] if p.instruction == 0x83
                           and int.from_bytes(p.params[0:2], "little") == 116]
            bus.drain(last=0x83, timeout=5.0)  # the torque-off SYNC WRITE has no reply: let the emulator take it
            torque = [bus.torque_on(k + 1) for k in range(18) if k + 1 != MISSED]
    finally:
        logging.getLogger("shc_cli").removeHandler(handler)
    summary = result.summary
    assert summary.fault is not None and summary.fault.startswith("no reply from BR_femur in 3 consecutive cycles")
    assert clock.cycles_after == 2  # the reads of cycles 1 and 2 bridged, the 3rd faulted (no wait after it)
    assert summary.missed_cycles_max == 3 and summary.missed_reads_fault == 3
    assert summary.bridged_cycles is not None and summary.bridged_cycles >= 2  # (+ any the loaded machine made)
    after = [name for name, at in stamped if at >= clock.wall]
    assert after[:after.index("fault")].count("read_bridged") == 2
    assert len(goal_writes) <= 2
    assert not any(torque)
    faulted = next(at for name, at in stamped if name == "fault")
    assert faulted - clock.wall < 3 * (0.01 + 2 * 0.040) + 2.0  # [s] of wall time; the slack is a loaded machine's
    events = [json.loads(line) for line in (tmp_path / "run" / "events.log").read_text().splitlines()]
    assert [e["event"] for e in events].count("fault") == 1


@pytest.mark.parametrize("value", ["0", "101"])
def test_a_count_out_of_range_is_one_line_and_exit_2(value: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    from tests.test_cli import run

    code, _, stderr = run(["run-hw", "bullet", "--port", "/dev/ttyNOTHERE0", "--missed-reads-fault", value,
                           "--out", str(tmp_path / "run")], capsys, monkeypatch)
    assert code == 2 and stderr.count("\n") == 1, stderr
    assert "--missed-reads-fault" in stderr and "give 1 to 100" in stderr and "Traceback" not in stderr
    code, _, stderr = run(["validate", str(_robot(tmp_path, "XM430-W350", f"missed_reads_fault = {value}"))], capsys,
                          monkeypatch)
    assert code == 2 and "missed_reads_fault" in stderr, stderr
