"""Finding the servos on serial ports (``shc hw scan``): for each port, baud rate and protocol, which ids answer,
their model and firmware.

* Dynamixel Protocol 2.0: one broadcast PING per port and baud (dynamixel-sdk's ``broadcastPing``): every servo
  answers it in id order, so an empty bus costs one wait (≈ 0.8 s), not one timeout per id.
* Protocol 1.0 framing (Dynamixel AX/MX 1.0 and Feetech STS/SCS share it): neither has a broadcast ping (a
  Protocol 1.0 PING to the broadcast id gets no status packet), so each id is pinged with a short timeout
  (``timeout_s``, default from the adapter's latency timer: 2 × latency + 6 ms; a pty: 6 ms, an adapter with
  latency 1 ms: 8 ms, so 253 ids take ≈ 2 s). A servo that answers is read at address 0 (6 bytes): a Dynamixel
  has its id at address 3 (model number at 0), a Feetech at address 5 (model number at 3, firmware at 0–1). The
  ids between the first and last found that did not answer are pinged once more (a reply lost on a busy host).
"""

from __future__ import annotations

import glob
import logging
import os
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

from shc_cli.hardware.bus import HardwareError, open_port
from shc_cli.hardware.models import MODELS

log = logging.getLogger(__name__)

Protocol = Literal["2.0", "1.0", "feetech"]
PROTOCOLS: tuple[Protocol, ...] = ("2.0", "1.0", "feetech")
DEFAULT_BAUDS = (1_000_000, 57_600)
"""Factory baud rates: AX series and Feetech STS 1 Mbps, X series and MX(1.0) 57 600 bit/s."""
PORT_PATTERNS = ("/dev/ttyUSB*", "/dev/ttyACM*", "/dev/serial/by-id/*")


@dataclass(frozen=True)
class Found:
    """One servo that answered: where, how, and what it is."""

    port: str
    baud: int
    protocol: Protocol
    servo_id: int
    model_number: int
    firmware: str

    @property
    def model(self) -> str:
        """The model's name in shc (:data:`~shc_cli.hardware.models.MODELS`), or ``model number N``."""
        family = {"2.0": "protocol2", "1.0": "protocol1", "feetech": "feetech"}[self.protocol]
        names = [m.name for m in MODELS.values() if m.model_number == self.model_number and m.family == family]
        return names[0] if names else f"model number {self.model_number}"


def serial_ports() -> list[str]:
    """The serial adapters this computer has (USB serial and CDC ACM devices), without duplicates by-id."""
    seen: dict[str, str] = {}
    for pattern in PORT_PATTERNS:
        for path in sorted(glob.glob(pattern)):
            seen.setdefault(os.path.realpath(path), path)
    return sorted(seen.values())


def default_timeout(port: str) -> float:
    """A reply timeout for ``port`` [s]: 2 × its USB latency timer (sysfs, FTDI adapters; 0 if it has none) + 6 ms."""
    name = Path(os.path.realpath(port)).name
    latency_ms = 0.0
    timer = Path(f"/sys/bus/usb-serial/devices/{name}/latency_timer")
    if timer.is_file():
        try:
            latency_ms = float(timer.read_text().strip())
        except (OSError, ValueError):
            latency_ms = 16.0
    return (2.0 * latency_ms + 6.0) / 1000.0


def _port(sdk: Any, name: str, timeout_s: float) -> Any:
    """An SDK port handler whose packet timeout is ``timeout_s`` plus the packet's bytes (not 2 × 16 ms + 2 ms)."""

    class Port(sdk.PortHandler):  # type: ignore[misc]
        def setPacketTimeout(self, packet_length: int) -> None:
            self.packet_start_time = self.getCurrentTime()
            self.packet_timeout = self.tx_time_per_byte * packet_length + timeout_s * 1000.0

    return Port(name)


def scan(ports: list[str], bauds: Iterable[int] = DEFAULT_BAUDS, protocols: Iterable[Protocol] = PROTOCOLS,
         ids: range = range(0, 253), timeout_s: float | None = None,
         on_step: Callable[[str], None] | None = None) -> list[Found]:
    """Every servo that answers on ``ports`` at ``bauds`` in ``protocols`` with an id in ``ids``.

    Args:
        ports: serial devices.
        bauds: baud rates to try [bit/s].
        protocols: ``2.0``, ``1.0`` (Dynamixel) and/or ``feetech``.
        ids: servo ids to look for (0–252).
        timeout_s: reply timeout of a unicast ping [s] (default :func:`default_timeout`).
        on_step: called with a description before each port/baud/protocol sweep (also logged at INFO: ``shc -v``).

    Raises:
        HardwareError: a port cannot be opened (one line naming it).
    """
    wanted = set(protocols)
    found: list[Found] = []
    for name in ports:
        wait = default_timeout(name) if timeout_s is None else timeout_s
        for baud in bauds:
            if "2.0" in wanted:
                _step(on_step, f"{name} at {baud} baud: Dynamixel Protocol 2.0 broadcast ping")
                found += _scan_protocol2(name, baud, ids)
            if wanted & {"1.0", "feetech"}:
                _step(on_step, f"{name} at {baud} baud: Protocol 1.0 pings of ids {ids.start}-{ids.stop - 1} "
                      f"({wait * 1e3:.0f} ms timeout)")
                found += [f for f in _scan_protocol1(name, baud, ids, wait) if f.protocol in wanted]
    return found


def _step(on_step: Callable[[str], None] | None, text: str) -> None:
    log.info("scanning %s", text)
    if on_step:
        on_step(text)


def _scan_protocol2(name: str, baud: int, ids: range) -> list[Found]:
    """One broadcast PING; its wait (dynamixel-sdk: 3 ms per id up to 252, + 16 ms) cut to the ids asked for."""
    import dynamixel_sdk as sdk

    last = max(ids, default=0)

    class Port(sdk.PortHandler):  # type: ignore[misc]
        def setPacketTimeoutMillis(self, msec: float) -> None:
            super().setPacketTimeoutMillis(min(msec, 14 * (last + 1) * self.tx_time_per_byte + 3.0 * (last + 1)
                                               + 16.0))

    port = open_port(Port(name), name, baud, lambda: None)
    port.ser.timeout = 0.001  # wait for bytes instead of spinning through the broadcast's wait
    try:
        answered, _ = sdk.PacketHandler(2.0).broadcastPing(port)
        return [Found(name, baud, "2.0", servo_id, int(model), str(firmware))
                for servo_id, (model, firmware) in sorted((answered or {}).items()) if servo_id in ids]
    finally:
        port.closePort()


def _scan_protocol1(name: str, baud: int, ids: range, timeout_s: float) -> list[Found]:
    """Unicast pings (the Protocol 1.0 framing, which Feetech shares), then a read of address 0–5 to tell the
    vendor and the model."""
    import dynamixel_sdk as sdk

    port = open_port(_port(sdk, name, timeout_s), name, baud, lambda: None)
    port.ser.timeout = 0.001  # wait for bytes instead of spinning (a spinning host starves a busy computer)
    handler = sdk.PacketHandler(1.0)
    found: list[Found] = []
    try:
        missed = [i for i in ids if not _identify(sdk, handler, port, name, baud, i, found)]
        answered = [f.servo_id for f in found]
        if answered:  # a reply lost on a busy host: the gaps between the ids found are asked once more
            for servo_id in [i for i in missed if min(answered) < i < max(answered)]:
                _identify(sdk, handler, port, name, baud, servo_id, found)
    finally:
        port.closePort()
    return sorted(found, key=lambda f: f.servo_id)


def _identify(sdk: Any, handler: Any, port: Any, name: str, baud: int, servo_id: int, found: list[Found]) -> bool:
    """PING ``servo_id``; if it answers, READ addresses 0–5 and add what it is to ``found``."""
    port.clearPort()
    _, result, _ = handler.txRxPacket(port, [0xFF, 0xFF, servo_id, 2, 1, 0])
    if result != sdk.COMM_SUCCESS:
        return False
    for _ in range(3):  # it is there: a lost reply is asked again
        port.clearPort()
        data, result, _ = handler.readTxRx(port, servo_id, 0, 6)
        if result == sdk.COMM_SUCCESS:
            break
    if result != sdk.COMM_SUCCESS or len(data) != 6:
        log.info("%s: servo %d answers PING but not READ (Status Return Level 0?)", name, servo_id)
        found.append(Found(name, baud, "1.0", servo_id, 0, "?"))
    else:
        dynamixel = Found(name, baud, "1.0", servo_id, data[0] | data[1] << 8, str(data[2]))
        feetech = Found(name, baud, "feetech", servo_id, data[3] | data[4] << 8, f"{data[0]}.{data[1]}")
        if data[3] == servo_id and data[5] == servo_id:  # e.g. STS3215 (777 = 0x0309) as servo 9: its model says
            found.append(feetech if not feetech.model.startswith("model number") else dynamixel)
        elif data[3] == servo_id or data[5] == servo_id:
            found.append(dynamixel if data[3] == servo_id else feetech)
        else:
            found.append(Found(name, baud, "1.0", servo_id, 0, "?"))
    return True


def check_ports(ports: list[str]) -> list[str]:
    """``ports``, or every serial adapter found when none is given; raises :class:`HardwareError` when there is
    none."""
    if ports:
        return ports
    found = serial_ports()
    if not found:
        raise HardwareError("no serial ports found (/dev/ttyUSB*, /dev/ttyACM*): plug in the servo bus adapter or "
                            "give --port")
    return found
