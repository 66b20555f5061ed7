"""``out=DIR``: each episode of ``shc/Walk-v0`` written as a normal run directory ``DIR/episode-NNNN`` (``log.csv``,
``robot.toml``, ``summary.json``, as ``shc simulate --no-plots`` writes them; no ``events.log``)."""

from __future__ import annotations

from pathlib import Path

from shc_cli.backends.engine import Reading
from shc_cli.backends.simulated import SimulatedBackend
from shc_cli.control.controller import Controller
from shc_cli.domain.config import SimulationConfig
from shc_cli.loop.physics_summary import PhysicsRecord
from shc_cli.loop.run_loop import LoopResult, Observer, Recorder
from shc_cli.record.runlog import LogRecorder, RunDirectory
from shc_cli.spec.robot import Robot
from shc_cli.version import __version__


class EpisodeRecord:
    """The run directory of one episode (:func:`open_episode`): its recorder and observer for the loop."""

    def __init__(self, directory: Path, robot: Robot, backend: SimulatedBackend, config: SimulationConfig) -> None:
        self.run = RunDirectory(directory, overwrite=True)
        self.run.__enter__()
        self.run.write_robot(robot)
        self.config, self.backend = config, backend
        self.physics = PhysicsRecord(robot, backend, config.airborne)
        self.recorder: Recorder[Reading] = LogRecorder(self.run, robot, backend)
        self.observer: Observer[Reading] = self.physics

    def finish(self, result: LoopResult, controller: Controller) -> Path:
        """Close the log and write the summary (as ``shc simulate`` does); the finished directory."""
        import numpy as np

        self.run.close()
        world = self.backend.world
        summary = self.physics.summary(self.run.partial, self.config.scenario, controller.gait.name, controller)
        limited = controller.joint_speed_limited_cycles
        summary = summary.updated(
            seed=self.config.seed, terrain=str(world.terrain.spec), engine=world.name, engine_version=world.version,
            engine_warnings=world.warnings, versions={"shc": __version__, world.name: world.version,
                                                      "numpy": np.__version__},
            complete=result.complete, stop_reason=result.stop_reason, joint_speed_limited_cycles=limited,
            joint_speed_limited_share=limited / controller.cycles if controller.cycles else 0.0)
        path = self.run.finish(summary)
        self.run.__exit__(None)
        return path
