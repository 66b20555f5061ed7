"""Auto posing (OpenSHC ``updateAutoPose``, ``AutoPoser::updatePose``, ``LegPoser::updateAutoPose``).

Expectations are worked out by hand from the source formulas, not produced by the code under test.
The main fixture is Bullet's tripod set on the tripod gait at step frequency 11 Hz, dt 0.01 s:
raw period ((1/11)/0.01)/(2/4) = 18.18 → k = evenUp(trunc(18.18/4)) = 4, P = 16 iterations.
Poser 0 posts z 0.01 m, roll −0.05 rad over [1·4, 3·4) = [4, 12); poser 1 z 0.01, roll +0.05 over
[12, 4 + 16) (wraps). In a window of n = 8 iterations, iteration i = phase − start + 1; the first half
(i ≤ 4) follows A(4t³ − 3t⁴) with t = i/4, the second A(1 − t)³(1 + 3t) with t = (i − 4)/4.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from ruamel.yaml import YAML

from shc_cli.control.autopose import AutoPoser, PosingState
from shc_cli.control.gait import StepCycle, step_cycle
from shc_cli.control.pose import IDENTITY
from shc_cli.control.stepping import FORCE_STANCE, STANCE, SWING
from shc_cli.control.walk import WalkState
from shc_cli.errors import SpecError
from shc_cli.spec.autopose import (
    AutoPoseSet,
    Negation,
    Poser,
    compatibility_issues,
    load_auto_pose_set,
    load_pose_set,
    pose_set_name,
)
from shc_cli.spec.gait import Gait
from shc_cli.spec.loading import bundled, load_gait

from .conftest import GOLDEN

LEGS = ["AR", "BR", "CR", "CL", "BL", "AL"]
DT = 0.01

# Hand values of the quartic profiles at the quarter points (A = 1).
RISE = {1: 4 / 64 - 3 / 256, 2: 0.5 - 3 / 16, 3: 4 * 27 / 64 - 3 * 81 / 256, 4: 1.0}  # 4t³ − 3t⁴, t = i/4
FALL = {5: 0.75**3 * 1.75, 6: 0.5**3 * 2.5, 7: 0.25**3 * 3.25, 8: 0.0}  # (1−t)³(1+3t), t = (i−4)/4


@pytest.fixture(scope="module")
def gait() -> Gait:
    loaded = load_gait("tripod").gait
    return loaded


@pytest.fixture(scope="module")
def cycle(gait: Gait) -> StepCycle:
    result = step_cycle(gait, 11.0, DT)
    assert (result.period, result.normaliser, result.swing_start, result.swing_end) == (16, 4, 4, 12)
    return result


def bullet_tripod() -> AutoPoseSet:
    pose_set = load_pose_set("tripod").pose_set
    return pose_set


def drive(poser: AutoPoser, cycle: StepCycle, walk: WalkState, master: int, zero_stride: bool = False,
          states: dict[str, int] | None = None) -> None:
    """One update with leg phases as the walker has them: leg phase = master + offset (reference BL has 0)."""
    phases = np.array([(master + cycle.offsets[leg]) % cycle.period for leg in LEGS])
    step = np.where((phases >= cycle.swing_start) & (phases < cycle.swing_end), SWING, STANCE)
    for leg, state in (states or {}).items():
        step[LEGS.index(leg)] = state
    poser.update(int(walk), zero_stride, phases, step)


def moving_until(poser: AutoPoser, cycle: StepCycle, last: int, cycles: int = 0) -> None:
    """MOVING updates from master phase 0 through ``cycles`` whole cycles and then up to ``last``."""
    for master in list(range(cycle.period)) * cycles + list(range(last + 1)):
        drive(poser, cycle, WalkState.MOVING, master)


def state_of(poser: AutoPoser) -> PosingState:
    """The poser's state (a call, so that mypy does not narrow it across ``drive`` calls)."""
    return poser.state


def z_of(poser: AutoPoser) -> float:
    return float(poser.body_pose.position[2])


def roll_of(poser: AutoPoser) -> float:
    return poser.body_pose.euler()[0]


# -- the amplitude profile ---------------------------------------------------------------------------------------


def test_tripod_profile_follows_the_quartic_rise_and_fall(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    assert LEGS[poser.reference_leg] == "BL"
    # Phases 0–3 of the first cycle: poser 1 has not seen its start (12) yet, poser 0 not its start (4).
    for master in range(4):
        drive(poser, cycle, WalkState.MOVING, master)
        assert z_of(poser) == 0.0 and poser.body_pose.rotation is IDENTITY
    for master in range(4, 12):  # poser 0 alone, iteration = master − 3
        drive(poser, cycle, WalkState.MOVING, master)
        shape = {**RISE, **FALL}[master - 3]
        assert z_of(poser) == pytest.approx(0.01 * shape, abs=1e-15)
        assert roll_of(poser) == pytest.approx(-0.05 * shape, abs=1e-15)
    for master in [*range(12, 16), *range(4)]:  # poser 1 over its wrapped window [12, 20)
        drive(poser, cycle, WalkState.MOVING, master)
        shape = {**RISE, **FALL}[(master if master >= 12 else master + 16) - 11]
        assert z_of(poser) == pytest.approx(0.01 * shape, abs=1e-15)
        assert roll_of(poser) == pytest.approx(0.05 * shape, abs=1e-15)
    assert poser.state == PosingState.POSING


def test_peaks_equal_the_amplitudes_and_window_ends_are_exactly_zero(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    moving_until(poser, cycle, 15)
    z, roll = {}, {}
    for master in range(16):
        drive(poser, cycle, WalkState.MOVING, master)
        z[master], roll[master] = z_of(poser), roll_of(poser)
    assert z[7] == 0.01 and z[15] == 0.01  # iteration 4, t = 1 of the rise: A·t⁴ with t = 1, exactly
    assert roll[7] == pytest.approx(-0.05, abs=1e-15) and roll[15] == pytest.approx(0.05, abs=1e-15)
    assert max(z.values()) == 0.01
    assert z[11] == 0.0 and z[3] == 0.0  # last iteration of each window: (1 − 1)³ = 0
    drive(poser, cycle, WalkState.MOVING, 11)
    assert poser.body_pose.rotation is IDENTITY


def test_gravity_amplitude_replaces_xyz_along_gravity(gait: Gait, cycle: StepCycle) -> None:
    pose_set = AutoPoseSet(name="g", pose_frequency=-1.0, pose_phase_length=4,
                           poser=[Poser(start=1, end=3, x=0.5, z=0.5, gravity=0.02)])
    poser = AutoPoser(pose_set, gait, cycle, LEGS, DT, gravity=(0.0, 0.0, -9.8))
    moving_until(poser, cycle, 7)  # iteration 4: the peak
    assert poser.body_pose.position.tolist() == pytest.approx([0.0, 0.0, -0.02], abs=1e-15)


# -- per-leg negation --------------------------------------------------------------------------------------------


def test_negation_window_hides_the_auto_pose_from_the_swinging_tripod(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    moving_until(poser, cycle, 7, cycles=1)  # AR/CR/BL swing over phases 4–11; negated over [4, 12]
    assert poser.negated_legs == ["AR", "CR", "BL"]
    legs = dict(zip(LEGS, poser.leg_poses, strict=True))
    # Full negation: auto.removePose(auto) = (p − R·p, R·R⁻¹). OpenSHC's removePose is not A∘B⁻¹, so a
    # rotated auto pose leaves p − R·p: with p = (0, 0, 0.01), R = Rx(−0.05) that is
    # (0, −0.01·sin 0.05, 0.01·(1 − cos 0.05)).
    residual = [0.0, -0.01 * np.sin(0.05), 0.01 * (1.0 - np.cos(0.05))]
    for leg in ("AR", "CR", "BL"):
        assert legs[leg].position.tolist() == pytest.approx(residual, abs=1e-17)
        assert np.abs(legs[leg].rotation - np.eye(3)).max() < 1e-15
    for leg in ("BR", "CL", "AL"):
        assert legs[leg] is poser.body_pose
    drive(poser, cycle, WalkState.MOVING, 12)  # the end phase is still negated (> end switches off) and
    assert poser.negated_legs == LEGS  # BR/CL/AL switch on at their start 12: for one cycle all six are negated
    shape = RISE[1]  # poser 1, first iteration, roll +0.05·shape: p − R·p = (0, z·sin θ, z·(1 − cos θ))
    residual = [0.0, 0.01 * shape * np.sin(0.05 * shape), 0.01 * shape * (1.0 - np.cos(0.05 * shape))]
    assert poser.leg_poses[0].position.tolist() == pytest.approx(residual, abs=1e-17)
    assert z_of(poser) == pytest.approx(0.01 * shape, abs=1e-17)
    drive(poser, cycle, WalkState.MOVING, 13)
    assert poser.negated_legs == ["BR", "CL", "AL"]  # BR/CL/AL: [12, 20], switched on at 12


def test_negation_does_not_switch_on_in_force_stance(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    moving_until(poser, cycle, 3, cycles=1)
    drive(poser, cycle, WalkState.MOVING, 4, states={"AR": FORCE_STANCE})
    for master in range(5, 8):
        drive(poser, cycle, WalkState.MOVING, master)
    assert poser.negated_legs == ["CR", "BL"]
    assert poser.leg_poses[0] is poser.body_pose


def test_transition_ratio_blends_with_smooth_step_and_overshoots_at_the_end_phase(gait: Gait,
                                                                                  cycle: StepCycle) -> None:
    # AR negated over [4, 12], n = 8, ratio 0.25 → n·r = 2: c = min(1, i/2), then min(1, (8 − i)/2).
    # Translation only, so the leg keeps (1 − smoothStep(c)) of the body z.
    pose_set = AutoPoseSet(name="r", pose_frequency=-1.0, pose_phase_length=4,
                           poser=[Poser(start=1, end=3, z=0.01), Poser(start=3, end=1, z=0.01)],
                           negation={"AR": Negation(start=1, end=3, transition_ratio=0.25)})
    poser = AutoPoser(pose_set, gait, cycle, LEGS, DT)
    moving_until(poser, cycle, 3, cycles=1)
    kept = {4: 0.5, 5: 0.0, 8: 0.0, 10: 0.5, 11: 1.0,
            12: 1.0 + 2.375}  # i = 9: c = −0.5, smoothStep(−0.5) = −0.1875 − 0.9375 − 1.25 = −2.375
    body = {4: 0.01 * RISE[1], 5: 0.01 * RISE[2], 8: 0.01 * FALL[5], 10: 0.01 * FALL[7], 11: 0.0,
            12: 0.01 * RISE[1]}
    for master in range(4, 13):
        drive(poser, cycle, WalkState.MOVING, master)
        if master in kept:
            assert z_of(poser) == pytest.approx(body[master], abs=1e-15)
            assert poser.leg_poses[0].position[2] == pytest.approx(kept[master] * body[master], abs=1e-15)
    assert poser.leg_poses[1] is poser.body_pose  # BR has no negation table: never negated


# -- starting and stopping ---------------------------------------------------------------------------------------


def test_stopping_completes_only_after_every_poser_saw_a_full_window(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    moving_until(poser, cycle, 5, cycles=1)
    drive(poser, cycle, WalkState.STOPPING, 6, zero_stride=False)  # stride not yet zero: no change
    assert poser.state == PosingState.POSING
    # STOP_POSING from phase 7. Poser 1 [12, 20): start seen at 12, end at 20 ≡ phase 4 of the next cycle.
    # Poser 0 [4, 12): its start passed already; start at next 4, end at next 12 → complete there.
    for master in range(7, 16):
        drive(poser, cycle, WalkState.STOPPING, master, zero_stride=True)
        assert state_of(poser) == PosingState.STOP_POSING
    for master in range(12):
        drive(poser, cycle, WalkState.STOPPING, master, zero_stride=True)
        assert not poser.posing_complete
        if master == 7:
            assert z_of(poser) == 0.01  # poser 0 still runs its last full window
    drive(poser, cycle, WalkState.STOPPING, 12, zero_stride=True)
    assert poser.posing_complete and state_of(poser) == PosingState.POSING_COMPLETE
    for master in range(13, 16):  # idle posers give identity
        drive(poser, cycle, WalkState.STOPPED, master)
        assert z_of(poser) == 0.0 and poser.posing_complete
    # POSING while walking, but "all posers idle" overrides it until a poser reaches its start phase.
    for master in range(4):
        drive(poser, cycle, WalkState.STARTING, master)
        assert state_of(poser) == PosingState.POSING_COMPLETE
    drive(poser, cycle, WalkState.STARTING, 4)
    assert state_of(poser) == PosingState.POSING


def test_stopped_from_the_start_is_complete_and_identity(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    assert poser.posing_complete  # OpenSHC's initial value
    poser.update(int(WalkState.STOPPED), True, np.zeros(6, dtype=int), np.full(6, 3))
    assert poser.posing_complete and z_of(poser) == 0.0 and poser.negated_legs == []


def test_free_running_cycle_length_and_posers_never_stop(gait: Gait, cycle: StepCycle) -> None:
    # (1/0.7)/0.01 = 142.86 → /4 = 35.7 → trunc 35 → evenUp 36 → length 144, normaliser 36.
    pose_set = AutoPoseSet(name="f", pose_frequency=0.7, pose_phase_length=4, poser=[Poser(start=1, end=3, z=0.01)])
    poser = AutoPoser(pose_set, gait, cycle, LEGS, DT)
    assert (poser.phase_length, poser.normaliser) == (144, 36)
    for count in range(400):
        drive(poser, cycle, WalkState.STOPPED, 0, zero_stride=True)  # leg phases are ignored
        assert poser.master_phase == count % 144
        if count % 144 == 36 + 35:  # iteration 36 of 72: the peak
            assert z_of(poser) == 0.01
        assert not poser.posing_complete  # free-running posers never stop: STOPPING → STOPPED is blocked


def test_reference_leg_is_the_last_with_offset_multiplier_zero() -> None:
    expected = {"tripod": "BL", "wave": "BL", "ripple": "BR", "amble": "AL", "bipod": "CL"}
    for name, leg in expected.items():
        gait = load_gait(name).gait
        pose_set = load_pose_set(name).pose_set
        poser = AutoPoser(pose_set, gait, step_cycle(gait, 1.0, DT), LEGS, DT)
        assert LEGS[poser.reference_leg] == leg


def test_reset_follows_the_new_cycle_and_restarts_posers(gait: Gait, cycle: StepCycle) -> None:
    poser = AutoPoser(bullet_tripod(), gait, cycle, LEGS, DT)
    moving_until(poser, cycle, 7)
    slower = step_cycle(gait, 0.5, DT)  # ((1/0.5)/0.01)/0.5 = 400 → k = 100, P = 400
    poser.reset(slower)
    assert (poser.phase_length, poser.normaliser) == (400, 100)
    assert poser.state == PosingState.POSING  # kept, as OpenSHC keeps auto_posing_state_
    drive(poser, slower, WalkState.MOVING, 150)
    assert z_of(poser) == 0.0  # fresh posers wait for their start phase (100 and 300)


# -- files -------------------------------------------------------------------------------------------------------


def _yaml_sets(name: str) -> dict:  # type: ignore[type-arg]
    data = YAML(typ="safe").load((GOLDEN / "openshc" / name).read_text())
    return data["syropod"]["auto_pose_parameters"]  # type: ignore[no-any-return]


@pytest.mark.parametrize(("yaml_name", "prefix"), [("bullet_auto_pose.yaml", ""),
                                                   ("openshc_auto_pose.yaml", "openshc_")])
def test_shipped_sets_equal_the_yaml_sources(yaml_name: str, prefix: str) -> None:
    for key, expected in _yaml_sets(yaml_name).items():
        name = key.removesuffix("_gait_pose")
        pose_set = load_pose_set(("bullet_" if name == "quad_wave" else prefix) + name).pose_set
        assert pose_set.pose_frequency == expected["pose_frequency"]
        assert pose_set.pose_phase_length == expected["pose_phase_length"]
        assert [p.start for p in pose_set.poser] == expected["pose_phase_starts"]
        assert [p.end for p in pose_set.poser] == expected["pose_phase_ends"]
        for axis in ("x", "y", "z", "roll", "pitch", "yaw", "gravity"):
            assert [getattr(p, axis) for p in pose_set.poser] == expected[f"{axis}_amplitudes"]
        assert {leg: n.start for leg, n in pose_set.negation.items()} == expected["pose_negation_phase_starts"]
        assert {leg: n.end for leg, n in pose_set.negation.items()} == expected["pose_negation_phase_ends"]
        ratios = expected.get("negation_transition_ratio", dict.fromkeys(expected["pose_negation_phase_starts"], 0))
        assert {leg: n.transition_ratio for leg, n in pose_set.negation.items()} == ratios


def test_every_shipped_set_loads_and_fits_its_gait(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    names = bundled("poses")
    assert {"wave", "tripod", "ripple", "amble", "bipod", "quad_wave", "bullet_quad_wave", "openshc_tripod"} \
        <= set(names)
    for name in names:
        loaded = load_pose_set(name)
        if name == "bullet_quad_wave":
            continue
        gait = load_gait(name.removeprefix("openshc_")).gait
        assert compatibility_issues(loaded, gait, LEGS) == []


def test_auto_pose_type_auto_names_the_set_after_the_gait(gait: Gait) -> None:
    assert pose_set_name("auto", gait) == "tripod"
    assert pose_set_name("openshc_tripod", gait) == "openshc_tripod"
    loaded = load_auto_pose_set("auto", gait)
    assert loaded.pose_set is not None and loaded.path.name == "tripod.toml"


def test_bullet_quad_wave_set_does_not_fit_this_repositorys_quad_wave_gait() -> None:
    gait = load_gait("quad_wave").gait
    issues = compatibility_issues(load_pose_set("bullet_quad_wave"), gait, ["AR", "BR", "BL", "AL"])
    fields = [issue.field for issue in issues]
    assert fields == ["pose_phase_length", "negation.CR", "negation.CL"]
    assert "16-unit cycle" in issues[0].problem and "has 8" in issues[0].problem


@pytest.mark.parametrize(("body", "line", "field", "words"), [
    ("[[poser]]\nstart = 1\nend = 9\n", 6, "poser.0.end", "9 lies outside the cycle of 4 units (use 0 to 3)"),
    ("[[poser]]\nstart = 1\nend = 3\n\n[[poser]]\nstart = 3\nend = 4\n", 10, "poser.1.end",
     "4 lies outside the cycle of 4 units (write 0 for the cycle end"),
    ("[[poser]]\nstart = 1\nend = 3\nrol = 0.1\n", 7, "poser.0.rol", "unknown key 'rol' (did you mean 'roll'?)"),
    ('[[poser]]\nstart = 1\nend = 3\nz = "1 cm"\n', 7, "poser.0.z", "expected a number, got the text '1 cm'"),
    ("[negation.AR]\nstart = 1\nend = 1\n", 6, "negation.AR.end", "the window is empty"),
])
def test_a_broken_pose_file_gives_one_clear_line(tmp_path: Path, body: str, line: int, field: str,
                                                  words: str) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('name = "bad"\npose_frequency = -1.0\npose_phase_length = 4\n' + body)
    with pytest.raises(SpecError) as error:
        load_pose_set(path)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{path}:{line}: {field}: ")
    assert words in message


def test_pose_frequency_must_be_minus_one_or_positive(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text('name = "bad"\npose_frequency = 0\npose_phase_length = 4\n')
    with pytest.raises(SpecError) as error:
        load_pose_set(path)
    assert str(error.value) == (f"{path}:2: pose_frequency: must be -1 or a positive frequency, got 0 "
                                "(write -1 to follow the step cycle)")
