"""The recommended excitation for ``shc fit``: a TOML plan script (the ``--commands`` format of ``run-hw``,
``simulate`` and ``plan``, :mod:`shc_cli.spec.timeline`) that moves every joint in ways that tell the servo
parameters apart.

Phases, each separating parameters the others leave entangled:

1. **Stand** (still, loaded on the ground): the holding current — ``holding_ratio`` against ``coulomb_friction``.
2. **Sway**: the body posed along and about each axis (``pose_velocity`` inputs: z, roll, pitch, x, y, yaw), each
   axis out to +, over to − and back at two speeds (slow, then twice as fast) to ``SWAY_SHARE`` of the robot's
   posing limits (at most what the slow sway covers in ``SWAY_OUT_S``). Slow, smooth joint motion in both
   directions: Coulomb against viscous friction, the position gain from the steady position errors under load.
3. **Walk** at several step frequencies (:data:`FREQUENCY_SHARES` of the robot's default, within its adjustable
   range), each forward, back, turning left and right (so a robot on the ground ends about where it started) and
   a stop: swing accelerations for the ``armature``, speed for the back-EMF and ``viscous_friction``, the change
   between stance and swing for the torque constant.
4. **Stand** again (the same holding state after the motion: drift).

The same script is meant to be recorded twice: with the robot on a stand (legs in the air: the servos' own
dynamics without the ground's forces) and on the ground. ``docs/hardware.md`` says how to record it safely.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from shc_cli.spec.robot import Robot

SWAY_SHARE = 0.7
"""Sway amplitude as a share of the robot's posing limits (``[pose] max_translation``, ``max_rotation``)..."""
SWAY_OUT_S = 1.0
"""... or what the slow sway covers in this many seconds [s], whichever is smaller."""
SWAY_INPUTS = (0.5, 1.0)
"""Posing inputs of the two sway speeds (−1..1 of ``max_translation_velocity`` / ``max_rotation_velocity``)."""
FREQUENCY_SHARES = (0.5, 1.0, 1.5)
"""Walking step frequencies as shares of the robot's default (clipped to its adjustable range)."""
WALK_S = 3.0
"""Seconds of walking forward, then back, at each step frequency (turning: half of it each way)."""
STAND_S = 4.0
"""Seconds of standing still at the start and the end."""
STOP_S = 2.0
"""Seconds stopped between two step frequencies (the new frequency is set at the stop)."""
THROTTLE = (0.5, 0.5)
"""Walking inputs (linear, angular) in ``throttle`` input mode: half the robot's maximum speed."""
REAL = (0.05, 0.2)
"""Walking inputs in ``real`` input mode: 0.05 m/s, 0.2 rad/s."""
AXES = (("z", 2), ("roll", 3), ("pitch", 4), ("x", 0), ("y", 1), ("yaw", 5))
"""The sway's axes in order and their index in ``pose_velocity``."""


def _number(value: float) -> str:
    return f"{round(value, 4):g}"


def _vector(values: list[float] | tuple[float, ...]) -> str:
    return "[" + ", ".join(_number(v) for v in values) + "]"


def excitation_plan(robot: Robot) -> str:
    """The plan script for ``robot`` (TOML text with a comment per phase; module docstring)."""
    pose, walker, dt = robot.pose, robot.walker, robot.time_delta
    steps: list[str] = []
    t = 0.0

    def step(comment: str | None, **fields: str) -> None:
        lines = [f"# {comment}"] if comment else []
        lines += ["[[step]]", f"at = {_number(t)}", *(f"{key} = {value}" for key, value in fields.items())]
        steps.append("\n".join(lines))

    step(f"1. stand still {_number(STAND_S)} s", velocity="[0, 0, 0]")
    t += STAND_S
    limits = {"x": (pose.max_translation.x, pose.max_translation_velocity),
              "y": (pose.max_translation.y, pose.max_translation_velocity),
              "z": (pose.max_translation.z, pose.max_translation_velocity),
              "roll": (pose.max_rotation.roll, pose.max_rotation_velocity),
              "pitch": (pose.max_rotation.pitch, pose.max_rotation_velocity),
              "yaw": (pose.max_rotation.yaw, pose.max_rotation_velocity)}
    for name, index in AXES:
        limit, speed = limits[name]
        amplitude = min(SWAY_SHARE * limit, min(SWAY_INPUTS) * speed * SWAY_OUT_S)
        comment: str | None = (f"2. sway {name}: out to ±{_number(amplitude)} and back at inputs "
                               + " and ".join(_number(command) for command in SWAY_INPUTS))
        for command in SWAY_INPUTS:
            out = max(1, round(amplitude / (command * speed) / dt)) * dt  # [s] out to the amplitude, whole cycles
            for sign, hold in ((1.0, out), (-1.0, 2.0 * out), (1.0, out)):
                vector = [0.0] * 6
                vector[index] = sign * command
                step(comment, pose_velocity=_vector(vector))
                comment = None
                t += hold
    step("back to the neutral pose", pose_velocity=_vector([0.0] * 6), pose_reset='"all"')
    t += STOP_S
    step(None, pose_reset='"no_reset"')
    linear, angular = REAL if walker.velocity_input_mode == "real" else THROTTLE
    adjustable = walker.step_frequency
    frequencies = sorted({min(max(share * adjustable.default, adjustable.min), adjustable.max)
                          for share in FREQUENCY_SHARES})
    for frequency in frequencies:
        step(f"3. walk at {_number(frequency)} Hz: forward, back, turn left, turn right, stop",
             velocity="[0, 0, 0]", parameters=f"{{ step_frequency = {_number(frequency)} }}")
        t += STOP_S
        for velocity, hold in (((linear, 0.0, 0.0), WALK_S), ((-linear, 0.0, 0.0), WALK_S),
                               ((0.0, 0.0, angular), WALK_S / 2.0), ((0.0, 0.0, -angular), WALK_S / 2.0)):
            step(None, velocity=_vector(velocity))
            t += hold
    step(f"4. stop and stand still {_number(STAND_S)} s", velocity="[0, 0, 0]",
         parameters=f"{{ step_frequency = {_number(adjustable.default)} }}")
    t += STAND_S
    step("(the run ends 1 s after the last step)", velocity="[0, 0, 0]")
    header = (f"# shc fit excitation for {robot.name}: about {round(t)} s after start-up (shc fit --plan).\n"
              "# Record it twice with run-hw --commands: on a stand (legs in the air), then on the ground.\n")
    return header + "\n\n".join(steps) + "\n"


def write_plan(robot: str, out: Path | None = None) -> Path:
    """Write :func:`excitation_plan` of ``robot`` (file or bundled name) to ``out`` (default ``fit-plan.toml``);
    written whole or not at all. Returns the path."""
    from shc_cli.outputs import write_text
    from shc_cli.spec.loading import load_robot

    path = out or Path("fit-plan.toml")
    write_text(path, excitation_plan(load_robot(robot).robot))
    return path
