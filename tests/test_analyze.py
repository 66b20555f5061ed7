"""``shc analyze``: metrics against hand-computed values, CoM against PyBullet, and the CLI end to end."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.analysis.metrics import (
    Window,
    analyze_run,
    edge_margin,
    feet_and_com,
    per_cycle_rms,
    polygon_centroid,
    support_polygon,
    window_mask,
)
from shc_cli.record.runread import RunLog, read_run
from shc_cli.record.summary import RunSummary

from .test_cli import run


@pytest.fixture(scope="module")
def walked(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 3 s Bullet tripod walk in physics (after its start-up)."""
    from shc_cli.commands.simulate import run_simulate
    from shc_cli.domain.config import SimulationConfig

    out = tmp_path_factory.mktemp("analyze") / "walk"
    return run_simulate(SimulationConfig(robot="bullet", gait="tripod", duration=3.0, out=out, plots=False))


@pytest.fixture(scope="module")
def planned(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from shc_cli.commands.plan import run_plan

    out = tmp_path_factory.mktemp("analyze") / "plan"
    return run_plan("bullet", "tripod", "1,0,0", 8.0, None, out, False)


# -- geometry ----------------------------------------------------------------------------------------------------


def test_margin_of_the_unit_square() -> None:
    square = support_polygon(np.array([[0, 0], [1, 0], [1, 1], [0, 1], [0.5, 0.0]]))  # a collinear extra point
    assert len(square) == 4
    assert edge_margin(square, np.array([0.5, 0.5])) == pytest.approx(0.5)
    assert edge_margin(square, np.array([0.9, 0.5])) == pytest.approx(0.1)
    assert edge_margin(square, np.array([1.5, 0.5])) == pytest.approx(-0.5)
    np.testing.assert_allclose(polygon_centroid(square), [0.5, 0.5])


def test_two_feet_give_minus_the_distance_to_their_segment() -> None:
    line = support_polygon(np.array([[0.0, 0.0], [2.0, 0.0]]))
    assert edge_margin(line, np.array([1.0, 0.3])) == pytest.approx(-0.3)
    assert edge_margin(line, np.array([3.0, 0.0])) == pytest.approx(-1.0)


def _segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    ab = b - a
    if not np.dot(ab, ab):
        return float(np.linalg.norm(p - a))
    s = float(np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0))
    return float(np.linalg.norm(p - (a + s * ab)))


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=3, max_size=8),
       st.floats(0.01, 0.99), st.floats(0.01, 0.99))
def test_margin_inside_is_the_distance_to_the_nearest_edge(points: list[tuple[float, float]], u: float,
                                                            v: float) -> None:
    """Property: for a point inside the hull, the margin equals the brute-force distance to the nearest edge."""
    hull = support_polygon(np.array(points))
    if len(hull) < 3:
        return
    x, y = hull[:, 0], hull[:, 1]
    if abs(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) < 1e-3:
        return  # (nearly) no area
    # a point inside: a convex combination of three hull vertices
    a, b, c = hull[0], hull[len(hull) // 2], hull[-1]
    w = np.array([u, v * (1 - u), (1 - u) * (1 - v)])
    point = w[0] * a + w[1] * b + w[2] * c
    brute = min(_segment_distance(point, hull[i], hull[(i + 1) % len(hull)]) for i in range(len(hull)))
    assert edge_margin(hull, point) == pytest.approx(brute, abs=1e-9)


def test_per_cycle_rms_of_a_sine_is_amplitude_over_root_two() -> None:
    period = 100
    t = np.arange(3 * period + 17)  # the partial last cycle is dropped
    values = 2.0 * np.sin(2 * np.pi * t / period)
    rms = per_cycle_rms(values, period)
    assert len(rms) == 3
    np.testing.assert_allclose(rms, 2.0 / math.sqrt(2.0), rtol=1e-9)


# -- metrics on a synthetic run ----------------------------------------------------------------------------------


def _synthetic(bullet, n: int = 400) -> RunLog:  # type: ignore[no-untyped-def]
    """Bullet standing in its default pose, the body moving at 0.2 m/s along x, constant power 150 W, feet
    loaded 10/20/30/40/50/60 N."""
    from shc_cli.model.chains import Chains
    from shc_cli.model.ik import solve

    chains = Chains.from_robot(bullet)
    stance = np.array([[leg.stance.x, leg.stance.y, -bullet.walker.body_clearance] for leg in bullet.legs.values()])
    q, _ = solve(chains, chains.default_joints(), stance)
    dt = bullet.time_delta
    t = np.arange(n) * dt
    position = np.column_stack([0.2 * t, np.zeros(n), np.full(n, bullet.walker.body_clearance)])
    legs = len(bullet.legs)
    return RunLog(
        path=Path("synthetic"), kind="simulate",
        summary=RunSummary(scenario="WG", gait="tripod", step_period_cycles=100),
        robot=bullet, t=t, running=np.ones(n, dtype=bool), walk_state=np.array(["MOVING"] * n),
        command=np.tile([1.0, 0.0, 0.0], (n, 1)), desired=np.tile([0.25, 0.0, 0.0], (n, 1)), position=position,
        rpy=np.zeros((n, 3)), joints=np.repeat(q[None], n, axis=0), contact=np.ones((n, legs), dtype=bool),
        power=np.full(n, 150.0), foot_force=np.tile(np.arange(1, legs + 1) * 10.0, (n, 1)),
        body_rate=np.column_stack([0.1 * np.sin(2 * np.pi * t), np.full(n, 0.05), np.zeros(n)]),
        height=np.full(n, 0.25),
    )


def test_cost_of_transport_is_eq_22(bullet) -> None:  # type: ignore[no-untyped-def]
    result = analyze_run(_synthetic(bullet))
    speed = 0.2 * (399 * bullet.time_delta) / (400 * bullet.time_delta)  # the first row has no row before it
    assert result["mean_speed_mps"] == pytest.approx(speed)
    mass = bullet.total_mass() + len(bullet.legs) * 0.001  # what is simulated: the file's masses and 1 g feet
    assert result["cot"] == pytest.approx(150.0 / (mass * 9.81 * speed))
    assert result["speed_ratio"] == pytest.approx(speed / 0.25)
    assert result["duty_factor"] == 1.0
    assert result["foot_slip_m"] == pytest.approx(399 * 0.2 * bullet.time_delta)  # feet carried with the body
    assert result["height_median_m"] == pytest.approx(0.25)
    assert result["pitch_rate_median_rps"] == pytest.approx(0.05)
    assert result["gait_cycles"] == 4


def test_zmp_is_the_force_weighted_mean_of_the_feet(bullet) -> None:  # type: ignore[no-untyped-def]
    log = _synthetic(bullet, 10)
    result = analyze_run(log)
    feet = result["_series"]["feet"][0, :, :2]
    forces = np.arange(1, 7) * 10.0
    expected = (feet * forces[:, None]).sum(axis=0) / forces.sum()
    np.testing.assert_allclose(result["_series"]["zmp"][0], expected, atol=1e-12)
    hull = support_polygon(feet)
    assert result["zmp_margin_median_m"] == pytest.approx(edge_margin(hull, expected))


def test_steady_window_leaves_out_the_velocity_ramp(bullet) -> None:  # type: ignore[no-untyped-def]
    log = _synthetic(bullet)
    log.desired[:150, 0] = np.linspace(0.0, 0.25, 150)  # accelerating for 1.5 s
    mask = window_mask(log, Window(steady=True))
    assert not mask[:249].any() and mask[249:].all()  # steady once the velocity held for a period of 100
    assert window_mask(log, Window(skip_s=1.0)).sum() == 300


def test_centre_of_mass_matches_pybullet(bullet) -> None:  # type: ignore[no-untyped-def]
    """The whole robot's CoM from the link masses at segment midpoints equals the mass-weighted link CoMs of the
    generated URDF in PyBullet, for a random joint vector."""
    import os
    import tempfile

    from shc_cli.backends.pybullet_.urdf import robot_urdf
    from shc_cli.backends.pybullet_.world import quiet_stdout
    from shc_cli.model.chains import Chains

    with quiet_stdout():
        import pybullet as p
    chains = Chains.from_robot(bullet)
    rng = np.random.default_rng(3)
    q = rng.uniform(chains.lower, chains.upper)
    log = _synthetic(bullet, 2)
    log.joints[:] = q
    log.position[:] = [0.3, -0.2, 0.4]
    log.rpy[:] = [0.1, -0.2, 0.7]
    _, com = feet_and_com(log, np.array([0]))
    client = p.connect(p.DIRECT)
    try:
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as handle:
            handle.write(robot_urdf(bullet))
        with quiet_stdout():
            body = p.loadURDF(handle.name, [0.3, -0.2, 0.4], p.getQuaternionFromEuler([0.1, -0.2, 0.7]),
                              flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
        os.unlink(handle.name)
        names = {p.getJointInfo(body, j, physicsClientId=client)[1].decode(): j
                 for j in range(p.getNumJoints(body, physicsClientId=client))}
        for i, (leg_id, leg) in enumerate(bullet.legs.items()):
            for k, joint in enumerate(leg.joints):
                p.resetJointState(body, names[f"{leg_id}_{joint}_joint"], float(q[i, k]), physicsClientId=client)
        total, weighted = 0.0, np.zeros(3)
        for link in range(-1, p.getNumJoints(body, physicsClientId=client)):
            mass = p.getDynamicsInfo(body, link, physicsClientId=client)[0]
            where = (p.getBasePositionAndOrientation(body, physicsClientId=client)[0] if link < 0
                     else p.getLinkState(body, link, physicsClientId=client)[0])
            total += mass
            weighted += mass * np.array(where)
    finally:
        p.disconnect(client)
    np.testing.assert_allclose(com[0], weighted / total, atol=1e-6)


# -- end to end --------------------------------------------------------------------------------------------------


REQUIRED = {"cot", "mean_power_w", "mean_speed_mps", "height_median_m", "height_iqr_m", "pitch_rate_median_rps",
            "roll_rate_median_rps", "stability_margin_median_m"}


@pytest.mark.slow  # a 15 s simulated walk (the walked fixture)
def test_json_of_a_simulated_run(walked: Path, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    code, out, _ = run(["analyze", str(walked), "--json"], capsys, monkeypatch)
    assert code == 0
    result = json.loads(out)
    assert set(result) >= REQUIRED
    summary = json.loads((walked / "summary.json").read_text())
    # the summary is the analysis of the finished log over the same RUNNING window: the very same numbers
    for key in ("cot", "mean_power_w", "mean_speed_mps", "displacement_speed_mps", "path_speed_mps",
                "commanded_speed_mps", "distance_m"):
        assert result[key] == summary[key], key
    weight = summary["mass_kg"] * 9.81  # eq. 22: P / (m·g·v), v the distance walked over the window (issue 38)
    assert summary["cot"] == pytest.approx(summary["mean_power_w"] / (weight * summary["walked_m"]
                                                                      / summary["analysed_time_s"]), rel=1e-9)
    assert summary["cot_displacement"] == pytest.approx(summary["mean_power_w"] / (weight * summary["mean_speed_mps"]),
                                                        rel=1e-12)
    assert 0.1 < result["stability_margin_median_m"] < 0.3  # CoM well inside the tripod
    assert 0.4 < result["duty_factor"] < 0.8
    assert result["height_median_m"] == pytest.approx(0.20, abs=0.03)  # bullet's body clearance (paper Table III)


@pytest.mark.slow  # a 15 s simulated walk (the walked fixture)
def test_several_runs_make_a_table_and_plots(walked: Path, planned: Path, tmp_path: Path, capsys,  # type: ignore[no-untyped-def]
                                             monkeypatch) -> None:
    code, out, _ = run(["analyze", str(walked), str(planned), "--out", str(tmp_path / "an")], capsys, monkeypatch)
    assert code == 0
    lines = out.strip().splitlines()
    assert lines[0].split()[:3] == ["run", "scen", "f_s"]
    assert lines[1].startswith("walk") and lines[2].startswith("plan")
    assert "–" in lines[2]  # a plan has no power
    for name in ("analysis.json", "cycles.png", "power.png", "stability.png", "zmp_walk.png", "zmp_plan.png"):
        assert (tmp_path / "an" / name).stat().st_size > 0
    code, out, _ = run(["analyze", str(walked), str(planned), "--json"], capsys, monkeypatch)
    data = json.loads(out)
    assert isinstance(data, list) and [d["kind"] for d in data] == ["simulate", "plan"]
    # the plan's ideal body path at its steady speed is the speed its stance feet achieve (plan's own summary)
    assert data[1]["cot"] is None and data[1]["steady_speed_mps"] == pytest.approx(
        read_run(planned).summary.eq16_speed_mps, rel=1e-3)
    plan_summary = read_run(planned).summary  # the plan's summary is the analysis of its tables too
    assert (data[1]["path_speed_mps"], data[1]["displacement_speed_mps"], data[1]["commanded_speed_mps"]) == (
        plan_summary.path_speed_mps, plan_summary.displacement_speed_mps, plan_summary.commanded_speed_mps)


@pytest.mark.parametrize(("make", "message"), [
    (lambda d: d, "not a run directory"),
    (lambda d: (d.mkdir(), d)[1], "no summary.json"),
])
def test_bad_run_directory_is_one_line(tmp_path: Path, make, message: str, capsys, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    path = make(tmp_path / "run")
    code, _, err = run(["analyze", str(path)], capsys, monkeypatch)
    assert code == 2
    assert len(err.strip().splitlines()) == 1 and message in err


def test_atomic_outputs_get_the_usual_permissions(tmp_path: Path) -> None:
    """Files written through a temporary name keep the umask's permissions, not mkstemp's 0600."""
    import os

    from shc_cli.outputs import write_text

    mask = os.umask(0o022)
    try:
        write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(mask)
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o644


@pytest.mark.parametrize("name", ["openshc_default", "bullet"])
def test_cot_divides_by_the_simulated_mass(name: str) -> None:
    """The cost of transport's mass is what PyBullet simulates (the links without a ``mass`` at 0.1 kg, 1 g foot
    spheres): for ``openshc_default`` 2.806 kg, not the file's 1.0 kg (its 18 links give no mass)."""
    import os
    import tempfile

    from shc_cli.backends.pybullet_.urdf import robot_urdf
    from shc_cli.backends.pybullet_.world import quiet_stdout
    from shc_cli.model.body import body_mass
    from shc_cli.spec.loading import load_robot

    robot = load_robot(name).robot
    assert robot is not None
    with quiet_stdout():
        import pybullet as p
    client = p.connect(p.DIRECT)
    try:
        with tempfile.NamedTemporaryFile("w", suffix=".urdf", delete=False) as handle:
            handle.write(robot_urdf(robot))
        with quiet_stdout():
            body = p.loadURDF(handle.name, flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
        os.unlink(handle.name)
        simulated = sum(p.getDynamicsInfo(body, link, physicsClientId=client)[0]
                        for link in range(-1, p.getNumJoints(body, physicsClientId=client)))
    finally:
        p.disconnect(client)
    assert body_mass(robot) == pytest.approx(simulated, rel=1e-9)
    if name == "openshc_default":
        assert robot.total_mass() == pytest.approx(1.0) and simulated == pytest.approx(1.0 + 18 * 0.1 + 6 * 0.001)
