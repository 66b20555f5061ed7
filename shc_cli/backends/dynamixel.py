"""The hardware backend of ``run-hw``: Dynamixel servos on one or more buses, at the robot's control period.

Each cycle: goal positions clamped to the joint limits and to 1.5 × the joints' speed limits, one sync write per
bus (not in ``--dry-run``), the real-time wait (a drift-free deadline, ``next += period``; after an overrun the
deadline restarts from now), one sync read per bus. A reading with a servo that did not answer or whose status
carries the alert bit is a fault: the loop stops without writing another goal. The cycle time (from the read to
the goal write, the row and the controller included) goes to ``timing.csv``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import IO, TYPE_CHECKING, Protocol

import numpy as np

from shc_cli.backends.base import MEASURED_BODY_COLUMNS, Measured
from shc_cli.control.sensing import Sensors
from shc_cli.model.chains import joint_slots

if TYPE_CHECKING:
    from shc_cli.control.controller import CycleOutput
    from shc_cli.hardware.bus import BusState, ServoBus
    from shc_cli.spec.robot import Robot

class Tables(Protocol):
    """Where ``timing.csv`` goes: a run directory (:class:`shc_cli.record.runlog.RunDirectory`)."""

    def table(self, name: str, columns: list[str], formats: list[str]) -> tuple[IO[str], str]:
        """A new table: its file and its row format (``cycle``, ``t`` first)."""
        ...


UNMEASURED = ["<LEG>_<joint>_power", "<LEG>_force", "<LEG>_contact", *MEASURED_BODY_COLUMNS]
"""``log.csv`` columns a robot on servos does not measure (written as 0)."""


class DynamixelBackend:
    """Servos on buses as a backend.

    Args:
        robot: the robot.
        bus: the opened, checked and configured bus(es).
        dry_run: never enable the torque or write goals.
        run: the run directory (for ``timing.csv``), or None.
        on_fault: ``"hold"`` or ``"torque-off"`` after a fault.
        on_stop: ``"hold"`` or ``"torque-off"`` after a normal end.
        clock: the monotonic clock [s] (injectable for tests).
        sleep: the wait [s] (injectable for tests).
    """

    def __init__(self, robot: Robot, bus: ServoBus, dry_run: bool, run: Tables | None = None,
                 on_fault: str = "torque-off", on_stop: str = "torque-off",
                 clock: Callable[[], float] = time.perf_counter, sleep: Callable[[float], None] = time.sleep) -> None:
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

    def start(self) -> np.ndarray:
        """The servos' present positions (the controller starts from them)."""
        self.state = self.bus.read_state()
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
        self._began = self.clock()
        self.state = self.bus.read_state()
        return self.state

    def measured(self, reading: BusState) -> Measured:
        """Positions and currents (logged as the torque column, in A: the servo does not measure its torque)."""
        rows, cols = self.rows, self.cols
        return Measured(reading.positions[rows, cols], reading.currents[rows, cols] / 1000.0)

    def fault(self) -> str | None:
        """The first servo that failed and why (the rest of its bus unread), or the hardware errors named."""
        state, bus = self.state, self.bus
        assert state is not None
        if not state.answered.all():
            missing = [bus.slots[i].key for i in np.flatnonzero(~state.answered)]
            reasons = [f"{reason} from {bus.slots[i].key}" for i, reason in state.failures.items()]
            return f"{'; '.join(reasons) or 'no reply'} (unread: {', '.join(missing)})"
        if state.alerts.any():
            errors = bus.hardware_errors()
            flagged = [bus.slots[i].key for i in np.flatnonzero(state.alerts)]
            return ("; ".join(f"{key}: {', '.join(names)}" for key, names in errors.items())
                    or f"hardware error alert from {', '.join(flagged)}")
        return None

    def close(self, faulted: bool = False) -> None:
        """Torque off (or held, ``--on-fault``/``--on-stop``); the bus stays open for the caller to close."""
        release = self.on_fault if faulted else self.on_stop
        if self.torque_on and release == "torque-off":
            self.bus.torque(False)
            self.torque_on = False

    def statistics(self) -> dict[str, float | int]:
        """Cycle-time statistics [ms] and overruns for the summary."""
        times = np.array(self.cycle_times) * 1e3 if self.cycle_times else np.zeros(1)
        return {"cycle_time_mean_ms": float(times.mean()), "cycle_time_p99_ms": float(np.percentile(times, 99)),
                "cycle_time_max_ms": float(times.max()), "overruns": int(self.overruns)}
