"""The numbers behind `shc view` and `shc render`: poses of the model's shapes, frame timing, paths."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from shc_cli.model.chains import Chains
from shc_cli.record.summary import RunSummary
from shc_cli.spec.robot import Robot
from shc_cli.view import scene
from shc_cli.view.render import frame_rows, scene_xml

angles = st.floats(-3.0, 3.0)


@settings(max_examples=50, deadline=None)
@given(angles, angles, angles)
def test_rpy_quaternion_is_scipys_zyx(roll: float, pitch: float, yaw: float) -> None:
    expected = Rotation.from_euler("ZYX", [yaw, pitch, roll])
    x, y, z, w = expected.as_quat()
    q = scene.rpy_quaternion(np.array([roll, pitch, yaw]))
    assert np.allclose(q, [w, x, y, z]) or np.allclose(q, [-w, -x, -y, -z])


@settings(max_examples=50, deadline=None)
@given(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(lambda v: np.linalg.norm(v) > 1e-3))
def test_z_to_turns_z_onto_the_direction(direction: tuple[float, float, float]) -> None:
    w, x, y, z = scene.z_to(np.array([direction]))[0]
    turned = Rotation.from_quat([x, y, z, w]).apply([0.0, 0.0, 1.0])
    assert np.allclose(turned, np.array(direction) / np.linalg.norm(direction), atol=1e-9)


def test_z_to_straight_down_is_a_half_turn() -> None:
    w, x, y, z = scene.z_to(np.array([[0.0, 0.0, -2.0]]))[0]
    assert np.allclose(Rotation.from_quat([x, y, z, w]).apply([0, 0, 1]), [0, 0, -1])


def test_poses_put_the_feet_at_the_chains_tips_in_the_world(bullet: Robot) -> None:
    shape = scene.shapes(bullet)
    chains = Chains.from_robot(bullet)
    rng = np.random.default_rng(1)
    q = rng.uniform(chains.lower, chains.upper, size=(3, *chains.lower.shape))
    position = rng.normal(size=(3, 3))
    rpy = rng.uniform(-0.5, 0.5, size=(3, 3))
    pose = scene.poses(shape, q, position, rpy)
    for n in range(3):
        expected = Rotation.from_euler("ZYX", rpy[n, ::-1]).apply(chains.tips(q[n])) + position[n]
        assert np.allclose(pose.feet[n], expected)
    # every link keeps its DH length |(r, d)| whatever the joints
    lengths = np.linalg.norm(np.diff(pose.origins, axis=2), axis=3)
    for i, leg in enumerate(bullet.legs.values()):
        for k, joint in enumerate(leg.joints.values()):
            assert np.allclose(lengths[:, i, k], np.hypot(joint.r, joint.d))


def test_at_limit_marks_joints_at_their_limits(bullet: Robot) -> None:
    shape = scene.shapes(bullet)
    q = shape.chains.default_joints()
    q[0, 0] = shape.chains.upper[0, 0]
    q[2, 1] = shape.chains.lower[2, 1] + 0.5 * scene.LIMIT_MARGIN
    hit = scene.at_limit(shape, q)
    assert hit[0, 0] and hit[2, 1]
    q[0, 0] -= 0.01
    assert not scene.at_limit(shape, q)[0, 0]


def test_frame_rows_sample_time_at_fps_times_speed() -> None:
    t = np.arange(0, 1001) * 0.01  # 10 s at 100 Hz
    rows = frame_rows(t, 25.0, 1.0)
    assert len(rows) == 251 and rows[1] == 4 and rows[-1] == 1000
    fast = frame_rows(t, 25.0, 2.0)
    assert len(fast) == 126 and fast[1] == 8


def test_workplane_outline_is_closed_and_has_the_radii() -> None:
    plane = {0: 0.1, 90: 0.2, 180: 0.3, 270: 0.4, 360: 0.1}
    outline = scene.workplane_outline(plane, (1.0, 2.0), 0.0)
    assert np.allclose(outline, [[1.1, 2, 0], [1, 2.2, 0], [0.7, 2, 0], [1, 1.6, 0], [1.1, 2, 0]])


def test_scene_xml_has_one_mocap_body_per_link_and_foot(bullet: Robot) -> None:
    terrain = scene.TerrainShapes("blocks", [scene.Box((1, 0, 0.05), (0.1, 0.1, 0.1), 0.0, (0.5, 0.5, 0.5))])
    xml = scene_xml(scene.shapes(bullet), terrain, 64, 48)
    assert xml.count('mocap="true"') == 1 + 30 + 6
    assert xml.count('type="box"') == 2  # the body and the terrain block


def test_terrain_shapes_follow_the_summary(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from shc_cli.backends.terrain import Terrain, parse_terrain

    assert scene.terrain_shapes(RunSummary()) == scene.TerrainShapes("flat", [])
    stairs = scene.terrain_shapes(RunSummary(terrain="stairs:0.05,0.3", seed=0))
    assert stairs.text == "stairs:0.05,0.3" and len(stairs.boxes) > 3 and stairs.mesh is None
    assert max(b.centre[2] + b.size[2] / 2 for b in stairs.boxes) > 0.5
    field = tmp_path / "field.csv"
    field.write_text("0,0.1,0.2\n0.3,0.4,0.5\n", encoding="utf-8")
    text = f"heightfield:{field},1,0.1"
    shapes = scene.terrain_shapes(RunSummary(terrain=text))
    assert shapes.mesh is not None
    vertices, faces = shapes.mesh
    assert vertices.shape == (6, 3) and faces.shape == (4, 3)
    # every triangle lies on the simulation's ground (Terrain.height_at, PyBullet's split of each cell): its
    # centroid's height is the ground's there
    terrain = Terrain(parse_terrain(text), 0)
    centroids = vertices[faces].mean(axis=1)
    assert all(abs(terrain.height_at(x, y) - z) < 1e-9 for x, y, z in centroids)
    assert sorted(vertices[:, 2]) == sorted([0.0, 0.1, 0.2, 0.3, 0.4, 0.5])
    assert scene.terrain_shapes(RunSummary(terrain="heightfield:/nowhere.csv")).mesh is None


def test_level_terrains_are_drawn_at_the_robots_scale() -> None:
    from shc_cli.spec.loading import load_robot, resolve

    bullet = load_robot(resolve("robots", "bullet")).robot  # body clearance 0.20 m: × 0.4 of legged_gym's
    steps = scene.terrain_shapes(RunSummary(terrain="steps:1", seed=0), bullet)
    assert abs(steps.boxes[0].size[2] - 0.092) < 1e-9  # the rise, (0.05 + 0.18) m × 0.4
    assert abs(steps.boxes[0].size[0] - 0.124) < 1e-9  # the run, 0.31 m × 0.4


def _synthetic_run(robot: Robot, rows: int = 400) -> object:
    """A run that walks a circle: forward 0.2 m/s while turning 0.5 rad/s, legs in the default joints."""
    from pathlib import Path

    from shc_cli.record.runread import RunLog

    dt = robot.time_delta
    t = np.arange(rows) * dt
    desired = np.tile([0.2, 0.0, 0.5], (rows, 1))
    yaw = 0.5 * t
    position = np.column_stack([0.4 * np.sin(yaw), 0.4 * (1 - np.cos(yaw)), np.full(rows, 0.1)])
    chains = Chains.from_robot(robot)
    joints = np.tile(chains.default_joints(), (rows, 1, 1))
    contact = np.zeros((rows, len(robot.legs)), dtype=bool)
    contact[: rows // 2, ::2] = True
    return RunLog(path=Path("synthetic"), kind="plan", summary=RunSummary(), robot=robot, t=t,
                  running=np.ones(rows, bool),
                  walk_state=np.full(rows, "MOVING"), command=desired, desired=desired, position=position,
                  rpy=np.column_stack([np.zeros(rows), np.zeros(rows), yaw]), joints=joints, contact=contact,
                  power=np.linspace(10.0, 50.0, rows))


def test_commanded_path_integrates_the_desired_velocity_along_the_heading(bullet: Robot) -> None:
    from shc_cli.view.server import commanded_path

    run = _synthetic_run(bullet)
    path = commanded_path(run)  # type: ignore[arg-type]
    # a circle of radius v/ω = 0.4 m, as the synthetic body path; forward Euler drifts by at most v·ω·dt·t/2 = 2 mm
    assert np.abs(path[:, :2] - run.position[:, :2]).max() < 2e-3  # type: ignore[attr-defined]
    assert np.abs(path[-1, :2] - run.position[-1, :2]).max() < 2e-3  # type: ignore[attr-defined]


def test_plot_cursor_moves_with_time(bullet: Robot) -> None:
    from shc_cli.view.server import PlotImage

    run = _synthetic_run(bullet)
    plot = PlotImage(run)  # type: ignore[arg-type]

    def cursor_x(time_s: float) -> float:
        red = (plot.at(time_s)[..., 0] > 200) & (plot.at(time_s)[..., 1] < 60) & (plot.at(time_s)[..., 2] < 60)
        columns = np.flatnonzero(red.sum(axis=0) > 0.5 * (plot.bottom - plot.top))
        assert len(columns)
        return float(columns.mean())

    start, middle, end = cursor_x(0.0), cursor_x(2.0), cursor_x(3.99)
    assert start < middle < end
    assert abs((middle - start) / (end - start) - 2.0 / 3.99) < 0.02


def test_the_commanded_path_starts_where_running_starts(bullet: Robot) -> None:
    """During start-up nothing is commanded and the body only rises: the path starts at the first RUNNING cycle
    (it began with a vertical line from the spawn height)."""
    from dataclasses import replace

    from shc_cli.view.server import commanded_path

    run = _synthetic_run(bullet)
    rows = len(run.t)  # type: ignore[attr-defined]
    running = np.arange(rows) >= 50
    position = run.position.copy()  # type: ignore[attr-defined]
    position[:50, 2] = np.linspace(0.05, 0.2, 50)  # rising during start-up
    started = replace(run, running=running, position=position)  # type: ignore[type-var]
    path = commanded_path(started)  # type: ignore[arg-type]
    assert len(path) == rows - 50 and np.allclose(path[0], position[50])


def test_a_closed_tabs_late_message_is_not_a_warning() -> None:
    import warnings

    from shc_cli.view.server import quiet_closed_connections

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        quiet_closed_connections()
        warnings.warn("Queued a GuiUpdateMessage on a closed connection (e.g. via a handle owned by a disconnected "
                      "client); it will never be delivered.", stacklevel=1)
        warnings.warn("another warning", stacklevel=1)
    assert [str(w.message) for w in caught] == ["another warning"]  # only viser's closed-tab message is dropped
