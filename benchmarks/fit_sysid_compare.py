"""``shc fit``'s solver and uncertainties beside MuJoCo's own system-identification toolbox (``mujoco.sysid``).

Run:  .venv/bin/python benchmarks/fit_sysid_compare.py RUN... [--robot bullet] [--params ...]

``mujoco.sysid`` (MuJoCo ≥ 3.5, with the ``mujoco[sysid]`` extra: absl-py, colorama, jinja2, plotly, tabulate) rolls
out MJCF models whose parameters it writes into an ``MjSpec`` and whose actuators MuJoCo computes itself; shc's
Dynamixel servo is a torque law evaluated in Python every physics step, which its native rollouts cannot run. What
it does have that applies is its solver and its interval computation: :func:`mujoco.sysid.optimize` with
``optimizer="mujoco"`` (:func:`mujoco.minimize.least_squares`, its default) over shc's own residuals (the same
replays), and :func:`mujoco.sysid.calculate_intervals` on shc's Jacobian. This prints, for the same runs and start,
each parameter as ``shc fit`` finds it (SciPy TRF, its forward differences) and as ``mujoco.sysid.optimize`` does,
the cost, the replays and wall time of each, and the uncertainties: shc's σ (with its correlation inflation) and
sysid's 95 % half-width (t-quantile × σ without inflation).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np


def main() -> None:
    from shc_cli.api import load_robot
    from shc_cli.domain.fit.params import parameters, parse_params
    from shc_cli.domain.fit.recording import load_recording
    from shc_cli.domain.fit.solve import CORRELATION_CYCLES, Problem, solve

    parser = argparse.ArgumentParser()
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--robot", default="bullet")
    parser.add_argument("--params", default=None)
    parser.add_argument("--max-iters", type=int, default=15)
    args = parser.parse_args()
    try:
        import mujoco
        import mujoco.sysid as sysid
        sysid_optimize, intervals = sysid.optimize, sysid.calculate_intervals
    except (ImportError, AttributeError):
        print("mujoco.sysid is not usable here: it needs MuJoCo >= 3.5 with the mujoco[sysid] extra "
              "(absl-py, colorama, jinja2, plotly, tabulate)")
        return
    robot = load_robot(args.robot)
    recordings = [load_recording(run, robot) for run in args.runs]
    names = parse_params(args.params)

    def problem() -> Problem:
        return Problem(recordings, robot.servo, parameters(robot.servo, names))

    ours = problem()
    started = time.perf_counter()
    solution = solve(ours, max_evaluations=args.max_iters * 2)
    ours_s = time.perf_counter() - started
    jacobian = ours.jacobian(solution.x)
    residual = ours.residuals(solution.x)
    _, half = intervals([residual], jacobian)

    theirs = problem()
    specs = theirs.parameters
    table = sysid.ParameterDict({p.name: sysid.Parameter(p.name, p.initial, p.lower, p.upper) for p in specs})

    def residual_fn(x: np.ndarray, _: object) -> tuple[list[np.ndarray], None, None]:
        x = np.asarray(x, dtype=float)
        if x.ndim == 2:  # mujoco.minimize's finite differences ask for several points at once
            return [np.stack([theirs.residuals(x[:, k]) for k in range(x.shape[1])], axis=1)], None, None
        return [theirs.residuals(x)], None, None

    started = time.perf_counter()
    found, _ = sysid_optimize(table, residual_fn, optimizer="mujoco", verbose=False, max_iters=args.max_iters,
                              x_scale=np.array([p.scale for p in specs]))
    theirs_s = time.perf_counter() - started
    x_theirs = found.as_vector()
    cost_theirs = 0.5 * float(np.sum(theirs.residuals(x_theirs) ** 2))
    print(f"MuJoCo {mujoco.__version__}; {len(recordings)} runs, {len(residual)} residuals")
    print(f"shc fit (SciPy TRF):          cost {solution.cost_after:.5g}, {ours.replays} replays, {ours_s:.1f} s")
    print(f"mujoco.sysid.optimize (mujoco): cost {cost_theirs:.5g}, {theirs.replays} replays, {theirs_s:.1f} s")
    inflation = np.sqrt(CORRELATION_CYCLES)
    for index, p in enumerate(specs):
        sigma = solution.uncertainty[index]
        print(f"  {p.name:20s} start {p.initial:9.4g}  shc {solution.x[index]:9.4g} ± {sigma:.3g}"
              f" (σ/√{CORRELATION_CYCLES:g} = {sigma / inflation:.3g})  sysid {x_theirs[index]:9.4g}"
              f"  sysid 95 % half-width {half[index]:.3g}")


if __name__ == "__main__":
    main()
