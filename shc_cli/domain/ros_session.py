"""What every backend of ``shc ros`` shares: the remote input, the outputs, the wall clock and the stop conditions
(:mod:`shc_cli.domain.ros_node`, :mod:`shc_cli.domain.ros_bus`)."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.control.controller import Controller
    from shc_cli.domain.ros_config import NodeConfig
    from shc_cli.loop.run_loop import ReadingT, RunLoop
    from shc_cli.ros.transport import Node
    from shc_cli.spec.gait import Gait
    from shc_cli.spec.robot import Robot


class NodeSession:
    """What every backend shares: the remote input (with the path follower), the outputs, the clock and the stop
    conditions (``sensors``: a simulated robot's sensors are published, ``joint_states``: a servo bus's measured
    joints, whose bus keeps the period: the clock only measures)."""

    def __init__(self, node: Node, config: NodeConfig, robot: Robot, controller: Controller,
                 gaits: dict[str, Gait], sensors: bool, joint_states: bool = False) -> None:
        from shc_cli.loop.pacing import WallClock
        from shc_cli.ros.outputs import NodeOutputs, ideal_odometry
        from shc_cli.ros.path_remote import RemotePath
        from shc_cli.ros.remote import RemoteInput
        from shc_cli.spec.path import load_path

        self.requested: Callable[[], bool] = lambda: False
        self.limit = None if config.duration is None else time.monotonic() + config.duration
        self.remote = RemoteInput(node, robot, gaits, stopped=self.stopped)
        node.serve_parameters(robot, self.remote)
        self.path = load_path(config.path) if config.path is not None else None
        self.source = RemotePath(self.remote, controller, self.path)
        self.source.subscribe(node)
        self.outputs = NodeOutputs(node, robot, config.individual, config.combined,
                                   walkspace=lambda: controller.walkspace, after=self.remote.latch, sensors=sensors,
                                   always=True, joint_states=joint_states, ideal=ideal_odometry(controller))
        self.clock = WallClock(robot.time_delta, pace=not joint_states)

    def keep_path(self, directory: Path) -> Callable[[], dict[str, object]]:
        """The ``--path`` file copied into the run ``directory``; the summary's path fields when called."""
        name = None
        if self.path is not None and self.path.source is not None:
            import shutil

            name = "path.toml" if self.path.source.suffix.lower() == ".toml" else "path.csv"
            shutil.copyfile(self.path.source, directory / name)
        return lambda: {**({"path_file": name} if name else {}), **self.source.summary()}

    def watch(self, loop: RunLoop[ReadingT]) -> None:
        """Ask ``loop`` whether a stop was requested (the run assembler tells the loop before it runs)."""
        self.requested = lambda: loop.requested

    def stopped(self) -> bool:
        """A stop was requested, or the duration passed (also while waiting for OPERATIONAL)."""
        return self.requested() or (self.limit is not None and time.monotonic() >= self.limit)

    def deadline(self, cycle: int, command: object, out: object, reading: object) -> str | None:
        """An observer that ends the run when the duration has passed."""
        return "end" if self.limit is not None and time.monotonic() >= self.limit else None

    def ready(self, node: Node, config: NodeConfig, robot: Robot, gait: Gait,
              on_ready: Callable[[str], None] | None) -> None:
        if on_ready is not None:
            on_ready(f"{node.program}: {robot.name} / {gait.name} as node {node.name} on {node.master_uri} (backend "
                     f"{config.backend}); waiting for /syropod_remote/system_state OPERATIONAL; Ctrl-C stops")
