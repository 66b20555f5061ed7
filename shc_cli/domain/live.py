"""``--live`` and ``--realtime`` for any run of the one loop (plan, simulate, run-hw, ``shc ros``): a Foxglove
server with the observer that streams each cycle to it, and the wall-clock pacer."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.control.controller import Controller
    from shc_cli.live.foxglove_server import FoxgloveTransport
    from shc_cli.loop.assembly import Assembly
    from shc_cli.loop.pacing import WallClock
    from shc_cli.ros.outputs import NodeOutputs
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


def open_live(port: int, robot: Robot, controller: Controller, sensors: bool,
              joint_states: bool = False) -> tuple[FoxgloveTransport, NodeOutputs]:
    """A Foxglove WebSocket server on 127.0.0.1:``port`` (0: any free port; its URL is logged as ``live: URL``) and
    the observer that streams each cycle's outputs to it (and a simulated reading's sensors when ``sensors``, a
    servo bus reading's measured joints when ``joint_states``). The caller closes the server when the run ends."""
    from shc_cli.live.foxglove_server import FoxgloveTransport
    from shc_cli.ros.messages import MessageTypes
    from shc_cli.ros.outputs import NodeOutputs, ideal_odometry

    transport = FoxgloveTransport(MessageTypes(), port)
    log.warning("live: %s (Foxglove WebSocket)", transport.url)
    outputs = NodeOutputs(transport, robot, individual=False, combined=True, sensors=sensors, always=False,
                          walkspace=lambda: controller.walkspace, joint_states=joint_states,
                          ideal=ideal_odometry(controller))
    return transport, outputs


def live_observer(parts: Assembly, enabled: bool, port: int, robot: Robot, controller: Controller, sensors: bool,
                  joint_states: bool = False) -> NodeOutputs | None:
    """With ``enabled`` (``--live``): :func:`open_live`'s observer, its server closed by the run's assembly
    (:class:`~shc_cli.loop.assembly.Assembly`) when the run is over; None without."""
    if not enabled:
        return None
    transport, outputs = open_live(port, robot, controller, sensors, joint_states)
    parts.closing(transport)
    return outputs


def wall_clock(robot: Robot) -> WallClock:
    """The pacer of ``--realtime``: one control period of wall time per cycle."""
    from shc_cli.loop.pacing import WallClock

    return WallClock(robot.time_delta)
