"""Verify a robot's walking speed limits by trial walks and print them as its file's ``[walker.speed_shares]`` tables.

Run (one to a few minutes per gait on two cores):

    .venv/bin/python docs/experiments/verify_speed_limits.py bullet tripod ripple wave amble bipod

For each gait, :func:`shc_cli.control.verified_limits.trial_shares` walks the controller alone at OpenSHC's limit of
every walkspace bearing and of turning, and bisects each share down until no cycle misses an IK target, clamps a
joint, has its speed guarded or comes within 5 % of a joint's range of a limit. Paste the printed tables into the
robot file: runs then use them with no trials (``walker.speed_shares``; a robot or gait edited since has another
fingerprint, and then OpenSHC's limits are used). ``walker.verify_speed_limits = true`` runs the same trials at
run time instead (cached per install). ``tests/test_speed_shares.py`` checks that the default robot's tables are
still clean and still match its file.
"""

from __future__ import annotations

import sys
import time

from shc_cli.control.verified_limits import shares_table, trial_shares
from shc_cli.spec.loading import load_gait, load_robot


def main(arguments: list[str]) -> int:
    """Print the speed-share tables of ``arguments[0]`` (a robot) for the gaits that follow."""
    if len(arguments) < 2:
        print(__doc__)
        return 2
    robot = load_robot(arguments[0]).robot
    for name in arguments[1:]:
        gait = load_gait(name).gait
        started = time.perf_counter()
        shares = trial_shares(robot, gait)
        print(f"# {gait.name}: verified in {time.perf_counter() - started:.0f} s", file=sys.stderr)
        print(shares_table(robot, gait, shares))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
