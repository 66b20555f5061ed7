"""The simulated depth sensor and the robot-centred height map (shc_cli.backends.height_map).

The sensor's geometry and the grid's bookkeeping against hand-worked numbers; the map made from each engine's ray
casts against :meth:`Terrain.height_at` on stairs and blocks (the robot held in the air at the origin).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from shc_cli.backends.engine import EngineOptions
from shc_cli.backends.engine_registry import open_engine
from shc_cli.backends.height_map import DepthSensor, HeightMap
from shc_cli.backends.terrain import parse_terrain
from shc_cli.model.chains import Chains
from shc_cli.spec.loading import load_robot, resolve
from shc_cli.spec.robot import Perception


def test_rays_span_the_field_of_view_about_the_pitched_axis() -> None:
    sensor = DepthSensor(Perception(pitch=0.5, fov=(1.0, 0.6), resolution=(3, 3)))
    assert sensor.count == 9
    assert np.allclose(np.linalg.norm(sensor.directions, axis=1), 1.0)
    centre = sensor.directions[4]  # the middle column of the middle row: the optical axis
    assert centre == pytest.approx([math.cos(0.5), 0.0, -math.sin(0.5)])
    # the top-left ray: yaw +1/3 rad (left), elevation +0.2 rad, in the pinhole's tangent plane, then pitched
    local = np.array([1.0, math.tan(1.0 / 3.0), math.tan(0.2)]) / math.hypot(1.0, math.tan(1.0 / 3.0), math.tan(0.2))
    c, s = math.cos(0.5), math.sin(0.5)
    assert sensor.directions[0] == pytest.approx([c * local[0] + s * local[2], local[1], -s * local[0] + c * local[2]])
    yaw = Rotation.from_euler("z", 0.7).as_matrix()
    origin, directions = sensor.rays(np.array([1.0, 2.0, 0.5]), yaw)
    assert origin == pytest.approx([1.0 + 0.1 * math.cos(0.7), 2.0 + 0.1 * math.sin(0.7), 0.55])
    assert directions[4] == pytest.approx(yaw @ centre)


def test_points_keep_the_range_and_add_noise_along_the_ray() -> None:
    sensor = DepthSensor(Perception(resolution=(2, 1), range=(0.2, 2.0), noise=0.01))
    origin = np.zeros(3)
    directions = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]])
    points = sensor.points(origin, directions, np.array([1.0, np.nan, 0.1, 2.5]))
    assert points.tolist() == [[1.0, 0.0, 0.0]]  # a miss, a too-near and a too-far ray are dropped
    rng = np.random.default_rng(0)
    many = sensor.points(origin, np.tile([[0.0, 0.0, -1.0]], (4000, 1)), np.full(4000, 1.0), rng)
    assert np.allclose(many[:, :2], 0.0)
    assert float(np.std(many[:, 2])) == pytest.approx(0.01, rel=0.05)


def test_map_keeps_the_highest_point_and_scrolls_with_the_robot() -> None:
    grid = HeightMap(0.1, 0.2)  # 5 × 5 cells centred on the robot's cell
    assert grid.size == 5 and np.isnan(grid.heights).all()
    seen = grid.update(np.array([[0.01, 0.0, 0.3], [0.04, 0.02, 0.5], [0.2, -0.2, 0.1], [0.9, 0.0, 7.0]]), 0.0, 0.0)
    assert seen == 2  # (0.9, 0) is outside the map
    assert grid.height_at(0.0, 0.0) == 0.5 and grid.height_at(0.2, -0.2) == 0.1
    assert math.isnan(grid.height_at(0.1, 0.0))
    grid.update(np.empty((0, 3)), 0.21, 0.0)  # two cells on along +x: the map scrolls, keeping what it saw
    assert grid.centre == (2, 0)
    assert grid.height_at(0.0, 0.0) == 0.5 and grid.height_at(0.2, -0.2) == 0.1
    grid.update(np.empty((0, 3)), 0.41, 0.0)  # x = 0 is now outside: forgotten
    assert math.isnan(grid.height_at(0.0, 0.0)) and grid.height_at(0.2, -0.2) == 0.1
    xs, ys = grid.cell_centres()
    assert xs[0, 0] == pytest.approx(0.2) and ys[0, 0] == pytest.approx(-0.2) and xs[4, 4] == pytest.approx(0.6)
    grid.update(np.array([[0.2, -0.2, 0.05]]), 0.41, 0.0)  # a newer scan replaces the cell
    assert grid.height_at(0.2, -0.2) == 0.05


@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
@pytest.mark.parametrize("text", ["stairs:0.05,0.3", "blocks"])
def test_map_from_engine_rays_is_the_terrain(engine: str, text: str) -> None:
    robot = load_robot(resolve("robots", "bullet")).robot
    world = open_engine(robot, EngineOptions(parse_terrain(text), 4, True, seed=5, engine=engine),  # type: ignore[arg-type]
                        Chains.from_robot(robot).default_joints())
    try:
        reading = world.read()
        sensor = DepthSensor(Perception(noise=0.0))
        origin, directions = sensor.rays(reading.position, Rotation.from_euler("xyz", reading.rpy).as_matrix())
        distances = world.cast_rays(origin, directions, sensor.spec.range[1])  # type: ignore[attr-defined]
        assert np.isfinite(distances).mean() > 0.9  # PyBullet: the rays that hit the legs 5 times are lost
        grid = HeightMap(0.05, 1.5)
        assert grid.update(sensor.points(origin, directions, distances), reading.position[0],
                           reading.position[1]) > 300
        terrain = world.terrain
        xs, ys = grid.cell_centres()
        inner = uneven = 0
        for x, y, mapped in zip(xs.ravel(), ys.ravel(), grid.heights.ravel(), strict=True):
            if math.isnan(mapped):
                continue
            levels = [terrain.height_at(x + dx, y + dy) for dx in (-0.025, 0.0, 0.02499) for dy in (-0.025, 0.0,
                                                                                                   0.02499)]
            if max(levels) == min(levels):  # a cell on one level: exactly it
                assert mapped == pytest.approx(levels[0], abs=1e-3), (x, y)
                inner += 1
            else:  # across an edge: between the levels (a ray on the face gives a height between them)
                assert min(levels) - 1e-3 <= mapped <= max(levels) + 1e-3, (x, y)
                uneven += 1
        assert inner > 100 and uneven > 0
    finally:
        world.close()
