"""Overhead per trial of ``shc optimize``: how much of a trial is the simulation.

Run:  .venv/bin/python benchmarks/bench_optimize.py [--trials 6] [--duration 10]

Runs ``studies/bullet_flat.toml`` (one seed per trial) with ``--duration`` seconds of walking, one local worker, in
this process, and splits the wall time of the trial loop per trial into

* the simulation loop (the run's ``summary.json`` ``wall_time_s``: controller + physics + log),
* the rest of the run (robot file variant, loading and checks, URDF and world set-up, analysis) — the trial's run
  time minus the simulation loop,
* the search: Optuna's ask / suggest / tell on the SQLite storage and rewriting ``trials.csv`` (the command times it
  and reports it per trial),
* the rest of the command spread over the trials (imports, creating the storage, the worker pool).

Medians over the trials; the first trial is excluded (it loads numba's compiled kernels).
"""

from __future__ import annotations

import argparse
import csv
import re
import statistics
import tempfile
import time
from pathlib import Path

from shc_cli.domain.optimize.checks import check_study
from shc_cli.domain.optimize.loop import run_optimize
from shc_cli.domain.optimize.outputs import write_outputs
from shc_cli.domain.optimize.storage import open_study
from shc_cli.spec.study import load_study

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=6)
    parser.add_argument("--duration", type=float, default=10.0)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        text = (ROOT / "studies" / "bullet_flat.toml").read_text(encoding="utf-8")
        study_file = Path(folder) / "bench.toml"
        study_file.write_text(re.sub(r"(?m)^duration = .*$", f"duration = {args.duration}", text), encoding="utf-8")
        started = time.perf_counter()
        check_study(load_study(study_file))
        checks = time.perf_counter() - started
        out = Path(folder) / "out"
        started = time.perf_counter()
        report = run_optimize(study_file, args.trials, 1, "local", None, out, False)
        total = time.perf_counter() - started
        search = report.overhead_s / max(report.ran, 1)
        spec = load_study(study_file)
        started = time.perf_counter()
        write_outputs(spec, out, open_study(spec, out, True).get_trials(deepcopy=False), figures=True)
        outputs = time.perf_counter() - started
        with (out / "trials.csv").open(newline="") as handle:
            rows = list(csv.DictReader(handle))
    runs = [float(r["trial_wall_s"]) for r in rows]
    sims = [float(r["sim_wall_s"]) for r in rows]
    rest = [a - b for a, b in zip(runs, sims, strict=True)]
    rest_of_command = (total - checks - outputs - sum(runs)) / len(rows) - search
    run, sim = statistics.median(runs[1:]), statistics.median(sims[1:])
    print(f"{len(rows)} trials of {args.duration:g} s walking (+ 5 s start-up), 1 worker; total {total:.1f} s, of "
          f"which study checks {checks:.1f} s and the final tables, robot files and figures {outputs:.1f} s")
    print(f"per trial, median of trials 2..{len(rows)}:")
    print(f"  trial runs        {run:7.3f} s")
    print(f"  simulation loop   {sim:7.3f} s  ({sim / run:.1%} of the runs)")
    print(f"  rest of the run   {statistics.median(rest[1:]):7.3f} s")
    print(f"  search, mean      {search:7.3f} s  (Optuna ask/suggest/tell on SQLite, trials.csv; timed by the command)")
    print(f"  rest, mean        {rest_of_command:7.3f} s  (imports, storage creation, process pool; once per command)")


if __name__ == "__main__":
    main()
