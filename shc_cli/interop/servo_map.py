"""The servo map an import writes: ``[hardware]`` with one ``[hardware.servos]`` entry per joint.

The one place where a joint meets its servo (bus, id, model, zero, direction) is the robot file's
``[hardware.servos]`` table (``run-hw`` reads it). An import cannot know the ids: it numbers them leg by leg in
the robot file's leg order, ``10 × leg + joint`` (AR's joints 11, 12, 13; BR's 21, …) as robots/bullet.toml does
(sequentially from 1 when a robot has more than 9 legs or 9 joints a leg), every servo on bus 0, direction +1,
zero at the middle of the servo's range, and says so in the comment above the table: they are to check, joint by
joint, on the robot.
"""

from __future__ import annotations

from typing import Any

CHECK_NOTE = [
    "# [hardware.servos] below is TO CHECK on the robot: written by the import, not read from it. Ids are numbered",
    "# 10 x leg + joint in leg order (AR 11, 12, …), every servo on bus 0, direction +1, zero at the middle of the",
    "# servo's range, and hardware.model is a guess from the joints' efforts. Set each servo's id, direction and",
    "# zero_ticks before shc run-hw: shc hw scan finds the ids, shc hw jog writes direction and zero",
    "# (docs/your-robot.md).",
]
"""Comment lines written above the table."""

MODELS_BY_TORQUE = [(2.0, "AX-12A"), (4.5, "XM430-W350"), (7.0, "MX-64"), (float("inf"), "MX-106")]
"""Servo model guessed from the joints' stall torque [N·m]: the first whose bound is at least it and that
``shc run-hw`` knows."""


def guess_model(stall_torque: float | None) -> str:
    """A servo model ``run-hw`` knows for joints of this stall torque [N·m] (MX-106 without one)."""
    from shc_cli.hardware.models import MODELS

    if stall_torque is None:
        return "MX-106"
    for bound, name in MODELS_BY_TORQUE:
        if stall_torque <= bound and name in MODELS:
            return name
    return "MX-106"


def servo_angle_range(model_name: str) -> tuple[float, float]:
    """The joint angles [rad] a servo of ``model_name`` reaches with the zero at the middle of its range and direction
    +1, as the import's servo map writes it: ticks 0 … resolution − 1 (``validation.servo_range_problem``'s rule,
    rounded inward to 0.1 mrad)."""
    import math

    from shc_cli.hardware.models import MODELS

    model = MODELS[model_name]
    return (math.ceil(-model.centre / model.ticks_per_radian * 1e4) / 1e4,
            math.floor((model.resolution - 1 - model.centre) / model.ticks_per_radian * 1e4) / 1e4)


def servo_table(legs: dict[str, list[str]], stall_torque: float | None = None,
                names: dict[str, str] | None = None) -> dict[str, Any]:
    """The ``[hardware]`` table for ``legs`` (``{leg id: [joint, …]}`` in file order).

    Args:
        legs: joint names of each leg, in the robot file's order.
        stall_torque: the joints' stall torque [N·m], for the model guess.
        names: the joints' names on the robot (``{"AR_coxa": "j_c1_rf"}``, e.g. the URDF's), written as
            ``joint`` so that recordings with those names replay.
    """
    sequential = len(legs) > 9 or any(len(joints) > 9 for joints in legs.values())
    servos: dict[str, Any] = {}
    for i, (leg, joints) in enumerate(legs.items()):
        for k, joint in enumerate(joints):
            key = f"{leg}_{joint}"
            servos[key] = {"id": len(servos) + 1 if sequential else 10 * (i + 1) + k + 1, "bus": 0, "direction": 1}
            if names and key in names:
                servos[key]["joint"] = names[key]
    return {"model": guess_model(stall_torque), "servos": servos}


def with_check_note(text: str) -> str:
    """TOML ``text`` with :data:`CHECK_NOTE` above its ``[hardware]`` table."""
    return text.replace("\n[hardware]\n", "\n" + "\n".join(CHECK_NOTE) + "\n[hardware]\n", 1)
