"""Simulator terrains: ``--terrain`` parsing, the bodies built in PyBullet and the analytic ground height.

Ray hits (``rayTest``) and resting spheres are compared with :meth:`Terrain.height_at`. On the ramp's slope
rays are only checked to Bullet's convex ray-cast tolerance (its GJK cast stops within 1 mm of a rotated
box, measured up to 1.01 mm high); resting spheres check the slope to 1 mm.
"""

from __future__ import annotations

import math
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pybullet
import pytest

from shc_cli.backends.pybullet_.terrain_bodies import build_terrain
from shc_cli.backends.terrain import (
    FEATURE_END_X,
    FEATURE_START_X,
    HALF_WIDTH,
    LANDING_END_X,
    PLATFORM_START_X,
    Terrain,
    TerrainSpec,
    parse_terrain,
    robot_scale,
)
from shc_cli.errors import SpecError

ROOT = Path(__file__).resolve().parents[1]
MM = 1e-3
SPHERE = 0.01


@pytest.fixture
def client() -> Iterator[int]:
    c = pybullet.connect(pybullet.DIRECT)
    yield c
    pybullet.disconnect(physicsClientId=c)


def ray_height(c: int, x: float, y: float) -> float:
    hit = pybullet.rayTest([x, y, 20.0], [x, y, -1.0], physicsClientId=c)[0]
    assert hit[0] >= 0, f"ray at ({x}, {y}) hit nothing"
    return float(hit[3][2])


def sample_points(n: int = 1500, seed: int = 1) -> np.ndarray:
    """Points over the start area, the features, the landings and beyond their sides."""
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-2.5, LANDING_END_X + 1.0, n), rng.uniform(-2.0, 2.0, n)])


def on_slope(spec: TerrainSpec, x: float, y: float) -> bool:
    return spec.kind == "ramp" and FEATURE_START_X < x < FEATURE_END_X and abs(y) <= HALF_WIDTH


# -- parsing ---------------------------------------------------------------------------------------------------


def test_parse_every_form(field_csv: Path) -> None:
    assert parse_terrain("flat").kind == "flat"
    ramp = parse_terrain(" Ramp:10 ")
    assert (ramp.kind, ramp.degrees, str(ramp)) == ("ramp", 10.0, "Ramp:10")
    default = parse_terrain("blocks")
    assert (default.low, default.high, default.size) == (0.04, 0.13, 0.1)
    two = parse_terrain("blocks:0.02,0.08")
    assert (two.low, two.high, two.size) == (0.02, 0.08, 0.1)
    three = parse_terrain("blocks:0.02, 0.08, 0.2")
    assert (three.low, three.high, three.size) == (0.02, 0.08, 0.2)
    stairs = parse_terrain("stairs:0.05,0.3")
    assert (stairs.kind, stairs.rise, stairs.run) == ("stairs", 0.05, 0.3)
    field = parse_terrain(f"heightfield:{field_csv}")
    assert (field.kind, field.path, field.scale, field.cell) == ("heightfield", field_csv, 1.0, 0.05)
    assert (len(field.heights), len(field.heights[0])) == (12, 8)  # x samples, y samples
    assert field.heights[11][7] == pytest.approx(0.3)  # last column, first line: +x end, +y edge
    scaled = parse_terrain(f"heightfield:{field_csv},0.5,0.1")
    assert (scaled.scale, scaled.cell) == (0.5, 0.1)
    assert np.allclose(np.array(scaled.heights), 0.5 * np.array(field.heights))


def test_parse_png_heightfields(tmp_path: Path) -> None:
    from matplotlib import image

    grey = np.linspace(0.0, 1.0, 6 * 5).reshape(6, 5)
    rgba = tmp_path / "rgba.png"
    image.imsave(rgba, grey, cmap="gray", vmin=0.0, vmax=1.0)  # colour PNG with R = G = B
    spec = parse_terrain(f"heightfield:{rgba}")
    assert spec.scale == 0.1  # default: 0.1 m per full white
    assert np.allclose(np.array(spec.heights), 0.1 * grey[::-1, :].T, atol=2 * 0.1 / 255)  # 8-bit levels
    from PIL import Image as pil  # Pillow comes with matplotlib

    levels = np.arange(12, dtype=np.uint16).reshape(3, 4) * 5000
    grey16 = tmp_path / "grey16.png"
    pil.fromarray(levels.astype(np.uint16)).save(grey16)
    spec16 = parse_terrain(f"heightfield:{grey16},0.3")
    assert np.allclose(np.array(spec16.heights), (levels / 65535.0 * 0.3)[::-1, :].T, atol=1e-6)


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("ramps:10", "did you mean 'ramp'"),
        ("stair:0.05,0.3", "did you mean 'stairs'"),
        ("moon", "unknown terrain 'moon'"),
        ("", "no terrain given"),
        ("flat:1", "flat takes no values"),
        ("ramp", "ramp takes 1 value, got none"),
        ("ramp:ten", "ramp slope 'ten' is not a number"),
        ("ramp:nan", "not finite"),
        ("ramp:-5", "ramp slope -5° is outside"),
        ("ramp:60", "outside (0, 45]"),
        ("blocks:0.13,0.04", "block LOW 0.13 m is above HIGH 0.04 m"),
        ("blocks:4,13", "block HIGH 13 m is outside"),
        ("blocks:-0.1,0.1", "negative"),
        ("blocks:0.04", "got 1 value"),
        ("blocks:0.04,0.13,0.01", "block SIZE 0.01 m"),
        ("blocks:0.04,,0.1", "empty value"),
        ("stairs:0.05", "stairs takes 2 values"),
        ("stairs:0,0.3", "stair rise 0 m"),
        ("stairs:0.05,x", "stair run 'x' is not a number"),
        ("heightfield:no/such/file.csv", "not found"),
        ("heightfield:field.txt", "neither .csv nor .png"),
        ("heightfield", "heightfield takes 1 value"),
        ("stairs-down:0.05", "stairs-down takes 2 values"),
        ("stairs-down:0.05,0.01", "stair run 0.01 m"),
        ("stairs-dwn:0.05,0.3", "did you mean 'stairs-down'"),
        ("slope", "slope takes 1 value"),
        ("steps:1.5", "steps difficulty 1.5 is outside [0, 1]"),
        ("gaps:-0.1", "outside [0, 1]"),
        ("stones:hard", "stones difficulty 'hard' is not a number"),
        ("obstacles:0.2,0.3", "obstacles takes 1 value"),
    ],
)
def test_bad_terrains_are_one_line(text: str, expected: str) -> None:
    with pytest.raises(SpecError) as caught:
        parse_terrain(text)
    (issue,) = caught.value.issues
    assert issue.field == "--terrain" and issue.file is None and issue.line is None
    assert issue.fix, "every terrain error says how to fix it"
    message = str(caught.value)
    assert expected in message
    assert "\n" not in message and message.startswith("--terrain: ")


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ("0,0.1\n0.2\n", "cannot read height field"),
        ("0,0.1,0.2\n", "1 × 3 samples"),
        ("0,-0.1\n0.2,0.1\n", "below the ground"),
        ("0,nan\n0.2,0.1\n", "nan or inf"),
        ("0,abc\n0.2,0.1\n", "cannot read height field"),
    ],
)
def test_bad_heightfield_files(tmp_path: Path, content: str, expected: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(SpecError) as caught:
        parse_terrain(f"heightfield:{path}")
    assert expected in str(caught.value) and "\n" not in str(caught.value)
    with pytest.raises(SpecError, match="SCALE -1"):
        parse_terrain(f"heightfield:{path},-1")


def test_parsing_does_not_import_pybullet() -> None:
    code = ("import sys; from shc_cli.backends.terrain import parse_terrain; parse_terrain('blocks'); "
            "print('pybullet' in sys.modules)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert result.stdout.strip() == "False"


# -- geometry --------------------------------------------------------------------------------------------------


def test_analytic_heights() -> None:
    ramp = Terrain(parse_terrain("ramp:10"), seed=0)
    top = math.tan(math.radians(10.0)) * (FEATURE_END_X - FEATURE_START_X)
    assert ramp.height_at(0.45, 0.0) == 0.0
    assert ramp.height_at(1.5, 0.0) == pytest.approx(math.tan(math.radians(10.0)))
    assert ramp.height_at(8.0, 1.0) == pytest.approx(top)
    assert ramp.height_at(8.0, 1.6) == 0.0 and ramp.height_at(10.5, 0.0) == 0.0
    stairs = Terrain(parse_terrain("stairs:0.05,0.3"), seed=0)
    assert [stairs.height_at(x, 0.0) for x in (0.45, 0.55, 0.85, 1.15)] == pytest.approx([0.0, 0.05, 0.1, 0.15])
    steps = math.floor((FEATURE_END_X - FEATURE_START_X) / 0.3)
    assert stairs.height_at(9.0, 0.0) == pytest.approx(steps * 0.05)  # the last step is the top landing
    blocks = Terrain(parse_terrain("blocks"), seed=3)
    assert blocks.block_heights is not None and blocks.block_heights.shape == (56, 30)
    assert blocks.block_heights.min() >= 0.04 and blocks.block_heights.max() <= 0.13
    assert blocks.height_at(0.45, -1.45) == blocks.block_heights[0, 0]
    assert blocks.height_at(5.95, 1.45) == blocks.block_heights[-1, -1]
    assert blocks.height_at(6.05, 0.0) == 0.0


BULLET = robot_scale(0.20)
"""The default Bullet's scale of the level terrains (body clearance 0.20 m over 0.5 m)."""


def test_level_terrains_follow_legged_gym() -> None:
    """legged_gym's numbers (terrain.py) × body_clearance / 0.5, worked by hand for the Bullet (× 0.4)."""
    assert pytest.approx(0.4) == BULLET
    slope = Terrain(parse_terrain("slope:0.5"), seed=0, scale=BULLET)
    assert (slope.spec.kind, slope.spec.text) == ("ramp", "slope:0.5")
    assert slope.spec.degrees == pytest.approx(11.459156)
    assert slope.height_at(1.5, 0.0) == pytest.approx(math.tan(0.2))  # 0.4·0.5 rad, not scaled
    assert Terrain(parse_terrain("slope:0"), seed=0).boxes() == []
    steps = Terrain(parse_terrain("steps:1"), seed=0, scale=BULLET)
    assert (steps.spec.rise, steps.spec.run) == pytest.approx((0.092, 0.124))  # 0.23·0.4, 0.31·0.4
    assert steps.height_at(0.5 + 2.5 * 0.124, 0.0) == pytest.approx(3 * 0.092)
    obstacles = Terrain(parse_terrain("obstacles:0.5"), seed=2, scale=BULLET)
    assert obstacles.block_heights is not None and obstacles.spec.size == pytest.approx(0.4)
    assert set(np.round(obstacles.block_heights.ravel(), 9)) == {0.0, 0.03, 0.06}  # h = 0.15·0.4, h/2, none
    stones = Terrain(parse_terrain("stones:1"), seed=0, scale=BULLET)
    assert (stones.spec.size, stones.spec.gap, stones.spec.depth) == pytest.approx((0.03, 0.04, 0.4))
    gaps = Terrain(parse_terrain("gaps:0.5"), seed=0, scale=BULLET)
    assert (gaps.spec.size, gaps.spec.gap, gaps.spec.depth) == pytest.approx((0.4, 0.2, 0.4))
    # the first gap is x in [0.5, 0.7), the first piece [0.7, 1.1), the second gap [1.1, 1.3)
    assert [gaps.height_at(x, 0.0) for x in (0.45, 0.6, 0.9, 1.2, 1.4)] == pytest.approx([0.4, 0, 0.4, 0, 0.4])
    assert Terrain(parse_terrain("gaps:0"), seed=0, scale=BULLET).height_at(3.0, 0.0) == pytest.approx(0.4)


def test_stairs_down_start_on_a_platform() -> None:
    stairs = Terrain(parse_terrain("stairs-down:0.15,0.3"), seed=0)
    top = 18 * 0.15  # ⌊5.5 / 0.3⌋ = 18 drops of 0.15 m
    assert stairs.start_height == pytest.approx(top)
    assert [stairs.height_at(x, 0.0) for x in (PLATFORM_START_X, 0.0, 0.499, 0.5, 0.85, 5.9, 7.0)] == pytest.approx(
        [top, top, top, top - 0.15, top - 0.3, 0.0, 0.0])
    assert stairs.height_at(PLATFORM_START_X - 0.01, 0.0) == 0.0 and stairs.height_at(0.0, HALF_WIDTH + 0.01) == 0.0
    boxes = stairs.boxes()
    assert len(boxes) == 18 and boxes[0].size[2] == pytest.approx(top) and boxes[-1].size[2] == pytest.approx(0.15)


@pytest.mark.parametrize("text", ["stairs-down:0.05,0.3", "stones:0", "stones:1", "gaps:1"])
def test_raised_start_platform_is_flat(text: str) -> None:
    terrain = Terrain(parse_terrain(text), seed=5, scale=BULLET)
    assert terrain.start_height > 0.0
    for x in np.linspace(PLATFORM_START_X, 0.4999, 40):
        for y in np.linspace(-HALF_WIDTH, HALF_WIDTH, 9):
            assert terrain.height_at(float(x), float(y)) == terrain.start_height


@pytest.mark.parametrize("text", ["flat", "ramp:10", "ramp:30", "blocks", "blocks:0,0.2,0.05", "stairs:0.05,0.3",
                                  "stairs:0.12,0.25", "heightfield", "slope:1", "steps:1", "obstacles:1"])
def test_start_area_is_flat(text: str, field_csv: Path) -> None:
    spec = parse_terrain(f"heightfield:{field_csv}" if text == "heightfield" else text)
    terrain = Terrain(spec, seed=5, scale=BULLET)
    for x in np.linspace(-1.0, 0.3999, 40):
        for y in np.linspace(-2.0, 2.0, 9):
            assert terrain.height_at(float(x), float(y)) == 0.0


# -- building --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("text", ["flat", "ramp:10", "ramp:5", "ramp:45", "blocks", "blocks:0,0.2,0.05",
                                  "stairs:0.05,0.3", "stairs:0.12,0.25", "heightfield", "stairs-down:0.15,0.3",
                                  "slope:0.5", "steps:0.5", "obstacles:1", "stones:0.5", "stones:1", "gaps:0.7"])
def test_rays_hit_height_at(client: int, text: str, field_csv: Path) -> None:
    spec = parse_terrain(f"heightfield:{field_csv},1,0.1" if text == "heightfield" else text)
    terrain = build_terrain(client, spec, friction=0.8, restitution=0.0, seed=11, scale=BULLET)
    spec = terrain.spec
    slope_tolerance = 1.02 * MM / math.cos(math.radians(spec.degrees))
    for x, y in sample_points():
        hit, expected = ray_height(client, x, y), terrain.height_at(x, y)
        if on_slope(spec, x, y):
            assert abs(hit - expected) <= slope_tolerance, (x, y, hit, expected)
        else:
            assert hit == pytest.approx(expected, abs=MM), (x, y, hit, expected)


def test_heightfield_placement(client: int, field_csv: Path) -> None:
    spec = parse_terrain(f"heightfield:{field_csv},1,0.1")
    terrain = build_terrain(client, spec, friction=0.8, restitution=0.0, seed=0)
    x_end, y_edge = FEATURE_START_X + 11 * 0.1, 3.5 * 0.1  # 12 samples along x from 0.5; 8 along y, centred
    assert terrain.height_at(x_end, y_edge) == pytest.approx(0.3)
    assert ray_height(client, x_end - 1e-4, y_edge - 1e-4) == pytest.approx(0.3, abs=MM)
    assert terrain.height_at(x_end + 0.01, 0.0) == 0.0 and terrain.height_at(1.0, y_edge + 0.01) == 0.0
    for x, y in np.random.default_rng(3).uniform([0.5, -0.35], [1.6, 0.35], size=(500, 2)):  # inside the field
        assert ray_height(client, x, y) == pytest.approx(terrain.height_at(x, y), abs=MM)


def drop_points(spec: TerrainSpec, terrain: Terrain) -> list[tuple[float, float]]:
    """Points at least a sphere radius away from every edge."""
    if spec.kind == "blocks":
        return [(0.4 + (i + 0.5) * spec.size, -1.5 + (j + 0.5) * spec.size) for i, j in [(0, 0), (3, 7), (20, 15),
                                                                                          (40, 29), (55, 2)]]
    if spec.kind == "stairs":
        return [(FEATURE_START_X + (k + 0.5) * spec.run, 0.3 * k - 1.0) for k in range(6)] + [(8.0, 0.0)]
    if spec.kind == "heightfield":
        return [(0.55, 0.0), (0.73, 0.12), (1.2, -0.2), (1.5, 0.3)]
    return [(-0.5, 0.0), (0.3, 1.0), (1.0, 0.0), (2.5, -1.0), (4.0, 1.2), (5.5, 0.0), (8.0, 0.5)]


def ground_normal_z(spec: TerrainSpec, terrain: Terrain, x: float, y: float) -> float:
    """cos of the ground's slope under (x, y), from height_at's finite differences."""
    d = 1e-4
    gx = (terrain.height_at(x + d, y) - terrain.height_at(x - d, y)) / (2 * d)
    gy = (terrain.height_at(x, y + d) - terrain.height_at(x, y - d)) / (2 * d)
    return 1.0 / math.sqrt(1.0 + gx * gx + gy * gy)


@pytest.mark.parametrize("text", ["flat", "ramp:10", "ramp:20", "blocks", "stairs:0.05,0.3", "heightfield"])
def test_spheres_rest_on_height_at(client: int, text: str, field_csv: Path) -> None:
    spec = parse_terrain(f"heightfield:{field_csv},0.5,0.1" if text == "heightfield" else text)
    terrain = build_terrain(client, spec, friction=1.0, restitution=0.0, seed=4)
    pybullet.setGravity(0.0, 0.0, -9.81, physicsClientId=client)
    shape = pybullet.createCollisionShape(pybullet.GEOM_SPHERE, radius=SPHERE, physicsClientId=client)
    spheres = []
    for x, y in drop_points(spec, terrain):
        lift = SPHERE / ground_normal_z(spec, terrain, x, y) + 0.002
        body = pybullet.createMultiBody(0.01, shape, basePosition=[x, y, terrain.height_at(x, y) + lift],
                                        physicsClientId=client)
        pybullet.changeDynamics(body, -1, lateralFriction=1.0, rollingFriction=0.01, spinningFriction=0.01,
                                physicsClientId=client)
        spheres.append(body)
    for _ in range(240):
        pybullet.stepSimulation(physicsClientId=client)
    for body in spheres:
        (x, y, z), _ = pybullet.getBasePositionAndOrientation(body, physicsClientId=client)
        gap = (z - terrain.height_at(x, y)) * ground_normal_z(spec, terrain, x, y) - SPHERE
        assert abs(gap) <= MM, (text, x, y, z, gap)


def test_blocks_are_one_compound_body(client: int) -> None:
    terrain = build_terrain(client, parse_terrain("blocks"), friction=0.8, restitution=0.0, seed=0)
    assert terrain.block_heights is not None
    plane, blocks = terrain.body_ids
    assert pybullet.getCollisionShapeData(plane, -1, physicsClientId=client)[0][2] == pybullet.GEOM_PLANE
    assert pybullet.getNumBodies(physicsClientId=client) == 2
    assert pybullet.getNumJoints(blocks, physicsClientId=client) == 0
    shapes = pybullet.getCollisionShapeData(blocks, -1, physicsClientId=client)
    assert len(shapes) == terrain.block_heights.size == 56 * 30
    assert all(shape[2] == pybullet.GEOM_BOX for shape in shapes)


def test_blocks_are_deterministic_per_seed() -> None:
    spec = parse_terrain("blocks")
    heights = []
    rays = []
    for seed in (5, 5, 6):
        c = pybullet.connect(pybullet.DIRECT)
        try:
            terrain = build_terrain(c, spec, friction=0.8, restitution=0.0, seed=seed)
            assert terrain.block_heights is not None
            heights.append(terrain.block_heights.copy())
            rays.append([ray_height(c, x, y) for x, y in sample_points(200, seed=2)])
        finally:
            pybullet.disconnect(physicsClientId=c)
    assert np.array_equal(heights[0], heights[1]) and rays[0] == rays[1]
    assert not np.array_equal(heights[0], heights[2]) and rays[0] != rays[2]


@pytest.mark.parametrize("text", ["flat", "ramp:10", "blocks", "stairs:0.05,0.3", "heightfield"])
def test_friction_and_restitution_on_every_body(client: int, text: str, field_csv: Path) -> None:
    spec = parse_terrain(f"heightfield:{field_csv}" if text == "heightfield" else text)
    terrain = build_terrain(client, spec, friction=0.63, restitution=0.21, seed=0)
    assert terrain.body_ids and pybullet.getNumBodies(physicsClientId=client) == len(terrain.body_ids)
    for body in terrain.body_ids:
        for link in range(-1, pybullet.getNumJoints(body, physicsClientId=client)):
            info = pybullet.getDynamicsInfo(body, link, physicsClientId=client)
            assert info[1] == pytest.approx(0.63) and info[5] == pytest.approx(0.21)


def test_building_prints_nothing(capfd: pytest.CaptureFixture[str], client: int, field_csv: Path) -> None:
    capfd.readouterr()
    for text in ("blocks", "ramp:10", f"heightfield:{field_csv}"):
        build_terrain(client, parse_terrain(text), friction=0.8, restitution=0.0, seed=0)
    assert capfd.readouterr().out == ""


@pytest.mark.slow  # two short simulations
@pytest.mark.parametrize("engine", ["mujoco", "pybullet"])
def test_simulate_starts_on_a_raised_platform(tmp_path: Path, engine: str, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """The robot spawns on the 0.9 m start platform of stairs-down:0.05,0.3 (18 drops of 0.05 m), stands up and walks
    without falling: its body stays about its clearance above the platform, not 0.9 m up in the air."""
    import json

    from .test_cli import run

    code, _, err = run(["simulate", "bullet", "--engine", engine, "--terrain", "stairs-down:0.05,0.3", "--duration",
                        "1", "--no-plots", "--out", str(tmp_path / "run")], capsys, monkeypatch)
    assert code == 0, err
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["terrain"] == "stairs-down:0.05,0.3" and not summary["fell"]
    import csv

    with (tmp_path / "run" / "log.csv").open() as file:
        last = list(csv.DictReader(file))[-1]
    z, height = float(last["z"]), float(last["height"])
    assert 0.9 + 0.1 < z < 0.9 + 0.35, z  # Bullet's body clearance 0.20 m above the platform's 0.9 m
    assert z - height == pytest.approx(0.9, abs=0.01)  # the engine's height ray lands on the platform


def test_bad_level_terrain_is_one_line_and_exit_2(tmp_path: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    from .test_cli import run

    code, _, err = run(["simulate", "bullet", "--terrain", "gaps:2", "--out", str(tmp_path / "run")], capsys,
                       monkeypatch)
    assert code == 2
    assert err.strip().splitlines() == [err.strip()] and "gaps difficulty 2 is outside [0, 1]" in err
