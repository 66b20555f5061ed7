"""``shc fit`` on logs with known truth, the full case: every default parameter perturbed, 60 s of bus logs.

Run:  .venv/bin/python benchmarks/bench_fit.py [--robot bullet] [--runs WA:25,SG:25] [--repeats 3] [--no-power]
      [--out DIR]

Simulates the robot (default Bullet, 30 servos; ``athena_paper`` has 18) with its ``[servo]`` values changed by
30–50 % (:data:`FACTORS`; a value of 0 becomes half the parameter's typical size) in the ``--runs`` (scenario:seconds
after the start-up; default walking in the air 25 s and standing on the ground 25 s: 60 s of logs with the 5 s
start-ups), turns them into what a servo
bus logs (positions in ticks, currents in 2.69 mA steps, noise; the supply power kept unless ``--no-power``) and
fits the robot's nominal servo to them with ``shc fit``'s default parameters (the held-out run always keeps its
supply power, as a bench check with a meter would). Prints each parameter (truth, fitted,
error, uncertainty, identifiable), the mean power of a held-out run (walking on the ground at another velocity)
measured, predicted by the fitted and by the nominal servo, and the fit's wall time: the median over ``--repeats``
with the machine's load average before each.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

FACTORS = {"position_p_gain": 1.4, "coulomb_friction": 0.6, "viscous_friction": 1.5, "holding_ratio": 1.4,
           "armature": 1.45, "idle_power": 0.65, "torque_constant": 0.7}
"""Truth ÷ nominal of each fitted parameter."""
HELD_OUT = ("WG", 10.0, "0.5,0,0.3")


def main() -> None:
    from shc_cli.api import fit, load_robot, simulate
    from shc_cli.domain.fit.params import DEFAULT_PARAMS, TYPICAL
    from shc_cli.domain.fit.recording import load_recording
    from shc_cli.domain.fit.rollout import replay
    from shc_cli.domain.fit.solve import electrical
    from shc_cli.domain.fit.synthetic import bus_log

    parser = argparse.ArgumentParser()
    parser.add_argument("--robot", default="bullet")
    parser.add_argument("--runs", default="WA:25,SG:25", help="fitted runs, SCENARIO:SECONDS,...")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--no-power", action="store_true")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    root = args.out or Path(tempfile.mkdtemp(prefix="bench_fit_"))
    root.mkdir(parents=True, exist_ok=True)
    nominal = load_robot(args.robot).servo
    truth = {}
    for name in DEFAULT_PARAMS:
        value = getattr(nominal, name)
        changed = value * FACTORS[name] if value > 0 else 0.5 * TYPICAL[name]
        truth[name] = changed if name != "holding_ratio" or changed <= 1.0 else value / FACTORS[name]  # a ratio ≤ 1
    body = "\n".join(f"{k} = {v!r}" for k, v in truth.items())
    (root / "truth.toml").write_text(f'extends = "{args.robot}"\n[servo]\n{body}\n', encoding="utf-8")
    logs = []
    runs = {f"{scenario}{seconds}": (scenario, float(seconds), "1,0,0")
            for scenario, seconds in (part.split(":") for part in args.runs.split(","))}
    for name, (scenario, seconds, velocity) in {**runs, "held_out": HELD_OUT}.items():
        sim = root / f"sim_{name}"
        if not sim.exists():
            simulate(root / "truth.toml", scenario=scenario, duration=seconds, velocity=velocity, plots=False,
                     out=sim)
        metered = not args.no_power or name == "held_out"  # the check run has a supply meter
        bus = root / f"bus_{name}{'' if metered else '_no_power'}"
        if not bus.exists():
            bus_log(sim, bus, seed=len(logs), power=metered)
        logs.append(bus)
    robot = load_robot(args.robot)
    seconds = sum(len(load_recording(p, robot).position) * robot.time_delta for p in logs[:-1])
    servos = sum(len(leg.joints) for leg in robot.legs.values())
    times, loads = [], []
    result = None
    for _ in range(args.repeats):
        loads.append(os.getloadavg()[0])
        started = time.perf_counter()
        result = fit(logs[:-1], robot=args.robot, out=root / "fit", overwrite=True, plots=False)
        times.append(time.perf_counter() - started)
    assert result is not None
    group = result.fits[0]
    print(f"{args.robot}: {servos} servos, {seconds:.1f} s of logs in {len(logs) - 1} runs "
          f"({'no supply power' if args.no_power else 'with supply power'}); {group.solution.replays} replays, "
          f"{group.solution.iterations} evaluations")
    for index, p in enumerate(group.parameters):
        value, sigma = group.solution.x[index], group.solution.uncertainty[index]
        partners = ", ".join(group.parameters[k].name for k in group.solution.correlated[index])
        ok = ("identifiable" if group.solution.identifiable[index] else "NOT identifiable") + (
            f", independence {group.solution.independence[index]:.3f}") + (
            f", trades with {partners}" if partners else "") + (
            ", probes still lowering the cost" if group.solution.unsettled[index] else "")
        print(f"  {p.name:20s} nominal {p.initial:9.4g} truth {truth[p.name]:9.4g} fitted {value:9.4g} "
              f"({value / truth[p.name] - 1:+.1%}) ± {sigma:.3g}  {ok}")
    held = load_recording(logs[-1], robot)
    fitted = load_robot(root / "fit" / "robot.toml").servo
    predicted = electrical(replay(held, fitted), fitted, held.dt).power.mean()
    before = electrical(replay(held, nominal), nominal, held.dt).power.mean()
    measured = held.power.mean() if held.power is not None else float("nan")
    print(f"held-out run (WG at {HELD_OUT[2]}): mean power measured {measured:.1f} W, fitted {predicted:.1f} W "
          f"({predicted / measured - 1:+.1%}), nominal {before:.1f} W ({before / measured - 1:+.1%})")
    print(f"fit wall time: median {statistics.median(times):.1f} s of {len(times)} "
          f"({', '.join(f'{t:.1f}' for t in times)}); load average before each: "
          f"{', '.join(f'{x:.1f}' for x in loads)} on {os.cpu_count()} cores")


if __name__ == "__main__":
    main()
