"""A simulated depth sensor and the robot-centred 2.5-D height map it feeds (issue 40).

:class:`DepthSensor` is the robot file's ``[perception]`` table (:class:`~shc_cli.spec.robot.Perception`) as rays:
``columns × rows`` directions spread evenly over the field of view, about an optical axis pitched ``pitch`` below
the body's x axis, from ``mount`` in the body frame. An engine casts them (``cast_rays`` of the PyBullet and MuJoCo
worlds: terrain only, never the robot) and returns each ray's distance to the first hit (``nan``: nothing within
range); :meth:`DepthSensor.points` adds the sensor's noise along each ray, drops what lies outside its range and
gives the hit points in the world.

:class:`HeightMap` fuses the points into a grid of ``cell``-sized squares, axis-aligned in the odometry frame and
centred on the robot's odometry position (it scrolls by whole cells as the robot moves, forgetting what leaves
it): each cell seen in a scan takes the highest point of that scan in it, a cell not seen keeps its last height,
a cell never seen is ``nan``. The highest point, since a cell across an edge sees both levels and a foot on it
stands on the upper one. With true odometry the map is the terrain (``tests/test_height_map.py`` checks it against
:meth:`~shc_cli.backends.terrain.Terrain.height_at` on stairs and blocks).
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.spec.robot import Perception


class DepthSensor:
    """The rays of a depth sensor mounted on the body.

    Attributes:
        spec: The robot file's ``[perception]`` table.
        mount: Sensor origin in the body frame [m].
        directions: Unit ray directions in the body frame ``(columns·rows, 3)``, as an image: row by row from the top,
            each from the left.
    """

    def __init__(self, spec: Perception) -> None:
        self.spec = spec
        self.mount = np.array(spec.mount, dtype=float)
        columns, rows = spec.resolution
        horizontal, vertical = spec.fov
        yaw = horizontal / 2.0 - (np.arange(columns) + 0.5) / columns * horizontal  # + left, first column left
        elevation = vertical / 2.0 - (np.arange(rows) + 0.5) / rows * vertical  # + up, first row at the top
        yaws, elevations = np.meshgrid(yaw, elevation)  # (rows, columns)
        # in the sensor frame (x along the optical axis, y left, z up): a pinhole's evenly spaced pixel angles
        local = np.stack([np.ones_like(yaws), np.tan(yaws), np.tan(elevations)], axis=-1).reshape(-1, 3)
        local /= np.linalg.norm(local, axis=1, keepdims=True)
        c, s = math.cos(spec.pitch), math.sin(spec.pitch)
        pitch_down = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])  # Rot_y(+pitch): x axis tilts down
        self.directions = local @ pitch_down.T

    @property
    def count(self) -> int:
        """Rays per scan."""
        return int(self.directions.shape[0])

    def rays(self, position: np.ndarray, rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The sensor's origin (3,) and its rays' unit directions ``(count, 3)`` in the world, for a body at
        ``position`` with ``rotation`` (body to world)."""
        origin = np.asarray(position, dtype=float) + rotation @ self.mount
        return origin, self.directions @ np.asarray(rotation, dtype=float).T

    def points(self, origin: np.ndarray, directions: np.ndarray, distances: np.ndarray,
               rng: np.random.Generator | None = None) -> np.ndarray:
        """The points ``(m, 3)`` the sensor reports: each distance plus Gaussian noise of ``noise`` along its ray,
        kept if within ``range`` (a miss, ``nan``, never is)."""
        near, far = self.spec.range
        measured = np.asarray(distances, dtype=float)
        if rng is not None and self.spec.noise > 0.0:
            measured = measured + rng.normal(0.0, self.spec.noise, measured.shape)
        keep = np.isfinite(measured) & (measured >= near) & (measured <= far)
        points: np.ndarray = origin + directions[keep] * measured[keep, None]
        return points


class HeightMap:
    """A robot-centred grid of terrain heights [m] in the odometry frame (``nan``: never seen).

    Attributes:
        cell: Side of a cell [m].
        size: Cells along x and along y (odd: the robot's cell is the middle one).
        heights: ``(size, size)`` heights, x index along +x, y index along +y.
        centre: The (i, j) cell the map is centred on, in whole cells of the odometry frame.
    """

    def __init__(self, cell: float, extent: float) -> None:
        self.cell = cell
        half = max(1, math.ceil(extent / cell - 1e-9))
        self.size = 2 * half + 1
        self.heights = np.full((self.size, self.size), np.nan)
        self.centre = (0, 0)

    @classmethod
    def of(cls, spec: Perception) -> HeightMap:
        """An empty map of the robot file's ``cell`` and ``extent``."""
        return cls(spec.cell, spec.extent)

    def _index(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        half = self.size // 2
        return (np.floor(x / self.cell + 0.5).astype(np.int64) - self.centre[0] + half,
                np.floor(y / self.cell + 0.5).astype(np.int64) - self.centre[1] + half)

    def recentre(self, x: float, y: float) -> None:
        """Centre the map on the cell under the robot's odometry position (x, y) [m]: it scrolls by whole cells,
        and the cells that come in are unknown."""
        target = (math.floor(x / self.cell + 0.5), math.floor(y / self.cell + 0.5))
        di, dj = target[0] - self.centre[0], target[1] - self.centre[1]
        if di == 0 and dj == 0:
            return
        moved = np.full_like(self.heights, np.nan)
        n = self.size
        if abs(di) < n and abs(dj) < n:
            moved[max(0, -di):n - max(0, di), max(0, -dj):n - max(0, dj)] = \
                self.heights[max(0, di):n - max(0, -di), max(0, dj):n - max(0, -dj)]
        self.heights = moved
        self.centre = target

    def update(self, points: np.ndarray, x: float, y: float) -> int:
        """Fuse one scan's world points ``(m, 3)`` with the robot at odometry position (x, y) [m]; returns the
        cells it saw. Each seen cell takes the scan's highest point in it."""
        self.recentre(x, y)
        if len(points) == 0:
            return 0
        i, j = self._index(points[:, 0], points[:, 1])
        inside = (i >= 0) & (i < self.size) & (j >= 0) & (j < self.size)
        flat = i[inside] * self.size + j[inside]
        top = np.full(self.size * self.size, -np.inf)
        np.maximum.at(top, flat, points[inside, 2])
        seen = np.isfinite(top)
        self.heights.reshape(-1)[seen] = top[seen]
        return int(seen.sum())

    def cell_centres(self) -> tuple[np.ndarray, np.ndarray]:
        """World x and y [m] of every cell's centre, each ``(size, size)``."""
        half = self.size // 2
        offsets = np.arange(self.size) - half
        xs = (self.centre[0] + offsets) * self.cell
        ys = (self.centre[1] + offsets) * self.cell
        grid_x, grid_y = np.meshgrid(xs, ys, indexing="ij")
        return grid_x, grid_y

    def height_at(self, x: float, y: float) -> float:
        """The map's height of the cell under (x, y) [m]; ``nan`` if unknown or outside the map."""
        i, j = self._index(np.array([x]), np.array([y]))
        if 0 <= i[0] < self.size and 0 <= j[0] < self.size:
            return float(self.heights[i[0], j[0]])
        return math.nan
