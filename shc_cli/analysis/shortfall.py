"""Why a walk fell short of the distance asked (issue 37, point 8): the joint that saturated, the foot that slipped.

A simulated walk that covered less than :data:`SHORT_SHARE` of its commanded distance (and did not fall) gets a
reason on its summary line, read from its log over the RUNNING window:

* a joint **saturated**: its measured torque at the servo's stall torque (:data:`STALL_SHARE` of it), its command
  moving at its ``max_vel`` (the speed guard or the IK's clamp held it), or its command at a joint limit — in more
  than :data:`SATURATED_SHARE` of the window's cycles; the joint with the largest share is named;
* a foot **slipped**: the foot that slid the most while in contact, when that is more than
  :data:`~shc_cli.analysis.run_line.SLIP_SHARE` of the distance walked.

Each is a figure a user can check (``shc analyze``, ``log.csv``), not a diagnosis the controller made.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from shc_cli.record.runread import RunLog

SHORT_SHARE = 0.6
"""A walk that covered less than this share of its commanded distance says why (issue 37's bar for an imported
robot on flat ground)."""
STALL_SHARE = 0.95
"""A joint whose measured torque is at least this share of its servo's stall torque is saturated."""
SATURATED_SHARE = 0.05
"""A joint saturated in more than this share of the window's cycles is named."""
LIMIT_MARGIN = 1e-3
"""A command this close to a joint limit [rad] is at it."""


@dataclass(frozen=True)
class Saturation:
    """The joint saturated most often over a window.

    Attributes:
        joint: ``<LEG>_<joint>``.
        how: ``"at stall torque"``, ``"at its speed limit"`` or ``"at its joint limit"``.
        share: the share of the window's cycles it was.
    """

    joint: str
    how: str
    share: float


def saturation(log: RunLog, rows: np.ndarray) -> Saturation | None:
    """The joint most often at its servo's stall torque, its speed limit or a joint limit over ``rows`` (each of the
    three counted on its own, the largest share kept), or None when none reaches :data:`SATURATED_SHARE`."""
    robot = log.robot
    names = [f"{leg_id}_{name}" for leg_id, leg in robot.legs.items() for name in leg.joints]
    slots = [(i, k) for i, leg in enumerate(robot.legs.values()) for k in range(len(leg.joints))]
    joints = [joint for leg in robot.legs.values() for joint in leg.joints.values()]
    if len(rows) < 2:
        return None
    candidates: list[tuple[float, str, str]] = []
    if log.efforts is not None:
        torque = np.abs(np.stack([log.efforts[rows, i, k] for i, k in slots], axis=1))
        stall = robot.servo.stall_torque
        shares = (torque >= STALL_SHARE * stall).mean(axis=0)
        candidates += [(float(s), n, "at stall torque") for s, n in zip(shares, names, strict=True)]
    if log.commanded is not None:
        command = np.stack([log.commanded[rows, i, k] for i, k in slots], axis=1)
        bound = np.array([j.max_vel * robot.time_delta for j in joints])
        fast = (np.abs(np.diff(command, axis=0)) >= 0.99 * bound).mean(axis=0)
        candidates += [(float(s), n, "at its speed limit") for s, n in zip(fast, names, strict=True)]
        lower, upper = np.array([j.min for j in joints]), np.array([j.max for j in joints])
        at_limit = ((command <= lower + LIMIT_MARGIN) | (command >= upper - LIMIT_MARGIN)).mean(axis=0)
        candidates += [(float(s), n, "at its joint limit") for s, n in zip(at_limit, names, strict=True)]
    if not candidates:
        return None
    share, joint, how = max(candidates)
    return Saturation(joint, how, share) if share > SATURATED_SHARE else None


def worst_slip(feet: np.ndarray, contact: np.ndarray, legs: list[str]) -> tuple[str, float]:
    """The leg whose foot slid the most while in contact, and how far [m] (``feet`` (N, legs, 3) world positions,
    ``contact`` (N, legs))."""
    from shc_cli.analysis.metrics import foot_slip

    slip = foot_slip(feet, contact)
    worst = int(np.argmax(slip))
    return legs[worst], float(slip[worst])


def shortfall_reasons(log: RunLog, rows: np.ndarray, walked: float, slip_share: float) -> list[str]:
    """What held a short walk back over ``rows`` (the RUNNING window), ``walked`` [m] its distance: the saturated
    joint, and the foot that slipped more than ``slip_share`` of ``walked``; empty when neither shows."""
    from shc_cli.analysis.metrics import feet_and_com

    reasons = []
    found = saturation(log, rows)
    if found is not None:
        reasons.append(f"{found.joint} {found.how} in {100.0 * found.share:.0f} % of the cycles")
    feet, _ = feet_and_com(log, rows)
    leg, slid = worst_slip(feet, log.contact[rows], list(log.robot.legs))
    if walked > 0.0 and slid > slip_share * walked:
        reasons.append(f"foot {leg} slips most ({slid:.3f} m over {walked:.3f} m walked)")
    return reasons
