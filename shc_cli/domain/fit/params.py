"""The fittable servo parameters: the numeric fields of the robot file's ``[servo]`` table, their short names,
typical sizes and default bounds.

Which parameters change the motion matters for the cost of a fit: every physics engine here applies the servo's
torque law (gain, torque constant, winding, back-EMF, viscous friction, limits) and its armature, but Coulomb
friction, the holding ratio, idle power, the static speed and the regenerative share enter only the electrical
model after the physics (:meth:`~shc_cli.backends.servo.ServoModel.electrical`), so changing them needs no new
rollout (:data:`ELECTRICAL_ONLY`).
"""

from __future__ import annotations

from dataclasses import dataclass

from shc_cli.errors import Issue, SpecError
from shc_cli.spec.robot import Servo

ALIASES = {"gain": "position_p_gain", "p_gain": "position_p_gain", "i_gain": "position_i_gain",
           "d_gain": "position_d_gain", "coulomb": "coulomb_friction", "viscous": "viscous_friction",
           "holding": "holding_ratio", "idle": "idle_power", "kt": "torque_constant", "resistance":
           "winding_resistance", "regenerative": "regenerative_efficiency"}
"""Short names accepted by ``--params`` → the ``[servo]`` field."""
DEFAULT_PARAMS = ("position_p_gain", "coulomb_friction", "viscous_friction", "holding_ratio", "armature",
                  "idle_power", "torque_constant")
"""What ``shc fit`` fits without ``--params``: the figures no datasheet gives (issue 30)."""
ELECTRICAL_ONLY = frozenset({"idle_power", "coulomb_friction", "holding_ratio", "static_speed",
                             "regenerative_efficiency"})
"""Parameters that change no motion in any engine (only current and power): no rollout to vary them."""
TYPICAL = {"position_p_gain": 850.0, "position_i_gain": 100.0, "position_d_gain": 100.0, "coulomb_friction": 0.5,
           "viscous_friction": 0.1, "holding_ratio": 0.5, "armature": 0.01, "idle_power": 1.0,
           "torque_constant": 1.6, "winding_resistance": 2.3, "static_speed": 0.1, "regenerative_efficiency": 0.5,
           "stall_torque": 8.4, "no_load_speed": 4.7, "supply_voltage": 12.0, "current_limit": 5.0,
           "stiffness": 5.0, "damping": 0.05, "position_gain": 0.1, "velocity_gain": 1.0, "firmware_period": 0.001,
           "pwm_limit": 885.0}
"""A typical size of each parameter (its unit as in :class:`~shc_cli.spec.robot.Servo`): the scale of the solver's
steps and of the bounds of a parameter whose robot value is 0."""
SPAN = 3.0
"""Default bounds: the robot's value ÷ and × this (0 … 1 for ratios; 0 … SPAN × typical for a value of 0)."""


@dataclass(frozen=True)
class Parameter:
    """One fitted parameter.

    Attributes:
        name: the ``[servo]`` field.
        initial: the robot file's value (the fit's start).
        lower, upper: bounds.
        scale: typical size (steps, the identifiability threshold for a value near 0).
    """

    name: str
    initial: float
    lower: float
    upper: float
    scale: float

    @property
    def moves(self) -> bool:
        """Changing it changes the motion (a rollout per value)."""
        return self.name not in ELECTRICAL_ONLY


def fittable() -> list[str]:
    """Every ``[servo]`` field ``shc fit`` can fit (the numeric ones)."""
    return [name for name, info in Servo.model_fields.items()
            if (info.annotation is float or name in TYPICAL) and name != "ticks_per_revolution"]


def parse_params(text: str | None) -> list[str]:
    """``--params`` (comma-separated names or short names) as ``[servo]`` field names; one-line error for an
    unknown one. ``None``: :data:`DEFAULT_PARAMS`."""
    if text is None:
        return list(DEFAULT_PARAMS)
    names: list[str] = []
    known = fittable()
    for raw in (part.strip() for part in text.split(",")):
        if not raw:
            continue
        name = ALIASES.get(raw, raw)
        if name not in known:
            raise SpecError([Issue(None, None, "--params", f"'{raw}' is not a fittable [servo] parameter",
                                   f"use names of the robot file's [servo] table: {', '.join(TYPICAL)} (or "
                                   f"{', '.join(ALIASES)})")])
        if name not in names:
            names.append(name)
    if not names:
        raise SpecError([Issue(None, None, "--params", "no parameter given", "e.g. --params gain,coulomb")])
    return names


def parameters(servo: Servo, names: list[str]) -> list[Parameter]:
    """The fitted parameters of ``servo``: start at its values, bounds from the field's own limits and
    :data:`SPAN`."""
    out = []
    for name in names:
        value = float(getattr(servo, name))
        scale = TYPICAL.get(name, abs(value) or 1.0)
        low, high = _limits(name)
        lower = max(low, value / SPAN) if value > 0 else max(low, 0.0)
        upper = min(high, value * SPAN) if value > 0 else min(high, SPAN * scale)
        if name == "holding_ratio" or name == "regenerative_efficiency":
            lower, upper = 0.0, 1.0
        out.append(Parameter(name, value, lower, upper, scale))
    return out


def _limits(name: str) -> tuple[float, float]:
    """The field's own ``ge``/``gt``/``le`` limits (−inf, inf when none)."""
    low, high = -float("inf"), float("inf")
    for item in Servo.model_fields[name].metadata:
        for attribute in ("ge", "gt"):
            bound = getattr(item, attribute, None)
            if bound is not None:
                low = max(low, float(bound))
        bound = getattr(item, "le", None)
        if bound is not None:
            high = min(high, float(bound))
    return low, high
