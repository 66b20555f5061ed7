"""OpenSHC's dynamic parameters as ROS 2 parameters of ``shc ros2``'s node.

Each of OpenSHC's run-time adjustable parameters (``step_frequency``, ``swing_height``, ``swing_width``,
``step_depth``, ``stance_span_modifier``, ``virtual_mass``, ``virtual_stiffness``, ``virtual_damping_ratio``,
``force_gain``: the robot file's ``{default, min, max, step}``, OpenSHC's ``dynamic_parameters``) is declared as a
double with a descriptor (its description and its ``[min, max]`` as a floating-point range); a parameter client
(``ros2 param``, rclpy's ``AsyncParameterClient``) lists, gets and sets them. A set inside the range changes the
running controller from the next cycle, as the remote's parameter adjustment does (the controller's own change,
the study's §9.6); a set outside it is refused by rclpy with the reason (the range). A ``--params-file`` gives
start values; one outside its range refuses the start in one line. The robot's name, gait and control rate are
read-only parameters.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from shc_cli.errors import Issue, SpecError
from shc_cli.events import event
from shc_cli.spec.robot import ADJUSTABLE, ADJUSTABLE_WALKER

if TYPE_CHECKING:
    from shc_cli.ros.transport import ParameterSink
    from shc_cli.spec.robot import Robot

log = logging.getLogger(__name__)

DESCRIPTIONS = {
    "step_frequency": "step frequency [Hz]",
    "swing_height": "swing height of the tips [m]",
    "swing_width": "swing width of the tips [m]",
    "step_depth": "step depth below the walk plane [m]",
    "stance_span_modifier": "stance span modifier (-1 narrow .. 1 wide)",
    "virtual_mass": "admittance virtual mass [kg]",
    "virtual_stiffness": "admittance virtual stiffness [N/m]",
    "virtual_damping_ratio": "admittance virtual damping ratio",
    "force_gain": "admittance force gain",
}


def adjustable(robot: Robot) -> dict[str, tuple[float, float, float]]:
    """``name → (default, min, max)`` of the robot's dynamic parameters."""
    found: dict[str, tuple[float, float, float]] = {}
    for name in ADJUSTABLE:
        table = robot.walker if name in ADJUSTABLE_WALKER else robot.admittance
        spec = getattr(table, name, None)
        if spec is not None and hasattr(spec, "default"):
            found[name] = (float(spec.default), float(spec.min), float(spec.max))
    return found


class Parameters:
    """Declares the parameters on ``node`` (an rclpy node) and hands accepted sets to ``remote``."""

    def __init__(self, node: Any, robot: Robot, remote: ParameterSink) -> None:
        from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
        from rclpy.exceptions import InvalidParameterValueException

        self.remote = remote
        self.ranges = adjustable(robot)
        for name, (default, low, high) in self.ranges.items():
            descriptor = ParameterDescriptor(
                description=f"OpenSHC dynamic parameter: {DESCRIPTIONS.get(name, name)}",
                floating_point_range=[FloatingPointRange(from_value=low, to_value=high, step=0.0)])
            try:
                node.declare_parameter(name, default, descriptor)
            except InvalidParameterValueException:
                raise SpecError([Issue(None, None, f"--params-file: {name}", f"outside its range [{low:g}, "
                                       f"{high:g}]", "give a value in the robot's range")]) from None
            value = float(node.get_parameter(name).value)
            if value != default:
                remote.set_parameter(name, value)
        info: tuple[tuple[str, object], ...] = (("robot", robot.name), ("gait", str(robot.walker.gait)),
                                                ("control_rate", 1.0 / robot.time_delta))
        for name, shown in info:
            node.declare_parameter(name, shown, ParameterDescriptor(description=f"the robot's {name}",
                                                                    read_only=True))
        node.add_post_set_parameters_callback(self._changed)

    def _changed(self, parameters: list[Any]) -> None:
        for parameter in parameters:
            if parameter.name in self.ranges:
                self.remote.set_parameter(parameter.name, float(parameter.value))
                event(log, logging.INFO, "parameter", "parameter %s set to %g (ROS 2 parameter client)",
                      parameter.name, float(parameter.value))
