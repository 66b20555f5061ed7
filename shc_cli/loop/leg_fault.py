"""Walking on after a servo fault (``run-hw --on-fault adapt``, issue 39): the faulted servo's leg is failed.

When a servo reports a hardware error (overload, overheating, …) mid-run, :class:`LegFaultAdapter` — the run loop's
``absorb`` hook — sets the leg aside on the bus (no goal is written to any of its servos from the next cycle: the
faulted servo has turned its own torque off, the leg's other servos keep their torque and hold their last goal, so
the leg stays where it was rather than dropping onto the ground and dragging), and declares the leg failed
``locked`` to the controller, which holds its joints there, stops walking as for a gait change and walks on with
the gait re-planned for the legs left (:func:`shc_cli.control.leg_failure.adapt`). The plans are made before the
run (one per leg: planning takes seconds, a control cycle milliseconds). A fault that is not one leg's, a second
leg when too few would be left, or a vanished servo still ends the run as before.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from shc_cli.events import event

if TYPE_CHECKING:
    from shc_cli.backends.dynamixel import DynamixelBackend
    from shc_cli.control.controller import Controller
    from shc_cli.control.leg_failure import Adapted
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)


class LegFaultAdapter:
    """The run loop's ``absorb`` hook for ``--on-fault adapt``.

    Args:
        robot: the robot walking.
        controller: its controller (told the failure).
        backend: the servo bus backend (told to write no more goals to the leg).
        heading_rad: the walking direction the plans are made for [rad].
    """

    def __init__(self, robot: Robot, controller: Controller, backend: DynamixelBackend,
                 heading_rad: float = 0.0) -> None:
        from shc_cli.control.leg_failure import FailedLeg, adapt
        from shc_cli.errors import ShcError

        self.controller, self.backend = controller, backend
        self.plans: dict[str, Adapted] = {}
        for leg in robot.legs:
            try:
                self.plans[leg] = adapt(robot, [FailedLeg(leg, "locked", 0.0)], heading_rad)
            except ShcError as error:  # no gait for the legs left: a fault of this leg stops the run
                event(log, logging.WARNING, "leg_fault_plan", "warning: no re-plan without %s: %s", leg, error)

    def __call__(self, fault: str) -> bool:
        """Fail the leg of the alerting servos; False (the run stops) unless they are all one planned leg's."""
        if self.backend.failed_legs:
            return False  # one failed leg is planned for; a second fault stops the run
        servos = self.backend.alerting_servos()
        legs = {leg for leg in self.plans if any(key.startswith(f"{leg}_") for key in servos)}
        if len(legs) != 1 or not all(any(key.startswith(f"{leg}_") for leg in legs) for key in servos):
            return False
        leg = legs.pop()
        self.backend.fail_leg(leg)
        adapted = self.plans[leg]
        self.controller.declare_failure(adapted.failure)
        event(log, logging.ERROR, "leg_failed", "fault: %s — leg %s failed: its servos get no more goals (the "
              "others of the leg hold theirs), walking on %s with a generated gait (%s, duty factor %.3f)", fault,
              leg, ", ".join(other for other in self.plans if other != leg),
              " → ".join("+".join(group) for group in adapted.planned.groups), adapted.planned.duty_factor)
        return True


class FailureEvents:
    """An observer of the run loop: the cycle a failure declared mid-walk (``--fail-leg LEG@T``) is taken up and
    the cycle its re-planned gait starts, as events in ``events.log`` (``leg_failure``)."""

    def __init__(self, controller: Controller) -> None:
        self.controller = controller
        self.declared = self.walking = False

    def __call__(self, cycle: int, command: object, out: object, reading: object) -> str | None:
        controller = self.controller
        scheduled = controller.scheduled_failure
        if not self.declared and scheduled is not None and controller.pending_gait is scheduled.gait:
            self.declared = True
            event(log, logging.INFO, "leg_failure", "leg failure declared (%s): stopping to change to the gait "
                  "re-planned for the legs left", ", ".join(map(str, scheduled.failed)))
        failure = controller.failure
        if not self.walking and self.declared and failure is not None and controller.gait is failure.gait:
            self.walking = True
            event(log, logging.INFO, "leg_failure", "walking on without %s: gait %s, duty factor %.3f",
                  ", ".join(failure.legs), controller.gait.name, controller.cycle.duty_factor)
        return None
