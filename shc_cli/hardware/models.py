"""Dynamixel models shc knows: model number and the Protocol 2.0 control-table addresses it uses.

Addresses are those of the e-Manual's "Control Table of RAM/EEPROM Area" for the X series and the MX series with
Protocol 2.0 firmware (identical for the items below). Units: position 4096 ticks per revolution, velocity
0.229 rpm per unit, current in mA per unit (model specific).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ServoModel:
    """One Dynamixel model's numbers (Protocol 2.0)."""

    name: str
    model_number: int
    current_unit_ma: float = 2.69
    ticks_per_revolution: int = 4096
    velocity_unit_rpm: float = 0.229
    # control table
    model_number_address: int = 0
    firmware_address: int = 6
    return_delay_time: int = 9
    operating_mode: int = 11
    current_limit: int = 38
    max_position_limit: int = 48
    min_position_limit: int = 52
    torque_enable: int = 64
    hardware_error_status: int = 70
    profile_velocity: int = 112
    goal_position: int = 116
    present_current: int = 126
    present_velocity: int = 128
    present_position: int = 132


MODELS = {
    "MX-106": ServoModel("MX-106", 321, current_unit_ma=3.36),
    "MX-64": ServoModel("MX-64", 311, current_unit_ma=3.36),
    "XM430-W350": ServoModel("XM430-W350", 1020),
    "XM540-W270": ServoModel("XM540-W270", 1120),
    "XH430-W350": ServoModel("XH430-W350", 1010, current_unit_ma=1.34),
    "generic": ServoModel("generic", 0),
}
"""By name; ``generic`` accepts any model number with the X-series addresses."""

POSITION_MODES = {3: "position", 4: "extended position"}
"""Operating Mode values in which Goal Position drives the servo."""
OPERATING_MODES = {0: "current", 1: "velocity", 3: "position", 4: "extended position", 5: "current-based position",
                   16: "PWM"}

# Hardware Error Status bits (e-Manual).
INPUT_VOLTAGE_ERROR, OVERHEATING_ERROR, MOTOR_ENCODER_ERROR, ELECTRICAL_SHOCK_ERROR, OVERLOAD_ERROR = 1, 4, 8, 16, 32
HARDWARE_ERRORS = {INPUT_VOLTAGE_ERROR: "input voltage", OVERHEATING_ERROR: "overheating",
                   MOTOR_ENCODER_ERROR: "motor encoder", ELECTRICAL_SHOCK_ERROR: "electrical shock",
                   OVERLOAD_ERROR: "overload"}


def hardware_error_names(bits: int) -> list[str]:
    """The Hardware Error Status bits set in ``bits``, by name."""
    return [name for bit, name in HARDWARE_ERRORS.items() if bits & bit]
