"""``shc fit`` on the servo emulator's bus: the full ``shc fit --plan`` excitation recorded by run-hw on 18 emulated
XM430-W350 with a known servo model, fitted with ``--scenario BENCH`` (issue 30's emulator acceptance).

Run:  .venv/bin/python benchmarks/bench_fit_emulator.py [--wall-clock] [--out DIR]

The emulated servos' truth and the robot file's start are :data:`tests.test_fit_emulator.TRUTH` and ``START`` (gain
−30 %, friction and armature +50 %). Three fits are printed, each parameter with its truth, fitted value, error,
uncertainty and identifiability, plus the channels' RMS error and the wall time:

1. the run on the emulator's virtual clock (run-hw's cycles exactly periodic), fitting gain, Coulomb and viscous
   friction and armature;
2. the same with ``torque_constant`` too: on a bench the torque constant, armature and both frictions scale together
   exactly (only their ratios change what the bus reads), so this one shows what a fit makes of a direction the logs
   do not see;
3. with ``--wall-clock``, a real-time ``shc run-hw`` (its own process) against the emulator on the wall clock, as on a
   real robot: its ``timing.csv`` gives the replay the cycles' real lengths. On a loaded machine run-hw can end early
   with a false "no reply" (the emulator thread starved, see tests/test_run_hw.py); the fit then takes what was
   logged.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def _fit(run: Path, robot: Path, params: str, out: Path) -> None:
    from shc_cli.api import fit
    from tests.test_fit_emulator import TRUTH

    started = time.perf_counter()
    result = fit([run], robot=robot, params=params, scenario="BENCH", out=out, plots=False, overwrite=True)
    elapsed = time.perf_counter() - started
    group = result.fits[0]
    print(f"  {'parameter':18s} {'truth':>9s} {'fitted':>9s} {'error':>7s} {'± 1σ':>9s}  identifiable")
    for index, parameter in enumerate(group.parameters):
        truth = TRUTH.get(parameter.name)
        value = group.values[parameter.name]
        error = f"{value / truth - 1:+.1%}" if truth else "—"
        print(f"  {parameter.name:18s} {truth or parameter.initial:9.4g} {value:9.4g} {error:>7s} "
              f"{float(group.solution.uncertainty[index]):9.2g}  {bool(group.solution.identifiable[index])} "
              f"(independence {group.solution.independence[index]:.3f}"
              + "".join(f", trades with {group.parameters[k].name}" for k in group.solution.correlated[index])
              + (", still moving" if group.solution.unsettled[index] else "") + ")")
    print("  RMS " + ", ".join(f"{k} {group.before[k]:.3g} → {group.after[k]:.3g}" for k in group.after)
          + f"; {group.solution.replays} replays, {elapsed:.1f} s (load {os.getloadavg()[0]:.1f})")


def _wall_clock(robot: Path, plan: Path, out: Path) -> Path:
    """Real-time run-hw in its own process against the emulator in this one (the wall clock)."""
    from shc_cli.hardware.emulator import BusEmulator
    from shc_cli.spec.robot import Servo
    from tests.test_fit_emulator import TRUTH

    truth = Servo(model="XM430-W350", control="dynamixel", **TRUTH)  # type: ignore[arg-type]
    gc.collect()
    gc.disable()
    try:
        with BusEmulator({k + 1: "XM430-W350" for k in range(18)}, dynamics=truth, current_noise_ma=5.0) as bus:
            done = subprocess.run([sys.executable, "-m", "shc_cli.cli", "run-hw", str(robot), "--port", bus.port,
                                   "--commands", str(plan), "--out", str(out), "--overwrite"],
                                  capture_output=True, text=True, timeout=600)
    finally:
        gc.enable()
    summary = json.loads((out / "summary.json").read_text())
    timing = (out / "timing.csv").read_text().splitlines()[1:]
    late = sum(line.endswith(",1") for line in timing)
    print(f"  run-hw exit {done.returncode}: {summary['cycles']} cycles, {late} late, fault {summary['fault']}")
    return out


def main() -> None:
    from shc_cli.api import fit_plan
    from shc_cli.spec.robot import Servo
    from tests.test_fit_emulator import START, TRUTH, hexapod, record

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--wall-clock", action="store_true", help="also a real-time run-hw (3.)")
    parser.add_argument("--out", type=Path, default=None, help="where the runs and fits go (default a temporary "
                        "directory)")
    args = parser.parse_args()
    folder = args.out or Path(tempfile.mkdtemp(prefix="bench_fit_emulator_"))
    folder.mkdir(parents=True, exist_ok=True)
    robot = hexapod(folder, START)
    plan = fit_plan(robot, out=folder / "plan.toml", overwrite=True)
    print(f"robot file {START}; emulated truth {TRUTH}")
    started = time.perf_counter()
    run = record(robot, plan, folder / "run-virtual", Servo(model="XM430-W350", control="dynamixel", **TRUTH))
    print(f"1. virtual clock: run-hw {time.perf_counter() - started:.1f} s")
    _fit(run, robot, "gain,coulomb,viscous,armature", folder / "fit-virtual")
    print("2. virtual clock, with the torque constant")
    _fit(run, robot, "gain,coulomb,viscous,armature,kt", folder / "fit-virtual-kt")
    if args.wall_clock:
        print("3. wall clock")
        wall = _wall_clock(robot, plan, folder / "run-wall")
        _fit(wall, robot, "gain,coulomb,viscous,armature", folder / "fit-wall")
    print(f"→ {folder}")


if __name__ == "__main__":
    main()
