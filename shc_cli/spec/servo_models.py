"""Datasheet figures of the servos people build legged robots with, by model name, each with its source.

``[servo] model = "AX-12A"`` in a robot file fills the ``[servo]`` fields the file leaves unset from these figures
(:func:`servo_defaults`), so ``shc simulate`` predicts what that servo does: the torque–speed line through the
stall torque and the no-load speed at the rated voltage, the torque constant (stall torque ÷ stall current), the
winding resistance (voltage ÷ stall current), the current limit (the stall current) and the firmware's position
gain expressed in the simulator's Protocol 2.0 units (``position_p_gain``: K_P = value/128 of 885 PWM units per
4096-tick tick; see :mod:`shc_cli.backends.servo`).

Position gains differ per family, and each entry says how its own gain converts:

* Dynamixel Protocol 2.0 (X, MX(2.0)): Position P Gain, K_P = value / 128 (e-Manual) — the simulator's unit.
* MX with Protocol 1.0 firmware: P Gain, K_P = value / 8 (e-Manual MX-64/MX-106 (1.0)) of a 1023 full scale
  (the full scale is **estimated**: the e-Manual gives the divisor, not the output unit).
* AX series: no PID; the compliance slope (default 32) is the position error at which the output reaches full
  torque [ticks of 0.29°]: K = 1/slope of full scale per tick.
* Feetech STS: P coefficient (address 21, default 32); Feetech does not give its unit: **estimated** as K = value/8
  of a 1000 full scale per tick (the MX(1.0) form), so treat simulated stiffness as a guess until measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

PWM_FULL_SCALE = 885.0
P_GAIN_DIVISOR = 128.0
SIMULATOR_TICKS = 4096


@dataclass(frozen=True)
class Datasheet:
    """One servo's rated figures.

    Attributes:
        name: model name.
        voltage: rated supply voltage of the figures [V].
        stall_torque: [N·m] at ``voltage``.
        stall_current: [A] at ``voltage``.
        no_load_speed_rpm: [rpm] at ``voltage``.
        gear_ratio: motor turns per output turn.
        resolution: position ticks over ``range_degrees``.
        range_degrees: [°].
        p_gain: the factory position gain in the model's own control-table unit.
        p_gain_unit: what that unit is (text, for docs and ``validate --show``).
        stiffness_per_tick: the share of full output per tick of error per unit of ``p_gain`` (K = p_gain ×
            this).
        source: where the figures come from.
        estimated: the figures (or the gain unit) marked as estimates.
    """

    name: str
    voltage: float
    stall_torque: float
    stall_current: float
    no_load_speed_rpm: float
    gear_ratio: float
    resolution: int
    range_degrees: float
    p_gain: float
    p_gain_unit: str
    stiffness_per_tick: float
    source: str
    estimated: str = ""

    @property
    def no_load_speed(self) -> float:
        """[rad/s]."""
        return self.no_load_speed_rpm * 2.0 * math.pi / 60.0

    def simulator_p_gain(self) -> float:
        """The factory gain as a Protocol 2.0 Position P Gain over 4096 ticks per turn (the simulator's unit): the
        same volts per radian of error."""
        ticks_per_turn = self.resolution * 360.0 / self.range_degrees
        share_per_rad = self.p_gain * self.stiffness_per_tick * ticks_per_turn
        return share_per_rad * P_GAIN_DIVISOR * PWM_FULL_SCALE / SIMULATOR_TICKS


EMANUAL = "ROBOTIS e-Manual, {} page (Specifications and Control Table), emanual.robotis.com"
_P2_UNIT = "Position P Gain: K_P = value/128 (of 885 PWM units per tick)"
_P2_K = 1.0 / (P_GAIN_DIVISOR * PWM_FULL_SCALE)
_AX_UNIT = "compliance slope: full torque at this many ticks of error (no PID)"

DATASHEETS: dict[str, Datasheet] = {d.name: d for d in (
    Datasheet("AX-12A", 12.0, 1.5, 1.5, 59.0, 254.0, 1024, 300.0, 32.0, _AX_UNIT, 1.0 / 32.0 / 32.0,
              EMANUAL.format("AX-12A")),
    Datasheet("AX-18A", 12.0, 1.8, 2.2, 97.0, 254.0, 1024, 300.0, 32.0, _AX_UNIT, 1.0 / 32.0 / 32.0,
              EMANUAL.format("AX-18A")),
    Datasheet("XL430-W250", 12.0, 1.5, 1.4, 61.0, 258.5, 4096, 360.0, 640.0, _P2_UNIT, _P2_K,
              EMANUAL.format("XL430-W250")),
    Datasheet("XM430-W350", 12.0, 4.1, 2.3, 46.0, 353.5, 4096, 360.0, 800.0, _P2_UNIT, _P2_K,
              EMANUAL.format("XM430-W350")),
    Datasheet("MX-64", 12.0, 6.0, 4.1, 63.0, 200.0, 4096, 360.0, 850.0, _P2_UNIT, _P2_K,
              EMANUAL.format("MX-64(2.0)")),
    Datasheet("MX-106", 12.0, 8.4, 5.2, 45.0, 225.0, 4096, 360.0, 850.0, _P2_UNIT, _P2_K,
              EMANUAL.format("MX-106(2.0)")),
    Datasheet("MX-64(1.0)", 12.0, 6.0, 4.1, 63.0, 200.0, 4096, 360.0, 32.0,
              "P Gain: K_P = value/8 (of 1023 per tick)", 1.0 / 8.0 / 1023.0, EMANUAL.format("MX-64(1.0)"),
              "the P gain's output full scale (1023)"),
    Datasheet("MX-106(1.0)", 12.0, 8.4, 5.2, 45.0, 225.0, 4096, 360.0, 32.0,
              "P Gain: K_P = value/8 (of 1023 per tick)", 1.0 / 8.0 / 1023.0, EMANUAL.format("MX-106(1.0)"),
              "the P gain's output full scale (1023)"),
    Datasheet("STS3215", 7.4, 1.91, 2.7, 52.0, 345.0, 4096, 360.0, 32.0,
              "P coefficient (address 21): unit not given by Feetech", 1.0 / 8.0 / 1000.0,
              "Feetech STS3215 (C001, 7.4 V) specification: 19.5 kg·cm stall torque, 0.192 s/60° (52 rpm) "
              "no-load, 1:345 gears, 4096 steps per 360° (as listed by DFRobot SER0069)",
              "the stall current (2.7 A) and the P coefficient's unit"),
)}
"""By model name."""
DATASHEETS["AX-12"] = DATASHEETS["AX-12A"]


def servo_defaults(name: str) -> dict[str, float | int | str]:
    """The ``[servo]`` fields a datasheet fills (empty for an unknown name)."""
    sheet = DATASHEETS.get(name)
    if sheet is None:
        return {}
    return {"stall_torque": sheet.stall_torque, "no_load_speed": round(sheet.no_load_speed, 4),
            "torque_constant": round(sheet.stall_torque / sheet.stall_current, 4),
            "winding_resistance": round(sheet.voltage / sheet.stall_current, 4),
            "supply_voltage": sheet.voltage, "current_limit": sheet.stall_current,
            "position_p_gain": round(sheet.simulator_p_gain(), 1), "ticks_per_revolution": SIMULATOR_TICKS}
