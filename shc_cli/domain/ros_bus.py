"""``shc ros --backend bus``: OpenSHC's node driving the robot's servos itself, with ``run-hw``'s safety.

The servo bus (:mod:`shc_cli.hardware`, every family ``run-hw`` drives) is opened and checked exactly as ``run-hw``
does (:func:`shc_cli.domain.hardware.prepare_bus`: every servo answers with its model, no hardware error, position
mode, limits that cover the joints', a bus fast enough for the control period — or a one-line refusal before the
torque goes on). The torque goes on only once the remote's ``system_state`` is OPERATIONAL, and the controller
starts from the joints measured then (direct shut-down allowed, as ``run-hw``); from then the remote's robot state
requests and velocities drive it, as they drive OpenSHC. Each cycle the servos' sync read is published on
``/joint_states`` (what OpenSHC's hardware node would publish) beside OpenSHC's outputs. A servo fault stops
commanding at once and holds or releases the torque (``on_fault``); Ctrl-C, SIGTERM, ``rosnode kill`` or the end of
``duration`` walk the robot to a stop and shut it down to ``stop_state`` before the torque goes off (``on_stop``).
While the remote is SUSPENDED the loop waits, as OpenSHC's does, the servos holding their last goal.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from shc_cli.domain.result import RunResult

if TYPE_CHECKING:
    from shc_cli.control.controller import Command, CycleOutput
    from shc_cli.domain.ros_config import NodeConfig
    from shc_cli.hardware.bus import BusState, ServoBus
    from shc_cli.loop.assembly import Assembly, Finished, RunSpec
    from shc_cli.loop.run_loop import RunLoop
    from shc_cli.record.summary import RunSummary
    from shc_cli.ros.transport import Node
    from shc_cli.spec.autopose import AutoPoseSet
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


def run_on_bus(node: Node, config: NodeConfig, robot: Robot, gait: Gait, pose_sets: dict[str, AutoPoseSet],
               gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunResult:
    """Run the node on the servos until a stop; returns the finished run directory (``summary.fault`` names a
    servo fault).

    Raises:
        HardwareError: the bus refused to start (one line), before the torque goes on and anything is written.
    """
    from shc_cli.loop.assembly import assemble

    return RunResult(*assemble(lambda parts: _on_bus(parts, node, config, robot, gait, pose_sets, gaits, directory,
                                                     on_ready)).pair)


def _on_bus(parts: Assembly, node: Node, c: NodeConfig, robot: Robot, gait: Gait, pose_sets: dict[str, AutoPoseSet],
            gaits: dict[str, Gait], directory: Path, on_ready: Callable[[str], None] | None) -> RunSpec[BusState]:
    """The node's run specification on the servos: the checked bus, the session, the wait for OPERATIONAL, the
    backend, a controlled stop at the deadline, the release of the torque as soon as the loop ends."""
    from shc_cli.backends.dynamixel import DynamixelBackend
    from shc_cli.control.controller import Controller
    from shc_cli.control.verified_limits import source_for
    from shc_cli.domain.hardware import STOP_TIMEOUT_S, Release, bus_run_fields, fault_action, prepare_bus
    from shc_cli.domain.live import live_observer
    from shc_cli.domain.ros_session import NodeSession
    from shc_cli.hardware.buses import servo_bus
    from shc_cli.loop.assembly import RunSpec
    from shc_cli.loop.input_sources import STATES
    from shc_cli.loop.run_loop import ControlledStop
    from shc_cli.record.runlog import LogRecorder, RunDirectory
    from shc_cli.record.summary_kinds import summary_of

    bus = parts.closing(servo_bus(robot, list(c.ports), c.baud, c.profile_velocity))
    prepare_bus(bus, robot, c.dry_run)
    joints = bus.read_state().positions
    controller = Controller(robot, gait, joints=joints, pose_sets=pose_sets, direct_shutdown=True,
                            speed_shares=source_for(robot))
    session = NodeSession(node, c, robot, controller, gaits, sensors=False, joint_states=True)
    session.ready(node, c, robot, gait, on_ready)
    # the torque goes on once the remote is OPERATIONAL (Ctrl-C meanwhile: nothing commanded, nothing written)
    operational = session.remote.wait_operational(float("inf"))
    if operational:
        _answering(bus)
        _unmoved(bus, robot, joints)
    run = parts.enter(RunDirectory(directory, c.overwrite))
    run.write_robot(robot)
    path_fields = session.keep_path(run.partial)
    backend = DynamixelBackend(robot, bus, c.dry_run or not operational, run, c.on_fault, c.on_stop)
    release = Release(backend)
    parts.callback(release.close)  # torque off (or held) also when the run raised
    backend.start()  # the goals start from the joints now (as the controller's, within MOVED_LIMIT)
    stop = STATES[c.stop_state]
    loop: RunLoop[BusState] | None = None

    def started(running: RunLoop[BusState]) -> None:
        nonlocal loop
        loop = running
        session.watch(running)

    def deadline(cycle: int, command: Command, out: CycleOutput, reading: object) -> str | None:
        """The duration has passed: walk to a stop and shut down (not an abrupt end, on servos)."""
        if session.limit is not None and time.monotonic() >= session.limit and loop is not None \
                and not loop.requested:
            loop.request_stop("end")
        return None

    def summarise(finished: Finished) -> RunSummary:
        return summary_of(("hardware", "ros"), {
            **bus_run_fields(robot, controller, backend, finished.result, c.dry_run, stop.name), "backend": "bus",
            "ros_master": node.master_uri, "node": node.name, **finished.shared})

    return RunSpec(controller, backend, session.source, LogRecorder(run, robot, backend), None, run, summarise,
                   ControlledStop(stop, STOP_TIMEOUT_S), observers=[session.outputs],
                   live=live_observer(parts, c.live, c.live_port, robot, controller, sensors=False, joint_states=True),
                   pacing=session.clock, late_observers=[deadline], path_fields=path_fields, after_loop=release,
                   on_loop=started, flush_every=100, on_fault=fault_action(c.on_fault))


def _answering(bus: ServoBus, tries: int = 3) -> None:
    """Read the bus until every servo answers (after the wait for the remote: the first read after a long idle may
    miss a reply, as run-hw's first cycle would retry it), or refuse to start naming the silent servos."""
    from shc_cli.hardware.bus import HardwareError

    for _ in range(tries):
        state = bus.read_state()
        if state.answered.all():
            return
    silent = ", ".join(bus.slots[i].key for i in (~state.answered).nonzero()[0])
    raise HardwareError(f"{bus.port_name}: refusing to start: no reply from {silent} after waiting for the remote")


MOVED_LIMIT = 0.05
"""A joint that moved more than this while the node waited for the remote refuses the start [rad]."""


def _unmoved(bus: ServoBus, robot: Robot, joints: np.ndarray) -> None:
    """Refuse to start, naming the joint, if one moved more than :data:`MOVED_LIMIT` since the controller was built
    from ``joints`` (someone moved the robot while the node waited: the first goals would pull it back)."""
    from shc_cli.hardware.bus import HardwareError
    from shc_cli.model.chains import joint_slots

    rows, cols = joint_slots(robot)
    moved = np.abs(bus.read_state().positions - joints)[rows, cols]
    worst = int(np.argmax(moved))
    if moved[worst] > MOVED_LIMIT:
        leg = list(robot.legs)[rows[worst]]
        joint = list(robot.legs[leg].joints)[cols[worst]]
        raise HardwareError(f"{bus.port_name}: refusing to start: {leg}_{joint} moved {moved[worst]:.2f} rad while "
                            "the node waited for the remote (restart shc ros with the robot still)")
