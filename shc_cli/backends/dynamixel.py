"""The hardware backend of ``run-hw``: Dynamixel servos on one or more buses, at the robot's control period.

Each cycle: goal positions clamped to the joint limits and to 1.5 × the joints' speed limits, one sync write per
bus (not in ``--dry-run``), the real-time wait (a drift-free deadline, ``next += period``; after an overrun the
deadline restarts from now), one sync read per bus. A status whose alert bit is set is a fault at once: the loop
stops without writing another goal. A missed reply is not (:class:`MissedReads`): the bus has already asked again
once within the cycle; a servo still unread stands in with its last reading (bridged, counted, an event) and only
``hardware.missed_reads_fault`` consecutive cycles without its reading are a fault — on a loaded computer (a
Raspberry Pi running a browser; a test machine at load 4) the reader is kept off the CPU for 40–70 ms at times, and
that is not a dead servo. The cycle time (from the read to the goal write, the row and the controller included)
goes to ``timing.csv``.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import IO, TYPE_CHECKING, Protocol

import numpy as np

from shc_cli.backends.base import MEASURED_BODY_COLUMNS, Measured
from shc_cli.control.sensing import Sensors
from shc_cli.events import event
from shc_cli.model.chains import joint_slots

if TYPE_CHECKING:
    from shc_cli.control.controller import CycleOutput
    from shc_cli.hardware.bus import BusState, ServoBus
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


class Tables(Protocol):
    """Where ``timing.csv`` goes: a run directory (:class:`shc_cli.record.runlog.RunDirectory`)."""

    def table(self, name: str, columns: list[str], formats: list[str]) -> tuple[IO[str], str]:
        """A new table: its file and its row format (``cycle``, ``t`` first)."""
        ...


UNMEASURED = ["<LEG>_<joint>_power", "<LEG>_force", "<LEG>_contact", *MEASURED_BODY_COLUMNS]
"""``log.csv`` columns a robot on servos does not measure (written as 0)."""


class MissedReads:
    """The rule for servos whose state read failed (no reply, a corrupt or error reply, after the bus's retry in
    the same cycle): their last reading stands in (bridged) until one of them has failed ``limit`` consecutive
    cycles, which is a fault. Counts what it bridged for the summary; each bridged cycle is an event
    (``read_bridged``, at INFO: ``events.log``, the terminal with ``-v``).

    A servo that is really silent is therefore a fault at its ``limit``-th cycle: within ``limit`` × (the period +
    the bus's two packet timeouts, ≈ 35 ms each with the vendors' SDKs, + up to 50 ms waiting for silence on
    Protocol 1.0 and Feetech buses) of its last reply.

    Args:
        keys: each servo's joint name (the bus's slot order).
        rows: each servo's row (leg) in the reading's padded ``(L, n)`` arrays.
        cols: each servo's column (joint) there.
        limit: consecutive failed cycles that are a fault (1: the first).
    """

    def __init__(self, keys: list[str], rows: np.ndarray, cols: np.ndarray, limit: int) -> None:
        self.keys, self.rows, self.cols, self.limit = keys, rows, cols, limit
        self.streak = np.zeros(len(keys), dtype=np.int64)
        """Each servo's consecutive cycles without a reading."""
        self.last: BusState | None = None
        self.bridged_cycles = 0
        """Cycles whose reading had a servo's last reading standing in."""
        self.bridged_reads = 0
        """Servo readings stood in for (a cycle that missed three servos counts three)."""
        self.longest = 0
        """The longest run of consecutive cycles any servo went without a reading."""
        self.fault: str | None = None

    def update(self, state: BusState) -> BusState:
        """The reading to use for ``state``: itself when every servo answered; else with the missing servos' last
        values (``bridged`` set), or unchanged with :attr:`fault` set when a servo reached :attr:`limit` or has
        no earlier reading."""
        missing = ~np.asarray(state.answered, dtype=bool)
        self.streak = np.where(missing, self.streak + 1, 0)
        if not missing.any():
            self.last = state
            return state
        self.longest = max(self.longest, int(self.streak.max()))
        reasons = "; ".join(f"{reason} from {self.keys[i]}" for i, reason in state.failures.items()) or "no reply"
        unread = ", ".join(self.keys[i] for i in np.flatnonzero(missing))
        worst = int(self.streak.max())
        if self.last is None or worst >= self.limit:
            cycles = (f" in {worst} consecutive cycle{'s' if worst > 1 else ''}" if self.last is not None
                      else " at the first reading")
            self.fault = f"{reasons}{cycles} (unread: {unread})"
            return state
        last, rows, cols = self.last, self.rows, self.cols
        positions, velocities, currents = state.positions.copy(), state.velocities.copy(), state.currents.copy()
        where = np.flatnonzero(missing)
        for values, previous in ((positions, last.positions), (velocities, last.velocities),
                                 (currents, last.currents)):
            values[rows[where], cols[where]] = previous[rows[where], cols[where]]
        self.bridged_cycles += 1
        self.bridged_reads += len(where)
        event(log, logging.INFO, "read_bridged", "%s: the last reading stands in for %s (%d of %d cycles allowed)",
              reasons, unread, worst, self.limit - 1)
        bridged = type(state)(positions, velocities, currents, state.answered, state.alerts, state.failures,
                              missing)
        self.last = bridged
        return bridged

    def statistics(self) -> dict[str, int]:
        """The summary's counts."""
        return {"bridged_cycles": self.bridged_cycles, "bridged_reads": self.bridged_reads,
                "missed_cycles_max": self.longest, "missed_reads_fault": self.limit}


class DynamixelBackend:
    """Servos on buses as a backend.

    Args:
        robot: the robot.
        bus: the opened, checked and configured bus(es).
        dry_run: never enable the torque or write goals.
        run: the run directory (for ``timing.csv``), or None.
        on_fault: ``"hold"`` or ``"torque-off"`` after a fault (``"adapt"``: a fault the run walks on from is no
            stop; any other turns the torque off).
        on_stop: ``"hold"`` or ``"torque-off"`` after a normal end.
        clock: the monotonic clock [s] (injectable for tests).
        sleep: the wait [s] (injectable for tests).
        missed_reads_fault: consecutive cycles without a servo's reading that are a fault (None: the robot file's
            ``hardware.missed_reads_fault``, else :data:`~shc_cli.spec.robot.MISSED_READS_FAULT`, 3;
            :class:`MissedReads`).
    """

    def __init__(self, robot: Robot, bus: ServoBus, dry_run: bool, run: Tables | None = None,
                 on_fault: str = "torque-off", on_stop: str = "torque-off",
                 clock: Callable[[], float] = time.perf_counter, sleep: Callable[[float], None] = time.sleep,
                 missed_reads_fault: int | None = None) -> None:
        from shc_cli.model.chains import Chains

        self.robot, self.bus, self.dry_run = robot, bus, dry_run
        self.on_fault, self.on_stop = on_fault, on_stop
        self.clock, self.sleep = clock, sleep
        self.dt = robot.time_delta
        chains = Chains.from_robot(robot)
        self.lower, self.upper = chains.lower, chains.upper
        self.max_step = chains.max_vel * self.dt * 1.5  # rate limit: 1.5 × the joint speed limit per cycle
        self.rows, self.cols = joint_slots(robot)
        self.timing = run.table("timing.csv", ["cycle_time_ms", "overrun"], ["%.4f", "%d"]) if run else None
        self.state: BusState | None = None
        self.goals: np.ndarray | None = None
        self.torque_on = False
        self.cycle_times: list[float] = []
        self.overruns = 0
        self._deadline = self._began = 0.0
        from shc_cli.spec.robot import MISSED_READS_FAULT

        limit = missed_reads_fault or robot.hardware.missed_reads_fault or MISSED_READS_FAULT
        self.misses = MissedReads([slot.key for slot in bus.slots], bus.layout.rows, bus.layout.cols, limit)
        self.failed_legs: list[str] = []
        """Legs set aside after a fault (``--on-fault adapt``): no goal is written to their servos any more."""

    def start(self) -> np.ndarray:
        """The servos' present positions (the controller starts from them): read again, up to the missed-reads
        limit, while a servo is missing (there is no earlier reading to stand in for it yet)."""
        for _ in range(self.misses.limit):
            state = self.bus.read_state()
            if state.answered.all():
                break
        self.state = self.misses.update(state)
        self.goals = self.state.positions.copy()
        return np.asarray(self.state.positions)

    def begin(self) -> None:
        if not self.dry_run:
            self.bus.torque(True)
            self.torque_on = True
        self._deadline = self._began = self.clock()

    def sensors(self, wanted: bool) -> Sensors | None:
        assert self.state is not None
        return Sensors(joints=self.state.positions)

    def apply(self, out: CycleOutput) -> np.ndarray:
        assert self.goals is not None
        target = np.clip(out.joints, self.lower, self.upper)
        self.goals = goals = self.goals + np.clip(target - self.goals, -self.max_step, self.max_step)
        if not self.dry_run:
            self.bus.write_goals(goals, self.dt)
        return np.asarray(goals)

    def advance(self) -> None:
        """The cycle's time and the wait for the next period."""
        now = self.clock()
        self.cycle_times.append(now - self._began)
        self._deadline += self.dt
        late = now > self._deadline
        self.overruns += late
        if self.timing is not None:
            handle, row = self.timing
            cycle = len(self.cycle_times) - 1
            handle.write(row % (cycle, cycle * self.dt, self.cycle_times[-1] * 1e3, late))
        if late:
            self._deadline = now  # drift-free while on time; after an overrun, restart from now
        else:
            self.sleep(self._deadline - now)

    def read(self) -> BusState:
        """The cycle's reading; a servo that missed it stands in with its last one (:class:`MissedReads`)."""
        self._began = self.clock()
        self.state = self.misses.update(self.bus.read_state())
        return self.state

    def measured(self, reading: BusState) -> Measured:
        """Positions and currents (logged as the torque column, in A: the servo does not measure its torque)."""
        rows, cols = self.rows, self.cols
        return Measured(reading.positions[rows, cols], reading.currents[rows, cols] / 1000.0)

    def fault(self) -> str | None:
        """A servo that missed its reading in ``missed_reads_fault`` consecutive cycles (the first that failed and
        why; the rest of its bus unread), or the hardware errors named."""
        state, bus = self.state, self.bus
        assert state is not None
        if self.misses.fault is not None:
            return self.misses.fault
        alerts = state.alerts.copy()
        alerts[list(bus.skipped)] = False  # a failed leg's servo keeps its error: walked on without it
        if alerts.any():
            skipped = {bus.slots[i].key for i in bus.skipped}
            errors = {key: names for key, names in bus.hardware_errors().items() if key not in skipped}
            flagged = [bus.slots[i].key for i in np.flatnonzero(alerts)]
            return ("; ".join(f"{key}: {', '.join(names)}" for key, names in errors.items())
                    or f"hardware error alert from {', '.join(flagged)}")
        return None

    def alerting_servos(self) -> list[str]:
        """The servos (keys, ``LEG_joint``) whose last status carried the hardware-error alert, but for the failed
        legs'."""
        assert self.state is not None
        return [self.bus.slots[i].key for i in np.flatnonzero(self.state.alerts) if i not in self.bus.skipped]

    def fail_leg(self, leg: str) -> None:
        """No goal to ``leg``'s servos from the next write on (their torque stays as it is: the servos hold their
        last goal, a faulted one is off by its own protection)."""
        slots = {i for i, slot in enumerate(self.bus.slots) if slot.key.startswith(f"{leg}_")}
        self.bus.skipped = frozenset(self.bus.skipped | slots)
        self.failed_legs.append(leg)

    def close(self, faulted: bool = False) -> None:
        """Torque off (or held, ``--on-fault``/``--on-stop``); the bus stays open for the caller to close."""
        release = self.on_fault if faulted else self.on_stop
        release = "torque-off" if release == "adapt" else release  # a fault adapt did not absorb: the safe stop
        if self.torque_on and release == "torque-off":
            self.bus.torque(False)
            self.torque_on = False

    def statistics(self) -> dict[str, float | int]:
        """Cycle-time statistics [ms] and overruns for the summary."""
        times = np.array(self.cycle_times) * 1e3 if self.cycle_times else np.zeros(1)
        return {"cycle_time_mean_ms": float(times.mean()), "cycle_time_p99_ms": float(np.percentile(times, 99)),
                "cycle_time_max_ms": float(times.max()), "overruns": int(self.overruns)}

    def bus_statistics(self) -> dict[str, int]:
        """The bus's repeated reads and the bridged ones (:class:`MissedReads`), for the summary."""
        return {"read_retries": self.bus.retries, **self.misses.statistics()}
