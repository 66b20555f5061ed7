"""``--perception rays``: a simulated depth sensor feeding the controller's step-plane input (issue 40).

:class:`RayPerception` is an observer of the run loop and a wrapper of its input source. After each cycle it
takes the body's pose from the reading and, at the sensor's rate, casts the robot file's ``[perception]`` rays
into the engine's world (MuJoCo ``mj_multiRay``, PyBullet ``rayTestBatch``: terrain only), adds the sensor's
noise and fuses the points into the robot-centred height map (:mod:`shc_cli.backends.height_map`). Every command
the source gives then carries the map and the body's pose in it as :attr:`Command.terrain
<shc_cli.control.controller.Command.terrain>`, the controller's step-plane input (:mod:`shc_cli.control.step_plane`):
one cycle of latency, as any sensor. The odometry the map is fused with is the engine's body pose (a perfect
odometry: what the map shows is where the terrain is).
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING, Literal, Protocol, runtime_checkable

import numpy as np

from shc_cli.backends.height_map import DepthSensor, HeightMap
from shc_cli.control.step_plane import TerrainMap
from shc_cli.spec.robot import Perception

if TYPE_CHECKING:
    from shc_cli.backends.base import InputSource
    from shc_cli.backends.engine import Reading
    from shc_cli.control.controller import Command, CycleOutput
    from shc_cli.spec.robot import Robot

PerceptionMode = Literal["off", "rays"]
"""``--perception``: walk blind (OpenSHC) or see the ground through simulated rays."""
PERCEPTION_MODES: tuple[PerceptionMode, ...] = ("off", "rays")


@runtime_checkable
class RayCaster(Protocol):
    """An engine's world that casts rays into its terrain (PyBullet's and MuJoCo's ``cast_rays``)."""

    def cast_rays(self, origin: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
        ...


def rotation_of(rpy: np.ndarray) -> np.ndarray:
    """Body → world rotation of roll, pitch, yaw (extrinsic x, y, z: ``Rz·Ry·Rx``)."""
    roll, pitch, yaw = (float(a) for a in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch), math.cos(yaw), \
        math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


class RayPerception:
    """The simulated depth sensor, its height map, and the commands that carry it.

    Args:
        robot: the robot (its ``[perception]`` table, or the defaults).
        world: the engine's world (``cast_rays(origin, directions, reach)``).
        seed: seed of the sensor noise.
    """

    def __init__(self, robot: Robot, world: RayCaster, seed: int = 0) -> None:
        self.spec = robot.perception or Perception()
        self.sensor = DepthSensor(self.spec)
        self.grid = HeightMap.of(self.spec)
        self.world = world
        self.every = max(1, round(1.0 / (self.spec.rate * robot.time_delta)))
        """Control cycles per scan."""
        self.rng = np.random.default_rng(seed)
        self.scans = 0
        self.terrain: TerrainMap | None = None
        """The map and the body's pose after the last cycle (what the next command carries)."""
        self._levels: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def scan(self, position: np.ndarray, rotation: np.ndarray) -> int:
        """One scan from the body at ``position`` with ``rotation`` (body → world) fused into the map; the cells
        it saw."""
        origin, directions = self.sensor.rays(position, rotation)
        distances = self.world.cast_rays(origin, directions, self.spec.range[1])
        seen = self.grid.update(self.sensor.points(origin, directions, distances, self.rng), float(position[0]),
                                float(position[1]))
        self.scans += 1
        self._levels = {}  # the map changed: its level cells are computed again when asked for
        return seen

    def __call__(self, cycle: int, command: Command, out: CycleOutput, reading: Reading) -> str | None:
        position = np.asarray(reading.position, dtype=float)
        rotation = rotation_of(reading.rpy)
        if cycle % self.every == 0:
            self.scan(position, rotation)
        grid = self.grid
        self.terrain = TerrainMap(grid.heights, grid.cell, grid.centre, position, rotation, self._levels)
        return None

    def wrap(self, source: InputSource) -> PerceivingSource:
        """``source`` whose every command carries the map."""
        return PerceivingSource(source, self)


class PerceivingSource:
    """An input source whose commands carry the height map (a :class:`~shc_cli.backends.base.FeedbackSource` when
    the wrapped source is one)."""

    def __init__(self, source: InputSource, perception: RayPerception) -> None:
        self.source, self.perception = source, perception
        self._observe = getattr(source, "observe", None)

    def next(self) -> Command | None:
        command = self.source.next()
        terrain = self.perception.terrain
        if command is None or terrain is None:
            return command
        return dataclasses.replace(command, terrain=terrain)

    def observe(self, out: CycleOutput) -> None:
        if self._observe is not None:
            self._observe(out)

    def close(self) -> None:
        self.source.close()
