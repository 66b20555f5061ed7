"""``shc fit``: servo parameters recovered from bus-like logs of a simulated robot with known (perturbed) servo
values, non-identifiable parameters reported, a held-out run's power predicted, and bad input refused.

The logs: ``shc simulate`` of Bullet whose ``[servo]`` values are the nominal ones changed by 30–40 %, rewritten as
a servo bus logs them (:func:`shc_cli.domain.fit.synthetic.bus_log`: positions in whole ticks, currents in 2.69 mA
steps, both with noise). Short runs and few parameters keep it fast; benchmarks/fit_servo.py is the full case.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from .test_cli import run

NOMINAL = """extends = "bullet"
[start_up]
time_to_start = 1.0   # a short start-up keeps the runs short
"""
TRUTH = {"position_p_gain": 850.0 * 1.4, "coulomb_friction": 0.73 * 0.6, "holding_ratio": 0.55 * 1.4,
         "idle_power": 0.96 * 0.65}
"""The simulated robot's servo: Bullet's nominal values changed by 30–40 %."""


@pytest.fixture(scope="module")
def logs(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """Bus logs of the perturbed robot: a walk in the air (fitted) and a stance on the ground (held out), each with
    and without a supply power meter; the nominal robot file."""
    from shc_cli.api import simulate
    from shc_cli.domain.fit.synthetic import bus_log

    root = tmp_path_factory.mktemp("fit")
    (root / "nominal.toml").write_text(NOMINAL, encoding="utf-8")
    servo = "\n".join(f"{k} = {v!r}" for k, v in TRUTH.items())
    (root / "truth.toml").write_text(f'extends = "nominal.toml"\n[servo]\n{servo}\n', encoding="utf-8")
    out = {"robot": root / "nominal.toml"}
    for scenario, seconds in (("WA", 1.5), ("SG", 1.0)):
        simulated = simulate(root / "truth.toml", scenario=scenario, duration=seconds, plots=False,
                             out=root / f"sim_{scenario}").path
        out[scenario] = bus_log(simulated, root / f"bus_{scenario}", seed=1)
        out[f"{scenario}_no_power"] = bus_log(simulated, root / f"bus_{scenario}_no_power", seed=2, power=False)
    return out


def test_fit_recovers_the_perturbed_servo_and_predicts_held_out_power(logs: dict[str, Path], tmp_path: Path,
                                                                       cli: Cli) -> None:
    from shc_cli.api import fit, load_robot
    from shc_cli.domain.fit.recording import load_recording
    from shc_cli.domain.fit.rollout import replay
    from shc_cli.domain.fit.solve import electrical

    result = fit([logs["WA"]], robot=logs["robot"], params="gain,coulomb,holding,idle", out=tmp_path / "fit",
                 plots=False)
    data = json.loads((tmp_path / "fit" / "fit.json").read_text(encoding="utf-8"))
    assert set(data) == {"params", "residuals"}
    assert set(data["params"]) == set(TRUTH)
    for name, entry in data["params"].items():
        assert set(entry) == {"value", "initial", "lower", "upper", "uncertainty", "identifiable", "independence",
                              "correlated_with", "unsettled"}
        assert 0.0 <= entry["independence"] <= 1.0 and set(entry["correlated_with"]) <= set(TRUTH) - {name}
        assert entry["lower"] <= entry["value"] <= entry["upper"]
        if entry["identifiable"]:
            assert entry["value"] == pytest.approx(TRUTH[name], rel=0.10), name
    assert data["params"]["position_p_gain"]["identifiable"] and data["params"]["coulomb_friction"]["identifiable"]
    assert data["residuals"]["after"]["current"] < 0.5 * data["residuals"]["before"]["current"]
    # the override extends the robot and validates; it holds the fitted values
    code, _, err = run(["validate", str(tmp_path / "fit" / "robot.toml")], *cli)
    assert code == 0, err
    fitted = load_robot(tmp_path / "fit" / "robot.toml").servo
    assert fitted.position_p_gain == pytest.approx(result.fits[0].values["position_p_gain"], rel=1e-4)
    # a held-out run (standing on the ground): its mean power, replayed with the fitted servo
    held = load_recording(logs["SG"], load_robot(logs["robot"]))
    assert held.power is not None
    predicted = electrical(replay(held, fitted), fitted, held.dt).power.mean()
    nominal = load_robot(logs["robot"]).servo
    before = electrical(replay(held, nominal), nominal, held.dt).power.mean()
    assert predicted == pytest.approx(held.power.mean(), rel=0.05)
    assert abs(before / held.power.mean() - 1.0) > 0.05  # the nominal servo did not already predict it


def test_a_parameter_the_logs_do_not_see_is_reported_as_such(logs: dict[str, Path], tmp_path: Path) -> None:
    """Without a supply meter nothing in a bus log depends on the idle power: infinite uncertainty, not
    identifiable; the Coulomb friction (currents) still is."""
    from shc_cli.api import fit

    fit([logs["WA_no_power"]], robot=logs["robot"], params="coulomb,idle", out=tmp_path / "fit", plots=True)
    data = json.loads((tmp_path / "fit" / "fit.json").read_text(encoding="utf-8"))
    idle, coulomb = data["params"]["idle_power"], data["params"]["coulomb_friction"]
    assert idle["identifiable"] is False and idle["uncertainty"] is None and idle["value"] == idle["initial"]
    assert coulomb["identifiable"] and coulomb["value"] == pytest.approx(TRUTH["coulomb_friction"], rel=0.10)
    assert "power" not in data["residuals"]["after"]
    names = sorted(p.name for p in (tmp_path / "fit").glob("*.png"))
    assert names == ["01_bus_WA_no_power_current.png", "01_bus_WA_no_power_position.png",
                     "01_bus_WA_no_power_power.png"]


Cli = tuple[pytest.CaptureFixture[str], pytest.MonkeyPatch]


@pytest.fixture
def cli(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Cli:
    """What :func:`tests.test_cli.run` needs."""
    return capsys, monkeypatch


@pytest.mark.parametrize(("argv", "message"), [
    (["--params", "gain,colomb"], "'colomb' is not a fittable [servo] parameter"),
    (["--robot", "quadruped"], "differs from 'quadruped'"),
    (["--engine", "bullet3"], "bullet3"),
])
def test_bad_input_is_one_line_and_exit_2(logs: dict[str, Path], tmp_path: Path, argv: list[str], message: str,
                                          cli: Cli) -> None:
    argv = ["fit", str(logs["WA"]), "--robot", str(logs["robot"]), "--out", str(tmp_path / "fit"), *argv]
    code, out, err = run(argv, *cli)
    assert code == 2, (out, err)
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "fit").exists()  # nothing half-written


def test_a_run_without_measured_joints_is_refused(tmp_path: Path, cli: Cli) -> None:
    (tmp_path / "plan").mkdir()
    plan = ["plan", "bullet", "--duration", "0.2", "--no-plots", "--out", str(tmp_path / "plan" / "p")]
    code, _, err = run(plan, *cli)
    assert code == 0, err
    code, _, err = run(["fit", str(tmp_path / "plan" / "p"), "--out", str(tmp_path / "fit")], *cli)
    assert code == 2 and "has no measured joints" in err and len(err.strip().splitlines()) == 1, err


def test_a_bus_log_is_what_a_bus_reads(logs: dict[str, Path]) -> None:
    """Positions in whole ticks, currents in whole 2.69 mA steps, the unmeasured columns listed."""
    from shc_cli.api import load_robot
    from shc_cli.domain.fit.recording import load_recording

    recording = load_recording(logs["WA"], load_robot(logs["robot"]))
    assert recording.current is not None and recording.torque is None and recording.power is not None
    ticks = recording.position / (2 * np.pi / 4096)
    assert np.allclose(ticks, np.round(ticks), atol=2e-3)
    steps = recording.current / 0.00269
    assert np.allclose(steps, np.round(steps), atol=2e-3)
    assert load_recording(logs["WA_no_power"], load_robot(logs["robot"])).power is None


def test_by_joint_fits_each_joint_name_in_its_own_folder(logs: dict[str, Path], tmp_path: Path, cli: Cli) -> None:
    """Every servo has the same (perturbed) Coulomb friction, so each joint group's fit finds it (from a robot that
    has the other values right)."""
    known = {k: v for k, v in TRUTH.items() if k != "coulomb_friction"}
    start = tmp_path / "start.toml"
    start.write_text(f'extends = "{logs["robot"].as_posix()}"\n[servo]\n'
                     + "".join(f"{k} = {v!r}\n" for k, v in known.items()), encoding="utf-8")
    argv = ["fit", str(logs["WA"]), "--robot", str(start), "--params", "coulomb", "--by", "joint",
            "--no-plots", "--out", str(tmp_path / "fit")]
    code, out, err = run(argv, *cli)
    assert code == 0, err
    groups = sorted(p.name for p in (tmp_path / "fit").iterdir())
    assert groups == ["coxa", "coxat", "femur", "tarsus", "tibia"], groups
    for group in groups:
        data = json.loads((tmp_path / "fit" / group / "fit.json").read_text(encoding="utf-8"))
        assert data["params"]["coulomb_friction"]["value"] == pytest.approx(TRUTH["coulomb_friction"], rel=0.10)
        assert (tmp_path / "fit" / group / "robot.toml").is_file()
    assert "[femur]" in out


def test_a_fit_stopped_by_its_budget_says_so(logs: dict[str, Path], tmp_path: Path, cli: Cli) -> None:
    argv = ["fit", str(logs["WA"]), "--robot", str(logs["robot"]), "--params", "coulomb,holding",
            "--max-evaluations", "1", "--no-plots", "--out", str(tmp_path / "fit")]
    code, _, err = run(argv, *cli)
    assert code == 0, err
    assert "stopped at its budget of 1 evaluations before converging" in err
    data = json.loads((tmp_path / "fit" / "fit.json").read_text(encoding="utf-8"))
    assert data["residuals"]["converged"] is False and data["residuals"]["evaluations"] == 1
    # a parameter whose probe still lowered the cost is where the solver stopped, not a value: not identifiable
    assert any(entry["unsettled"] for entry in data["params"].values())
    for name, entry in data["params"].items():
        assert not (entry["unsettled"] and entry["identifiable"]), name


class _Analytic:
    """A :class:`~shc_cli.domain.fit.solve.Problem` whose residuals are a formula of the parameters (no replays):
    the readings ``y = f(x)·u`` of three or four excitation signals ``u``, with noise."""

    @staticmethod
    def problem(names: list[str], model: str, truth: list[float]) -> object:
        from shc_cli.domain.fit.params import parameters
        from shc_cli.domain.fit.solve import Problem
        from shc_cli.spec.robot import Servo

        rng = np.random.default_rng(3)
        signals = rng.normal(size=(4, 400))
        noise = 1e-5 * rng.normal(size=400)

        def readings(x: np.ndarray) -> np.ndarray:
            if model == "scaling":  # a load-free joint: current = (Coulomb + armature·α + viscous·ω) / kt, and
                # a faint roughness in kt as open-loop replays have (so the Jacobian is not exactly singular)
                load = x[1] * signals[0] + 40 * x[2] * signals[1] + 4 * x[3] * signals[2]
                return np.asarray(load / x[0] + 1e-4 * np.sin(300 * x[0]) * signals[3])
            return np.asarray(signals[: len(x)].T @ x)

        measured = readings(np.array(truth)) + noise

        class Formula(Problem):
            def residuals(self, x: np.ndarray) -> np.ndarray:
                return readings(x) - measured

        return Formula([], Servo(), parameters(Servo(), names))


def test_an_exact_scaling_degeneracy_is_not_identifiable_and_names_its_partners() -> None:
    """Torque constant, Coulomb friction, armature and viscous friction scaled together leave a load-free joint's
    current unchanged: however small the noise (and so σ, the Jacobian kept off exact singularity by a faint
    roughness as replays have it), none is identifiable, each trades with the three others
    (the issue-30 bench case); the same four with independent effects are all identifiable."""
    from shc_cli.domain.fit.solve import INDEPENDENT, Problem, solve

    names = ["torque_constant", "coulomb_friction", "armature", "viscous_friction"]
    truth = [1.6 * 1.3, 0.5 * 1.3, 0.01 * 1.3, 0.1 * 1.3]
    problem = _Analytic.problem(names, "scaling", truth)
    assert isinstance(problem, Problem)
    solution = solve(problem, max_evaluations=40)
    assert (solution.uncertainty < 0.05 * solution.x).all()  # the noise alone would call them identifiable
    assert abs(solution.x[0] / truth[0] - 1.0) > 0.1  # though the fit slid along the valley
    assert not solution.identifiable.any()
    assert (solution.independence < INDEPENDENT).all()
    for index in range(4):
        assert set(solution.correlated[index]) == set(range(4)) - {index}
    # the ratios the data do see are fitted: the readings are reproduced
    assert solution.x[1] / solution.x[0] == pytest.approx(truth[1] / truth[0], rel=0.02)

    well = _Analytic.problem(names, "linear", truth)
    assert isinstance(well, Problem)
    solution = solve(well, max_evaluations=40)
    assert solution.identifiable.all(), solution.independence
    assert solution.independence.min() > 0.5 and solution.correlated == ((), (), (), ())
    assert solution.x == pytest.approx(truth, rel=0.01)


def test_independence_is_the_share_the_other_columns_cannot_reproduce() -> None:
    """Columns a, b, a + b (exactly dependent) and an orthogonal d: shares 0, 0, 0, 1; a partly dependent column
    c = a + 0.05·e (e ⟂ a, unit-size like a) has share 0.05/√(1 + 0.05²); a column of zeros has share 0 and is
    nobody's partner."""
    from shc_cli.domain.fit.solve import independence

    basis = np.linalg.qr(np.random.default_rng(0).normal(size=(50, 4)))[0]
    a, b, d, e = basis.T
    shares, partners = independence(np.column_stack([a, 2 * b, a + 2 * b, d, np.zeros(50)]), np.ones(5))
    assert shares == pytest.approx([0, 0, 0, 1, 0], abs=1e-9)
    assert partners == ((1, 2), (0, 2), (0, 1), (), ())
    shares, partners = independence(np.column_stack([a, a + 0.05 * e, d]), np.array([1.0, 1.0, 3.0]))
    assert shares == pytest.approx([0.05 / np.sqrt(1 + 0.05**2), 0.05 / np.sqrt(1 + 0.05**2), 1.0], rel=1e-9)
    assert partners == ((1,), (0,), ())
