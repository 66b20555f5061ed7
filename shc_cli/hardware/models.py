"""The servo models shc knows: their protocol, units, control-table addresses and datasheet figures.

A robot file names a model (``[hardware] model = "AX-12A"``, or per joint in ``[hardware.servos]``); the protocol,
the units and the control table follow from it. Three families:

* ``protocol2`` — Dynamixel Protocol 2.0 (X series, MX series with 2.0 firmware): the addresses below are the
  e-Manual's "Control Table of RAM/EEPROM Area" for those (identical for the items used). Position 4096 ticks per
  revolution, velocity 0.229 rpm per unit, current in mA per unit (model specific).
* ``protocol1`` — Dynamixel Protocol 1.0 (AX series; MX series with 1.0 firmware): e-Manual control tables of the
  AX-12A/AX-18A and MX-64/MX-106 (1.0) pages, see :data:`PROTOCOL1_TABLE`. AX: 1024 ticks over 300°; MX: 4096
  per revolution. Speed and load are sign-magnitude (bit 10 = clockwise) in 0.111 rpm (AX) / 0.114 rpm (MX) and
  0.1 % of the maximum torque. No sync read; the MX series has BULK READ.
* ``feetech`` — Feetech STS/SCS (the SMS/STS memory table, see :data:`FEETECH_TABLE`): 4096 steps per revolution,
  speed in steps/s with bit 15 as its sign, load 0.1 % with bit 10 as its sign, current 6.5 mA per unit. SYNC READ
  and SYNC WRITE.

Datasheet figures (:class:`Datasheet`) are per model with their source; ``shc simulate`` takes them for a robot
whose ``[servo] model`` names the model (see :mod:`shc_cli.spec.servo_models`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from shc_cli.spec.servo_models import DATASHEETS, Datasheet

Family = Literal["protocol2", "protocol1", "feetech"]
FAMILY_NAMES = {"protocol2": "Dynamixel Protocol 2.0", "protocol1": "Dynamixel Protocol 1.0",
                "feetech": "Feetech STS/SCS"}


@dataclass(frozen=True)
class ServoModel:
    """One servo model's numbers. The address fields are the Protocol 2.0 control table's; the other families'
    tables are :data:`PROTOCOL1_TABLE` and :data:`FEETECH_TABLE`."""

    name: str
    model_number: int
    current_unit_ma: float = 2.69
    resolution: int = 4096
    """Position ticks over ``range_degrees``."""
    range_degrees: float = 360.0
    """Angle the ``resolution`` ticks span [°] (300 for the AX series)."""
    velocity_unit_rpm: float = 0.229
    family: Family = "protocol2"
    bulk_read: bool = False
    """Protocol 1.0: the model answers BULK READ (MX series; the AX series does not)."""
    load_unit: float = 0.001
    """Present Load unit as a share of the maximum torque (Protocol 1.0 and Feetech)."""
    datasheet: Datasheet | None = field(default=None, compare=False)
    # Protocol 2.0 control table
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

    @property
    def ticks_per_revolution(self) -> float:
        """Position ticks per turn (1228.8 for the AX series' 1024 ticks per 300°)."""
        return self.resolution * 360.0 / self.range_degrees

    @property
    def ticks_per_radian(self) -> float:
        return self.ticks_per_revolution / (2.0 * math.pi)

    @property
    def centre(self) -> int:
        """The tick in the middle of the range (2048; 512 for the AX series): the default zero."""
        return self.resolution // 2


@dataclass(frozen=True)
class ControlTable:
    """The addresses (and sizes) a bus uses in a Protocol 1.0 or Feetech control table."""

    model_number: int
    firmware: int
    servo_id: int
    baud_rate: int
    return_delay_time: int
    status_return_level: int
    min_position_limit: int
    max_position_limit: int
    torque_enable: int
    goal_position: int
    goal_speed: int
    torque_limit: int
    present_position: int
    state_length: int
    """Present position, speed and load: 2 bytes each from ``present_position``."""
    mode: int | None = None
    """Feetech Operating Mode (0 = position); Protocol 1.0 has none (both angle limits 0 = wheel mode)."""
    status: int | None = None
    """Feetech servo status (the error bits of the status packet), if the table has it."""
    max_torque: int = 14
    """Max Torque (EEPROM; Protocol 1.0 14, Feetech 16)."""


PROTOCOL1_TABLE = ControlTable(model_number=0, firmware=2, servo_id=3, baud_rate=4, return_delay_time=5,
                               status_return_level=16, min_position_limit=6, max_position_limit=8,
                               torque_enable=24, goal_position=30, goal_speed=32, torque_limit=34,
                               present_position=36, state_length=6, max_torque=14)
"""e-Manual AX-12A / MX-64(1.0) control table: CW Angle Limit 6 (the low end), CCW Angle Limit 8, Present Position
36, Present Speed 38, Present Load 40."""
FEETECH_TABLE = ControlTable(model_number=3, firmware=0, servo_id=5, baud_rate=6, return_delay_time=7,
                             status_return_level=8, min_position_limit=9, max_position_limit=11,
                             torque_enable=40, goal_position=42, goal_speed=46, torque_limit=48,
                             present_position=56, state_length=6, mode=33, status=65, max_torque=16)
"""Feetech SMS/STS memory table: model number 3–4, ID 5, Min/Max Angle Limit 9/11, Operating Mode 33, Torque
Enable 40, Goal Position 42, Goal Speed 46, Present Position 56, Present Speed 58, Present Load 60, servo status
65."""

TABLES: dict[Family, ControlTable] = {"protocol1": PROTOCOL1_TABLE, "feetech": FEETECH_TABLE}


def _p1(name: str, number: int, ax: bool) -> ServoModel:
    if ax:
        return ServoModel(name, number, resolution=1024, range_degrees=300.0, velocity_unit_rpm=0.111,
                          family="protocol1", bulk_read=False, datasheet=DATASHEETS.get(name))
    return ServoModel(name, number, current_unit_ma=4.5, velocity_unit_rpm=0.114, family="protocol1",
                      bulk_read=True, datasheet=DATASHEETS.get(name.removesuffix("(1.0)")))


def _p2(name: str, number: int, current_unit_ma: float = 2.69) -> ServoModel:
    return ServoModel(name, number, current_unit_ma=current_unit_ma, datasheet=DATASHEETS.get(name))


MODELS = {
    "MX-106": _p2("MX-106", 321, 3.36),
    "MX-64": _p2("MX-64", 311, 3.36),
    "XM430-W350": _p2("XM430-W350", 1020),
    "XM540-W270": _p2("XM540-W270", 1120),
    "XH430-W350": _p2("XH430-W350", 1010, 1.34),
    "XL430-W250": _p2("XL430-W250", 1060),
    "generic": ServoModel("generic", 0),
    # Protocol 1.0 (model numbers: e-Manual control tables)
    "AX-12A": _p1("AX-12A", 12, ax=True),
    "AX-18A": _p1("AX-18A", 18, ax=True),
    "MX-28(1.0)": _p1("MX-28(1.0)", 29, ax=False),
    "MX-64(1.0)": _p1("MX-64(1.0)", 310, ax=False),
    "MX-106(1.0)": _p1("MX-106(1.0)", 320, ax=False),
    # Feetech (model number: the word at address 3, low byte first)
    "STS3215": ServoModel("STS3215", 777, current_unit_ma=6.5, velocity_unit_rpm=60.0 / 4096, family="feetech",
                          datasheet=DATASHEETS.get("STS3215")),
    "STS3250": ServoModel("STS3250", 2825, current_unit_ma=6.5, velocity_unit_rpm=60.0 / 4096, family="feetech"),
}
"""By name; ``generic`` accepts any model number with the X-series addresses."""

POSITION_MODES = {3: "position", 4: "extended position"}
"""Operating Mode values in which Goal Position drives the servo."""
OPERATING_MODES = {0: "current", 1: "velocity", 3: "position", 4: "extended position", 5: "current-based position",
                   16: "PWM"}

# Hardware Error Status bits (e-Manual, Protocol 2.0).
INPUT_VOLTAGE_ERROR, OVERHEATING_ERROR, MOTOR_ENCODER_ERROR, ELECTRICAL_SHOCK_ERROR, OVERLOAD_ERROR = 1, 4, 8, 16, 32
HARDWARE_ERRORS = {INPUT_VOLTAGE_ERROR: "input voltage", OVERHEATING_ERROR: "overheating",
                   MOTOR_ENCODER_ERROR: "motor encoder", ELECTRICAL_SHOCK_ERROR: "electrical shock",
                   OVERLOAD_ERROR: "overload"}

PROTOCOL1_ERRORS = {1: "input voltage", 2: "angle limit", 4: "overheating", 8: "range", 16: "checksum",
                    32: "overload", 64: "instruction"}
"""Protocol 1.0 status error bits (e-Manual)."""
PROTOCOL1_HARDWARE = 1 | 4 | 32
"""The bits that are the servo's own protection (voltage, overheating, overload), not a refused instruction."""
FEETECH_ERRORS = {1: "input voltage", 2: "angle sensor", 4: "overheating", 8: "overcurrent", 32: "overload"}
"""Feetech status error bits (the servo status at address 65)."""


def hardware_error_names(bits: int, family: Family = "protocol2") -> list[str]:
    """The error bits set in ``bits``, by name (Hardware Error Status for Protocol 2.0; the status packet's error
    byte for Protocol 1.0 and Feetech)."""
    names = {"protocol2": HARDWARE_ERRORS, "protocol1": PROTOCOL1_ERRORS, "feetech": FEETECH_ERRORS}[family]
    return [name for bit, name in names.items() if bits & bit]
