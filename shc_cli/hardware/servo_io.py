"""One servo at a time on an open bus (``shc hw jog`` and ``check``): its present position, a goal, its torque and
a torque limit, in every family (Dynamixel Protocol 2.0 and 1.0, Feetech), each transaction's status checked.

A servo that does not answer, answers corruptly or reports its protection (overload, overheating, input voltage;
Protocol 2.0: the status's alert bit) raises :class:`ServoFault` naming it; the caller turns the torque off.
Torque limits: Protocol 1.0 and Feetech write Torque Limit (RAM: 0–1023 / 0–1000 of the maximum torque); Protocol
2.0 writes Goal PWM (address 100, RAM), which limits the motor's voltage in position control (885 = 100 %).
"""

from __future__ import annotations

from shc_cli.hardware import protocol2 as p2
from shc_cli.hardware.bus import HardwareError, ServoBus
from shc_cli.hardware.bus_protocol1 import Protocol1Bus
from shc_cli.hardware.models import hardware_error_names

GOAL_PWM, PWM_FULL = 100, 885
"""Protocol 2.0 Goal PWM address and its 100 % value (X series)."""


class ServoFault(HardwareError):
    """A servo failed while moved one at a time (exit 3: the torque is released)."""


class OneServo:
    """The servo of the bus's slot ``index``."""

    def __init__(self, bus: ServoBus, index: int) -> None:
        self.bus, self.index = bus, index
        self.slot = bus.slots[index]
        self.name = f"{self.slot.key} (servo {self.slot.servo_id})"

    # -- Protocol 1.0 and Feetech ---------------------------------------------------------------------------

    def _p1_read(self, address: int, length: int) -> bytes:
        assert isinstance(self.bus, Protocol1Bus)
        data, error, failure = self.bus._read(self.index, address, length)
        if data is None:
            raise ServoFault(f"{self.name}: {failure}")
        self._p1_alert(error)
        return data

    def _p1_alert(self, error: int) -> None:
        assert isinstance(self.bus, Protocol1Bus)
        if error & self.bus.alert_bits:
            names = hardware_error_names(error & self.bus.alert_bits, self.bus.family)
            raise ServoFault(f"{self.name}: {', '.join(names)}")

    # -- Protocol 2.0 ---------------------------------------------------------------------------------------

    def _p2_read(self, address: int, length: int) -> bytes:
        from dynamixel_sdk import COMM_SUCCESS

        bus = self.bus
        data, result, error = bus._handler.readTxRx(bus._port_of(self.index), self.slot.servo_id, address, length)
        if result != COMM_SUCCESS:
            raise ServoFault(f"{self.name}: {bus._handler.getTxRxResult(result)}")
        if error & p2.ERROR_ALERT:
            errors = bus.hardware_errors().get(self.slot.key, ["hardware error"])
            raise ServoFault(f"{self.name}: {', '.join(errors)}")
        if error & 0x7F or len(data) != length:
            raise ServoFault(f"{self.name}: {p2.error_name(error) if error & 0x7F else 'short reply'}")
        return bytes(data)

    # -- both -------------------------------------------------------------------------------------------------

    def _write(self, address: int, data: bytes, what: str) -> None:
        try:
            self.bus._write(self.index, address, data, what)
        except ServoFault:
            raise
        except HardwareError as error:
            raise ServoFault(str(error)) from None

    def ticks(self) -> int:
        """Present Position [ticks]."""
        if isinstance(self.bus, Protocol1Bus):
            return int.from_bytes(self._p1_read(self.bus.table.present_position, 2), "little")
        return int.from_bytes(self._p2_read(self.slot.model.present_position, 4), "little", signed=True)

    def goal(self, ticks: int) -> None:
        """Write Goal Position [ticks]."""
        if isinstance(self.bus, Protocol1Bus):
            self._write(self.bus.table.goal_position, int(ticks).to_bytes(2, "little"), "Goal Position")
        else:
            self._write(self.slot.model.goal_position, int(ticks).to_bytes(4, "little", signed=True), "Goal Position")

    def torque(self, on: bool) -> None:
        address = self.bus.table.torque_enable if isinstance(self.bus, Protocol1Bus) else self.slot.model.torque_enable
        self._write(address, bytes([int(on)]), "Torque Enable")

    def limit_torque(self, share: float) -> tuple[int, bytes]:
        """Limit the torque to ``share`` (0–1) of the servo's maximum; returns (address, old value) to restore."""
        if isinstance(self.bus, Protocol1Bus):
            address = self.bus.table.torque_limit
            full = 1000 if self.bus.family == "feetech" else 1023
        else:
            address, full = GOAL_PWM, PWM_FULL
        old = self._p1_read(address, 2) if isinstance(self.bus, Protocol1Bus) else self._p2_read(address, 2)
        self._write(address, max(1, round(share * full)).to_bytes(2, "little"), "the torque limit")
        return address, old

    def restore(self, saved: tuple[int, bytes]) -> None:
        self._write(saved[0], saved[1], "the torque limit")
