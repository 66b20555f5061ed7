"""Generated gaits for a subset of legs (shc_cli/control/gait_planner.py): timing as the controller reads it,
margins against closed-form geometry, and the fault scenarios of Mailer et al. (GECCO 2021) on the bundled Bullet."""

from __future__ import annotations

import math

import numpy as np
import pytest

from shc_cli.control.gait import step_cycle
from shc_cli.control.gait_planner import GaitPlanningError, plan_gait, worst_margin
from shc_cli.spec.loading import load_robot


def test_a_tripod_on_a_regular_hexagon_holds_the_inscribed_circle_of_its_triangles() -> None:
    """Alternate vertices of a regular hexagon of radius R make an equilateral triangle whose inscribed circle has
    radius R/2: with no stride and no sway that is the tripod's margin."""
    stance = {f"L{i}": (math.cos(i * math.pi / 3), math.sin(i * math.pi / 3)) for i in range(6)}
    groups = (("L0", "L2", "L4"), ("L1", "L3", "L5"))
    margin, shift = worst_margin(stance, groups, 1.0, stride_m=0.0, sway=False)
    assert margin == pytest.approx(0.5, abs=1e-9)
    assert np.allclose(shift, 0.0, atol=1e-9)


def test_a_square_crawl_without_stride_or_sway_has_no_margin() -> None:
    """Each three-foot triangle of a square has the diagonal as an edge; the four triangles meet only at the centre."""
    stance = {"A": (0.3, 0.3), "B": (0.3, -0.3), "C": (-0.3, -0.3), "D": (-0.3, 0.3)}
    margin, _ = worst_margin(stance, (("A",), ("C",), ("B",), ("D",)), 1.0, stride_m=0.0, sway=False)
    assert margin == pytest.approx(0.0, abs=1e-9)


def test_two_stance_feet_have_no_margin() -> None:
    stance = {"A": (0.3, 0.3), "B": (0.3, -0.3), "C": (-0.3, -0.3), "D": (-0.3, 0.3)}
    margin, _ = worst_margin(stance, (("A", "C"), ("B", "D")), 1.0, stride_m=0.1)
    assert margin == -math.inf


@pytest.mark.parametrize("failed", [(), ("AR",), ("BR",), ("BR", "BL")])
def test_the_generated_table_lifts_the_groups_in_order_as_the_controller_times_them(failed: tuple[str, ...]) -> None:
    """Read back through the controller's own step cycle (OpenSHC's integer timing): the legs of a group lift off
    together, the groups one after another at equal spacing in the planned order, each swinging one swing period."""
    robot = load_robot("bullet").robot
    stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}
    planned = plan_gait(stance, [leg for leg in stance if leg not in failed], stride_m=0.2)
    cycle = step_cycle(planned.gait, 1.0, robot.time_delta)

    def swinging(leg: str, phase: int) -> bool:
        return cycle.swing_start <= (phase + cycle.offsets[leg]) % cycle.period < cycle.swing_end

    lift_off = {leg: next(p for p in range(cycle.period) if swinging(leg, p) and not swinging(leg, p - 1))
                for leg in cycle.offsets}
    times = [{lift_off[leg] for leg in group} for group in planned.groups]
    assert all(len(t) == 1 for t in times)  # a group lifts off together
    starts = [t.pop() for t in times]
    spacing = cycle.period // len(planned.groups)
    first = starts[0]
    assert [(s - first) % cycle.period for s in starts] == [j * spacing for j in range(len(starts))]
    assert sum(swinging(planned.groups[0][0], p) for p in range(cycle.period)) == cycle.swing_period
    assert cycle.duty_factor == pytest.approx(planned.duty_factor)
    assert set(cycle.offsets) == set(stance) - set(failed)


def test_the_intact_bullet_gets_a_duty_factor_of_one_half() -> None:
    robot = load_robot("bullet").robot
    stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}
    planned = plan_gait(stance, list(stance), stride_m=0.15)
    assert planned.duty_factor == pytest.approx(0.5)
    assert planned.speed_share == pytest.approx(1.0)
    assert planned.margin_m > 0.05


@pytest.mark.parametrize("failed", ["AR", "BR", "CR", "CL", "BL", "AL"])
def test_one_failed_leg_keeps_two_thirds_of_the_tripods_speed_with_a_margin(failed: str) -> None:
    """S1 of Mailer et al.: the five legs left get a gait at β = 0.6, (1 − β)/β = 2/3 of the tripod's speed, every
    instant statically stable with the body swaying (their unadapted tripod kept 53.6 %)."""
    robot = load_robot("bullet").robot
    stance = {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}
    planned = plan_gait(stance, [leg for leg in stance if leg != failed], stride_m=0.15)
    assert planned.speed_share == pytest.approx(2 / 3)
    assert planned.margin_m >= 0.02
    assert failed not in planned.gait.offset_multiplier


def test_fewer_than_three_legs_are_refused_in_one_line() -> None:
    with pytest.raises(GaitPlanningError, match="at least three"):
        plan_gait({"A": (0.1, 0.1), "B": (0.1, -0.1)}, ["A", "B"], stride_m=0.1)


def _bullet_stance() -> dict[str, tuple[float, float]]:
    robot = load_robot("bullet").robot
    return {leg: (spec.stance.x, spec.stance.y) for leg, spec in robot.legs.items()}


@pytest.mark.parametrize("failed", [("AR", "BR"), ("AR", "CR"), ("BL", "CL")])
def test_three_collinear_feet_need_a_moved_stance_and_get_one_within_reach(failed: tuple[str, ...]) -> None:
    """Two failed legs on one side leave the other side's three feet on one line: no table holds on Bullet's own
    stance (S3, S4); moving the stance positions by at most ``reach_m`` finds a wave that holds."""
    stance = _bullet_stance()
    left = [leg for leg in stance if leg not in failed]
    with pytest.raises(GaitPlanningError, match="static margin"):
        plan_gait(stance, left, stride_m=0.15)
    planned = plan_gait(stance, left, stride_m=0.15, reach_m=0.2)
    assert planned.margin_m >= 0.02
    assert planned.duty_factor == pytest.approx(0.75)
    moved = [math.dist(planned.stance[leg], stance[leg]) for leg in left]
    assert 0 < max(moved) <= 0.2 + 1e-9


def test_a_reachability_test_that_refuses_every_move_leaves_no_gait() -> None:
    stance = _bullet_stance()
    left = [leg for leg in stance if leg not in ("AR", "BR")]
    with pytest.raises(GaitPlanningError):
        plan_gait(stance, left, stride_m=0.15, reach_m=0.2, reachable=lambda leg, xy: False)


STANCE = _bullet_stance()
LEGS = list(STANCE)


def _qhull_margin(feet: np.ndarray, com: np.ndarray) -> float:
    """The distance of ``com`` inside the convex hull of ``feet`` by SciPy's Qhull (independent of the planner's)."""
    from scipy.spatial import ConvexHull

    equations = ConvexHull(feet).equations
    return float(np.min(-(equations[:, :2] @ com + equations[:, 2])))


@pytest.mark.parametrize("failed", [("AL", "CR"), ("BL", "BR"), ("CL", "AR")])
def test_the_sway_of_a_four_legged_crawl_keeps_the_margin_at_every_instant_and_stride(failed: tuple[str, ...]) -> None:
    """S2 (two opposite legs failed): no constant shift holds a crawl on four legs; the sway path keeps the centre
    of mass ≥ 0.02 m inside the stance feet at every sampled instant, at the full stride and the shorter ones the
    walker ramps through, moving no faster than twice a stance foot, within the legs' reach."""
    from shc_cli.control.gait_planner import stance_tips, sway_at, sway_path

    legs = [leg for leg in LEGS if leg not in failed]
    stride = 0.2
    with pytest.raises(GaitPlanningError):
        plan_gait(STANCE, legs, stride, sway=False)
    planned = plan_gait(STANCE, legs, stride, sway=True)
    assert planned.duty_factor == pytest.approx(0.75)  # a wave of four single-leg groups
    path = sway_path(planned, stride, 0.0, 0.02, (0.0, 0.5, 1.0), 2.0, 0.1)
    assert path is not None and np.abs(path).max() <= 0.1 + 1e-9
    swing = planned.gait.swing_phase * len(planned.groups) / planned.gait.base_length
    for share in (0.0, 0.5, 1.0):
        for i, feet in enumerate(stance_tips(planned.stance, planned.groups, swing, stride * share)):
            assert _qhull_margin(feet, path[i]) >= 0.02 - 1e-7
    step = np.abs(np.roll(path, -1, axis=0) - path).max()
    assert step <= 2.0 * stride / (len(planned.groups) - swing) / 8 + 1e-9
    assert sway_at(path, 0.0) == pytest.approx(path[0]) and sway_at(path, 1.0) == pytest.approx(path[0])
    assert sway_at(path, 0.5 / len(path)) == pytest.approx(0.5 * (path[0] + path[1]))


def test_a_constant_sway_is_one_shift_and_three_feet_in_a_line_have_none() -> None:
    """``rate_share`` 0: one shift for the whole cycle; S3's lone left leg lifted leaves three collinear right feet,
    which no shift within reach can stand on."""
    from shc_cli.control.gait_planner import sway_path

    planned = plan_gait(STANCE, [leg for leg in LEGS if leg != "BR"], 0.2, sway=False)
    path = sway_path(planned, 0.2, rate_share=0.0)
    assert path is not None and np.ptp(path, axis=0).max() <= 1e-9
    crawl = plan_gait(STANCE, ["AR", "BR", "CR", "BL"], 0.2, sway=True, reach_m=0.1)  # stance moved to hold
    assert sway_path(crawl, 0.2, 0.0, 0.02, (0.0, 0.5, 1.0), 2.0, 0.1) is None  # but only with a 0.37 m shift
