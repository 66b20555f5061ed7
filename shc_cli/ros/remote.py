"""OpenSHC's remote topics as the run loop's input: ``/syropod_remote/*`` → one :class:`Command` per cycle.

The topics, types and values are those ``syropod_highlevel_controller`` subscribes (OpenSHC's ``main.cpp`` and
``state_controller.cpp``; the study's §9–10): system state (SUSPENDED 0 / OPERATIONAL 1), desired robot state
(PACKED 0, READY 1, RUNNING 2), desired velocity and posing velocity (Twist), pose reset mode, gait selection
(WAVE 0, AMBLE 1, RIPPLE 2, TRIPOD 3; −1 none), cruise control (OFF 0 / ON 1), parameter selection (1..9 in
OpenSHC's order) and adjustment (−1/+1), primary/secondary leg selection (leg index, −1 none), leg state (WALKING 0
/ MANUAL 1, a change toggles the selected leg) and tip velocity (Point).

Timing is OpenSHC's: its loop publishes a cycle's outputs and *then* processes the messages that arrived
(``ros::spinOnce``), so a message counts from the cycle after the next publication. :meth:`RemoteInput.latch`
takes that snapshot (the node's outputs call it right after publishing) and :meth:`RemoteInput.next` returns it.
While the system is SUSPENDED, OpenSHC's loop does nothing; :meth:`next` waits (time does not pass for the
controller) until it is OPERATIONAL again or the run is stopped.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

from shc_cli.control.controller import Command, RobotState
from shc_cli.control.pose import PoseReset
from shc_cli.ros.transport import Node
from shc_cli.spec.gait import Gait
from shc_cli.spec.robot import ADJUSTABLE, Robot

log = logging.getLogger(__name__)

REMOTE = "/syropod_remote"
GAIT_SELECTION = ("wave", "amble", "ripple", "tripod")
"""OpenSHC's GaitDesignation values 0..3, as shc gait names."""
OPERATIONAL = 1


@dataclass
class _State:
    """The last value received on each remote topic."""

    operational: bool = False
    robot_state: int | None = None
    velocity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    pose_velocity: tuple[float, float, float, float, float, float] = (0.0,) * 6
    pose_reset: int = 0
    gait: int = -1
    cruise: int = 0
    parameter: int = 0
    adjustments: int = 0
    primary_leg: int = -1
    secondary_leg: int = -1
    toggles: list[int] = field(default_factory=list)
    tip_velocity: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    set_values: dict[str, float] = field(default_factory=dict)


class RemoteInput:
    """An input source fed by OpenSHC's remote topics (see the module's text for the semantics).

    Args:
        node: the ROS node to subscribe on.
        robot: the robot (leg ids for leg selection, adjustable parameters' steps and ranges).
        gaits: gait name → loaded gait for gait selection (names missing here are ignored with a warning).
        stopped: tells whether the run was asked to stop (a wait while SUSPENDED ends then).
    """

    def __init__(self, node: Node, robot: Robot, gaits: dict[str, Gait], stopped: Callable[[], bool]) -> None:
        self._robot, self._gaits, self._stopped = robot, gaits, stopped
        self._legs = list(robot.legs)
        self._state = _State()
        self._lock = threading.Lock()
        self._operational = threading.Event()
        self._command = Command()
        self._gait_now = -1
        self._cruise_now = 0
        self._leg_state = {0: 0, 1: 0}
        self._values = {name: _adjustable(robot, name) for name in ADJUSTABLE}
        self.subscribe(node)

    def subscribe(self, node: Node) -> None:
        """Subscribe every remote topic."""
        s = self._state

        def int8(name: str) -> Callable[[object], None]:
            def set_value(message: object) -> None:
                with self._lock:
                    self._set(name, int(getattr(message, "data", 0)))
            return set_value

        def twist(message: object) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
            lin, ang = message.linear, message.angular  # type: ignore[attr-defined]
            return (float(lin.x), float(lin.y), float(lin.z)), (float(ang.x), float(ang.y), float(ang.z))

        def velocity(message: object) -> None:
            lin, ang = twist(message)
            with self._lock:
                s.velocity = (lin[0], lin[1], ang[2])

        def pose(message: object) -> None:
            lin, ang = twist(message)
            with self._lock:
                s.pose_velocity = (*lin, *ang)

        def tip(index: int) -> Callable[[object], None]:
            def set_tip(message: object) -> None:
                with self._lock:
                    p = message
                    s.tip_velocity[index] = (float(p.x), float(p.y), float(p.z))  # type: ignore[attr-defined]
            return set_tip

        for topic in ("system_state", "robot_state", "pose_reset_mode", "gait_selection", "cruise_control_mode",
                      "parameter_selection", "parameter_adjustment", "primary_leg_selection",
                      "secondary_leg_selection", "primary_leg_state", "secondary_leg_state", "posing_mode",
                      "planner_mode"):
            node.subscribe(f"{REMOTE}/{topic}", "std_msgs/Int8", int8(topic))
        node.subscribe(f"{REMOTE}/desired_velocity", "geometry_msgs/Twist", velocity)
        node.subscribe(f"{REMOTE}/desired_pose", "geometry_msgs/Twist", pose)
        node.subscribe(f"{REMOTE}/primary_tip_velocity", "geometry_msgs/Point", tip(0))
        node.subscribe(f"{REMOTE}/secondary_tip_velocity", "geometry_msgs/Point", tip(1))

    def _set(self, name: str, value: int) -> None:
        s = self._state
        if name == "system_state":
            s.operational = value == OPERATIONAL
            (self._operational.set if s.operational else self._operational.clear)()
        elif name == "robot_state":
            s.robot_state = value if value in (0, 1, 2) else s.robot_state
        elif name == "pose_reset_mode":
            s.pose_reset = value
        elif name == "gait_selection":
            s.gait = value
        elif name == "cruise_control_mode":
            s.cruise = value
        elif name == "parameter_selection":
            s.parameter = value
        elif name == "parameter_adjustment" and value in (-1, 1):
            s.adjustments += value
        elif name in ("primary_leg_selection", "secondary_leg_selection"):
            setattr(s, name.replace("_selection", ""), value)
        elif name in ("primary_leg_state", "secondary_leg_state"):
            index = 0 if name.startswith("primary") else 1
            if value in (0, 1) and value != self._leg_state[index]:
                self._leg_state[index] = value
                s.toggles.append(index)

    def set_parameter(self, name: str, value: float) -> None:
        """Set a dynamic parameter from the next latched cycle on (a ROS 2 parameter set; ``value`` in range)."""
        with self._lock:
            self._state.set_values[name] = value

    def latch(self) -> None:
        """Take the messages received so far as the next cycle's command (called right after publishing)."""
        with self._lock:
            self._command = self._build()

    def _build(self) -> Command:
        s = self._state
        gait = None
        if s.gait != self._gait_now and 0 <= s.gait < len(GAIT_SELECTION):
            self._gait_now = s.gait
            gait = self._gaits.get(GAIT_SELECTION[s.gait])
            if gait is None:
                log.warning("gait selection %d (%s): no such gait for this robot", s.gait, GAIT_SELECTION[s.gait])
        cruise = None
        if s.cruise != self._cruise_now:
            self._cruise_now, cruise = s.cruise, bool(s.cruise)
        parameters: dict[str, float] = {}
        if s.adjustments and 1 <= s.parameter <= len(ADJUSTABLE):
            name = ADJUSTABLE[s.parameter - 1]
            value, low, high, step = self._values[name]
            if step > 0:
                value = min(max(value + s.adjustments * step, low), high)
                self._values[name] = (value, low, high, step)
                parameters[name] = value
        s.adjustments = 0
        for name, value in s.set_values.items():  # a parameter client's sets (shc ros2), already in range
            _, low, high, step = self._values[name]
            self._values[name] = (value, low, high, step)
            parameters[name] = value
        s.set_values = {}
        toggle = None
        if s.toggles:
            index = s.toggles.pop(0)
            leg = s.primary_leg if index == 0 else s.secondary_leg
            toggle = self._legs[leg] if 0 <= leg < len(self._legs) else None
        tips = {self._legs[leg]: s.tip_velocity.get(index, (0.0, 0.0, 0.0))
                for index, leg in ((0, s.primary_leg), (1, s.secondary_leg)) if 0 <= leg < len(self._legs)}
        return Command(velocity=s.velocity, state_request=None if s.robot_state is None else RobotState(s.robot_state),
                       pose_velocity=s.pose_velocity, pose_reset=PoseReset(s.pose_reset) if 0 <= s.pose_reset <= 5
                       else PoseReset.NO_RESET, gait=gait, cruise=cruise, parameters=parameters, leg_toggle=toggle,
                       tip_velocity=tips)

    def next(self) -> Command | None:
        """The latched command; waits while the system is SUSPENDED; None once the run is asked to stop."""
        if not self._operational.is_set():
            while not self._operational.wait(0.05):
                if self._stopped():
                    return None
            time.sleep(self._robot.time_delta)  # OpenSHC initialises for a while after OPERATIONAL, spinning
            self.latch()  # so its first cycle acts on what arrived meanwhile (the remote's robot state with it)
        command = self._command
        # one-shot inputs (gait change, cruise switch, parameter change, leg toggle) act once
        self._command = replace(command, gait=None, cruise=None, parameters={}, leg_toggle=None)
        return command

    def wait_operational(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for OPERATIONAL; whether it came."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline and not self._stopped():
            if self._operational.wait(0.05):
                return True
        return self._operational.is_set()

    def close(self) -> None:
        """Nothing to release (the node closes the subscriptions)."""


def _adjustable(robot: Robot, name: str) -> tuple[float, float, float, float]:
    """(current, min, max, step) of an adjustable parameter from the robot file (0 step: not adjustable)."""
    for table in (robot.walker, robot.admittance):
        spec = getattr(table, name, None)
        if spec is not None and hasattr(spec, "default"):
            return float(spec.default), float(spec.min), float(spec.max), float(spec.step)
    return 0.0, 0.0, 0.0, 0.0
