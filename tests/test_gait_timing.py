"""OpenSHC's integer step cycle: every row of the study's reference table (§4.2)."""

from __future__ import annotations

import pytest

from shc_cli.control.gait import even_up, step_cycle
from shc_cli.spec.loading import load_gait

# config, gait, k, P, Wp, S, swing window — openshc-study.md §4.2 "Reference step cycles".
TABLE = [
    ((0.02, 1.0), "wave", 26, 312, 52, 260, (130, 182)),
    ((0.02, 1.0), "tripod", 26, 104, 52, 52, (26, 78)),
    ((0.02, 1.0), "ripple", 26, 156, 52, 104, (52, 104)),
    ((0.02, 1.0), "amble", 50, 150, 50, 100, (50, 100)),
    ((0.01, 1.1), "wave", 46, 552, 92, 460, (230, 322)),
    ((0.01, 1.1), "tripod", 46, 184, 92, 92, (46, 138)),
    ((0.01, 1.1), "ripple", 46, 276, 92, 184, (92, 184)),
    ((0.01, 1.1), "amble", 90, 270, 90, 180, (90, 180)),
    ((0.01, 1.1), "bipod", 22, 132, 88, 44, (22, 110)),
]


@pytest.mark.parametrize(("config", "name", "k", "period", "swing", "stance", "window"), TABLE)
def test_reference_step_cycles(config: tuple[float, float], name: str, k: int, period: int, swing: int,
                               stance: int, window: tuple[int, int]) -> None:
    dt, frequency = config
    gait = load_gait(name).gait
    cycle = step_cycle(gait, frequency, dt)
    assert (cycle.normaliser, cycle.period, cycle.swing_period, cycle.stance_period) == (k, period, swing, stance)
    assert (cycle.swing_start, cycle.swing_end) == window
    assert cycle.frequency == pytest.approx(1.0 / (period * dt), rel=1e-12)


def test_tripod_offsets_and_swing_order() -> None:
    gait = load_gait("tripod").gait
    cycle = step_cycle(gait, 1.1, 0.01)
    assert cycle.offsets == {"AR": 0, "BR": 92, "CR": 0, "CL": 92, "BL": 0, "AL": 92}


def test_wave_swings_one_leg_at_a_time_in_the_documented_order() -> None:
    gait = load_gait("wave").gait
    cycle = step_cycle(gait, 1.1, 0.01)
    # A leg with offset o starts swinging (swing_start − o) mod P iterations after the start.
    starts = {leg: (cycle.swing_start - o) % cycle.period for leg, o in cycle.offsets.items()}
    assert sorted(starts, key=starts.__getitem__) == ["AR", "CL", "BL", "AL", "CR", "BR"]


def test_even_up() -> None:
    assert [even_up(n) for n in (0, 1, 2, 45, 46)] == [0, 2, 2, 46, 46]
