"""The step-plane input (shc_cli.control.step_plane): a height map given with the command shapes the footholds,
the swing clearance and the body height; a level map changes nothing."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.control import stepping
from shc_cli.control.controller import Command, Controller, RobotState
from shc_cli.control.step_plane import StepPlanes, StepPlaneSettings, TerrainMap
from shc_cli.validation import load_checked

CELL = 0.05
SIZE = 81  # ±2 m


def _map(height_of: Callable[[float, float], float],
         position: tuple[float, float, float] = (0.0, 0.0, 0.2)) -> TerrainMap:
    """A map centred on the origin whose cell (i, j) has ``height_of(x, y)`` at its centre."""
    offsets = (np.arange(SIZE) - SIZE // 2) * CELL
    xs, ys = np.meshgrid(offsets, offsets, indexing="ij")
    heights = np.vectorize(height_of)(xs, ys).astype(float)
    return TerrainMap(heights, CELL, (0, 0), np.array(position), np.eye(3))


def _walk(terrain: TerrainMap | None, cycles: int) -> Controller:
    """The default Bullet's controller: 600 cycles standing up, then walking forward with ``terrain`` given, the
    body placed in it by the controller's ideal odometry (the world the pure controller walks in)."""
    robot, gait, _ = load_checked("bullet", None)
    controller = Controller(robot, gait)
    for cycle in range(600 + cycles):
        walking = cycle >= 600
        seen = None
        if walking and terrain is not None and controller.walker is not None:
            x, y, _ = controller.walker.odometry_position
            yaw = controller.walker.odometry_yaw
            c, s = np.cos(yaw), np.sin(yaw)
            seen = TerrainMap(terrain.heights, CELL, (0, 0), np.array([x, y, 0.2]),
                              np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]))
        controller.step(Command(velocity=(1.0, 0.0, 0.0) if walking else (0.0, 0.0, 0.0),
                                state_request=RobotState.RUNNING, terrain=seen))
    return controller


STEP_X = 0.5
"""A 0.1 m step up across the map, 0.1 m beyond the Bullet's front feet."""
RISE = 0.1


def test_the_robot_walks_onto_a_platform_its_map_shows() -> None:
    """Walked onto a 0.1 m platform it sees: every foot stands 0.1 m up in the walk-plane frame and the body rides
    0.2 m above it (its clearance) — values from the map, not from the code; blind, everything stays at 0."""
    platform = _map(lambda x, y: RISE if x >= STEP_X else 0.0)
    controller = _walk(platform, 700)
    walker = controller.walker
    assert walker is not None
    assert STEP_X + 0.6 < walker.odometry_position[0] < 2.0 - 0.5  # hind feet past the edge, front ones on the map
    stance = walker.legs.floats[:, stepping.SWING_PROGRESS] < 0.0
    assert stance.sum() >= 3
    np.testing.assert_allclose(walker.legs.vectors[stance, stepping.CURRENT, 2], RISE, atol=0.005)
    assert walker.walk_plane[2] == pytest.approx(RISE, abs=0.01)
    assert controller.poser.walk_plane_pose.position[2] == pytest.approx(RISE + 0.2, abs=0.01)
    blind = _walk(None, 700).walker
    assert blind is not None
    np.testing.assert_allclose(blind.legs.vectors[stance, stepping.CURRENT, 2], 0.0, atol=0.005)


def test_a_level_map_walks_exactly_as_blind() -> None:
    """A flat map is no information: the same joints as without one (OpenSHC's blind walk)."""
    blind, seeing = _walk(None, 400), _walk(_map(lambda x, y: 0.0), 400)
    np.testing.assert_allclose(seeing.model.joints, blind.model.joints, atol=1e-9)
    assert seeing.walker is not None and blind.walker is not None
    np.testing.assert_allclose(seeing.walker.legs.vectors[:, stepping.TARGET],
                               blind.walker.legs.vectors[:, stepping.TARGET], atol=1e-12)


def _one_leg(terrain: TerrainMap, target: tuple[float, float, float], tip: tuple[float, float, float] = (0.0, 0.0, 0.0),
             swing_height: float = 0.15) -> tuple[np.ndarray, np.ndarray]:
    """One stance leg's (offset, clearance) for a target and tip in a walk-plane frame whose origin is the map's
    (the body pose: identity at the map's body position minus its height)."""
    planes = StepPlanes(1, StepPlaneSettings())
    body = np.asarray(terrain.position)
    return planes.update(terrain, np.array([target]), np.array([tip]), body.copy(), np.eye(3), np.array([-1.0]),
                         swing_height)


def test_a_target_on_an_edge_moves_to_level_ground() -> None:
    """A target right on a 0.1 m edge moves at least ``edge_margin`` (one cell) off it and lands at the height of
    the side it moved to."""
    terrain = _map(lambda x, y: RISE if x >= 0.3 else 0.0)  # the edge: between the cells at 0.25 and 0.30 m
    offsets, _ = _one_leg(terrain, (0.3, 0.0, 0.0))
    landed_x = 0.3 + offsets[0, 0]
    assert abs(landed_x - 0.275) >= StepPlaneSettings().edge_margin - 1e-9
    assert abs(offsets[0, 0]) <= StepPlaneSettings().max_shift + 1e-12 and offsets[0, 1] == 0.0
    assert offsets[0, 2] == pytest.approx(RISE if landed_x > 0.3 else 0.0, abs=1e-12)


def test_an_obstacle_on_the_swing_path_raises_the_clearance() -> None:
    """A 0.18 m bar between foot and target (both on the ground): clearance 0.18 + 0.04 margin; without it the
    walker's swing height."""
    bar = _map(lambda x, y: 0.18 if 0.1 <= x <= 0.2 else 0.0)
    _, clearance = _one_leg(bar, (0.35, 0.0, 0.0))
    assert clearance[0] == pytest.approx(0.18 + StepPlaneSettings().clearance_margin, abs=1e-12)
    _, flat = _one_leg(_map(lambda x, y: 0.0), (0.35, 0.0, 0.0))
    assert flat[0] == 0.15


@settings(max_examples=40, deadline=None)
@given(height=st.floats(-1.0, 1.0), x=st.floats(-0.5, 0.5), y=st.floats(-0.5, 0.5))
def test_a_plateau_at_any_height_is_flat_ground(height: float, x: float, y: float) -> None:
    """Heights are measured from where the foot stands: a level map at any height shifts nothing."""
    offsets, clearance = _one_leg(_map(lambda _x, _y: height, (x, y, height + 0.2)), (0.3, 0.1, 0.0))
    assert offsets.tolist() == [[0.0, 0.0, 0.0]] and clearance[0] == 0.15


def test_unknown_ground_is_walked_blind() -> None:
    """Cells never seen (nan) leave the leg as OpenSHC would: no shift, the swing height."""
    offsets, clearance = _one_leg(_map(lambda x, y: np.nan), (0.3, 0.0, 0.0))
    assert offsets.tolist() == [[0.0, 0.0, 0.0]] and clearance[0] == 0.15
