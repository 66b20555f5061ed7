"""A bus of emulated Protocol 2.0 Dynamixel servos behind a pseudo-terminal, for testing without hardware.

``BusEmulator(servos).start()`` opens a pty pair; open ``emulator.port`` with dynamixel-sdk (or anything that
speaks the protocol) as if it were a USB2Dynamixel. Each servo has a control table (the addresses of
:mod:`shc_cli.hardware.models`) and, by default, first-order position dynamics while its torque is enabled
(``present += (goal − present)·(1 − e^(−Δt/τ))``, evaluated at every read). With ``dynamics`` (a robot file's
``[servo]`` table) the shaft is instead a load-free servo joint of that model (:mod:`shc_cli.backends.servo_joint`:
the firmware's P/I/D law, the motor's torque–speed line, armature, viscous and Coulomb gearbox friction), and
Present Current, Present Velocity and Present Position report its motor current, speed and angle in the model's
units (e.g. 2.69 mA, 0.229 rpm, ticks), optionally with Gaussian current noise. Faults can be injected per servo at
any time: no reply, the next k replies dropped, a corrupted CRC, Hardware Error Status bits (the status error
byte then carries the alert bit), overload (also turns its torque off, as real servos do), vanishing after a given
number of packets, and a present position whose bytes contain ``FF FF FD`` (so status packets need byte stuffing).

Instructions: PING (unicast and broadcast), READ, WRITE, SYNC READ, SYNC WRITE; anything else gets an
"instruction error" status. Replies are sent in ID order for broadcast ping and in the order of the IDs for sync
read, each servo after its return delay.
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import threading
import time
import tty
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from shc_cli.hardware import protocol2 as p2
from shc_cli.hardware.models import MODELS, OVERLOAD_ERROR, ServoModel

if TYPE_CHECKING:
    from shc_cli.backends.servo_joint import FreeJoints
    from shc_cli.spec.robot import Servo

TABLE_SIZE = 256
STUFFING_POSITION = 0x00FDFFFF
"""A present position whose little-endian bytes contain FF FF FD (``FF FF FD 00``)."""


@dataclass
class Faults:
    """Injectable faults of one servo."""

    no_reply: bool = False
    corrupt_crc: bool = False
    hardware_error: int = 0
    overload: bool = False
    vanish_after_packets: int | None = None
    stuffing_position: bool = False
    drop_replies: int = 0
    """The next this many status packets of the servo are not sent (each a missed reply; then it answers again)."""


@dataclass
class EmulatedServo:
    """One servo: its control table and faults."""

    servo_id: int
    model: ServoModel
    firmware: int = 45
    time_constant: float = 0.03
    table: bytearray = field(default_factory=lambda: bytearray(TABLE_SIZE))
    faults: Faults = field(default_factory=Faults)
    packets_seen: int = 0
    clock: Callable[[], float] = time.monotonic
    """The clock the motion model reads [s] (a test gives its own to move the servos without waiting)."""
    dynamics: Servo | None = None
    """The servo model moving the shaft (a ``[servo]`` table: a load-free joint of
    :mod:`shc_cli.backends.servo_joint`); None: the first-order lag of ``time_constant``."""
    current_noise_ma: float = 0.0
    """Standard deviation of Gaussian noise on Present Current [mA] (with ``dynamics``)."""
    _updated: float = math.nan
    _position: float = 2048.0
    _joint: FreeJoints | None = None
    _noise: Callable[[], float] | None = None

    def __post_init__(self) -> None:
        self._updated = self.clock()
        if self.dynamics is not None:
            import random

            from shc_cli.backends.servo_joint import FreeJoints

            self._joint = FreeJoints(self.dynamics, 1)
            self._noise = random.Random(self.servo_id).gauss
        self.write(self.model.model_number_address, self.model.model_number.to_bytes(2, "little"))
        self.write(self.model.firmware_address, bytes([self.firmware]))
        self.write(7, bytes([self.servo_id]))
        self.write(self.model.operating_mode, bytes([3]))  # factory defaults: position control, full range,
        self.write(self.model.return_delay_time, bytes([250]))  # 500 µs return delay (not waited for here)
        self.write(self.model.max_position_limit, (4095).to_bytes(4, "little"))
        self.write(self.model.current_limit, (2047).to_bytes(2, "little"))
        self.write(36, (885).to_bytes(2, "little"))  # PWM Limit, and Goal PWM at power-up (its value: e-Manual)
        self.write(100, (885).to_bytes(2, "little"))
        self.set_position(2048)
        self.write(self.model.goal_position, (2048).to_bytes(4, "little", signed=True))

    # -- control table -------------------------------------------------------------------------------------

    def read(self, address: int, length: int) -> bytes:
        self._advance()
        if self.faults.hardware_error:
            self.table[self.model.hardware_error_status] |= self.faults.hardware_error
        return bytes(self.table[address:address + length])

    def write(self, address: int, data: bytes) -> None:
        self._advance()
        self.table[address:address + len(data)] = data
        if address <= self.model.goal_position < address + len(data) and self.faults.overload:
            self._overload()

    def set_position(self, ticks: int) -> None:
        self._position = float(ticks)
        if self._joint is not None:
            self._joint.position[:] = ticks / self.model.ticks_per_radian
            self._joint.speed[:] = 0.0
        self._store_position(ticks)

    def _store_position(self, ticks: int) -> None:
        value = STUFFING_POSITION if self.faults.stuffing_position else ticks
        self.table[self.model.present_position:self.model.present_position + 4] = int(value).to_bytes(
            4, "little", signed=value < 2**31)

    def _int(self, address: int, length: int) -> int:
        return int.from_bytes(self.table[address:address + length], "little", signed=True)

    def _advance(self) -> None:
        """Motion since the last access: the servo model's (``dynamics``), else first-order towards the goal
        (torque on only)."""
        now = self.clock()
        elapsed, self._updated = now - self._updated, now
        if self._joint is not None:
            if elapsed > 0.0:
                self._move(elapsed)
            return
        if self.table[self.model.torque_enable] != 1 or elapsed <= 0.0:
            self.table[self.model.present_velocity:self.model.present_velocity + 4] = bytes(4)
            return
        goal = self._int(self.model.goal_position, 4)
        before = self._position
        self._position += (goal - before) * (1.0 - math.exp(-elapsed / self.time_constant))
        self._store_position(round(self._position))
        rpm = (self._position - before) / self.model.ticks_per_revolution / elapsed * 60.0
        velocity = round(rpm / self.model.velocity_unit_rpm)
        self.table[self.model.present_velocity:self.model.present_velocity + 4] = velocity.to_bytes(
            4, "little", signed=True)
        current = max(-32768, min(32767, round((goal - self._position) * 2.0)))
        self.table[self.model.present_current:self.model.present_current + 2] = current.to_bytes(
            2, "little", signed=True)

    def _move(self, elapsed: float) -> None:
        """The load-free joint over ``elapsed`` [s] towards Goal Position, its state into the control table."""
        joint, model = self._joint, self.model
        assert joint is not None and self._noise is not None
        per_radian = model.ticks_per_radian
        joint.advance(self._int(model.goal_position, 4) / per_radian, elapsed, self.table[model.torque_enable] == 1)
        self._position = float(joint.position[0]) * per_radian
        self._store_position(round(self._position))
        rpm = float(joint.speed[0]) * 60.0 / (2.0 * math.pi)
        velocity = round(rpm / model.velocity_unit_rpm)
        self.table[model.present_velocity:model.present_velocity + 4] = velocity.to_bytes(4, "little", signed=True)
        milliamps = float(joint.current[0]) * 1000.0
        if self.current_noise_ma:
            milliamps += self.current_noise_ma * self._noise()
        current = max(-32768, min(32767, round(milliamps / model.current_unit_ma)))
        self.table[model.present_current:model.present_current + 2] = current.to_bytes(2, "little", signed=True)

    def _overload(self) -> None:
        self.table[self.model.hardware_error_status] |= OVERLOAD_ERROR
        self.table[self.model.torque_enable] = 0

    @property
    def error_byte(self) -> int:
        if self.faults.hardware_error:
            self.table[self.model.hardware_error_status] |= self.faults.hardware_error
        return p2.ERROR_ALERT if self.table[self.model.hardware_error_status] else 0

    @property
    def present(self) -> bool:
        """Whether the servo still answers (not vanished)."""
        limit = self.faults.vanish_after_packets
        return limit is None or self.packets_seen < limit


class BusEmulator:
    """Servos on one emulated bus behind a pseudo-terminal.

    Args:
        servos: servo id → model name (see :data:`shc_cli.hardware.models.MODELS`).
        return_delay: seconds each reply waits (a real servo's return delay time).
        clock: the servos' clock [s] (default the monotonic clock).
        dynamics: the servo model of every servo (a robot file's ``[servo]`` table, its parameters the truth a
            fit should find), or None for the first-order lag.
        current_noise_ma: Gaussian noise on Present Current [mA] (with ``dynamics``; seeded by servo id).
        baud: the servos' baud rate [bit/s]: when given, packets sent at another line speed go unheard (as on a
            real bus; ``shc hw scan`` tries several).
    """

    def __init__(self, servos: dict[int, str], return_delay: float = 0.0,
                 clock: Callable[[], float] = time.monotonic, dynamics: Servo | None = None,
                 current_noise_ma: float = 0.0, baud: int | None = None) -> None:
        self.servos = {servo_id: EmulatedServo(servo_id, MODELS[model], clock=clock, dynamics=dynamics,
                                               current_noise_ma=current_noise_ma)
                       for servo_id, model in sorted(servos.items())}
        self.return_delay = return_delay
        self.baud = baud
        self.packets: list[p2.Packet] = []
        """Every instruction packet received, in order (for tests)."""
        self.crc_errors = 0
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        tty.setraw(self._master)
        self.port = os.ttyname(self._slave)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="dynamixel-emulator", daemon=True)
        self._lock = threading.Lock()
        self._busy = False

    def start(self) -> BusEmulator:
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=2.0)
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)

    def __enter__(self) -> BusEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def faults(self, servo_id: int) -> Faults:
        return self.servos[servo_id].faults

    def goal(self, servo_id: int) -> int:
        servo = self.servos[servo_id]
        return servo._int(servo.model.goal_position, 4)

    def torque_on(self, servo_id: int) -> bool:
        servo = self.servos[servo_id]
        return servo.table[servo.model.torque_enable] == 1

    def position(self, servo_id: int) -> int:
        servo = self.servos[servo_id]
        servo._advance()
        return round(servo._position)

    # -- the wire ------------------------------------------------------------------------------------------

    def _serve(self) -> None:
        serve_promptly()
        buffer = bytearray()
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], 0.05)
            if not ready:
                continue
            self._busy = True  # before the read: drain() sees either unread bytes or a busy emulator
            try:
                chunk = os.read(self._master, 4096)
            except OSError:
                return
            if not line_speed_matches(self._slave, self.baud):
                self._busy = False
                continue
            buffer += chunk
            while True:
                try:
                    incoming = p2.parse(buffer)
                except p2.PacketError:
                    self.crc_errors += 1
                    continue
                if incoming is None:
                    break
                with self._lock:
                    self.packets.append(incoming)
                    replies = self._handle(incoming)
                for reply in replies:
                    if self.return_delay:
                        time.sleep(self.return_delay)
                    os.write(self._master, reply)
            self._busy = False

    def drain(self, last: int | None = None, timeout: float = 1.0) -> None:
        """Wait (up to ``timeout`` [s] of wall time) until the bus has handled every byte it has been sent and, with
        ``last``, until the last packet it handled has that instruction (the one the host sent last: a pty delivers
        bytes a moment after they are written, so "nothing unread" alone can come too early)."""
        import fcntl
        import struct
        import termios

        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            pending = struct.unpack("i", fcntl.ioctl(self._master, termios.FIONREAD, b"\0\0\0\0"))[0]
            handled = last is None or (bool(self.packets) and self.packets[-1].instruction == last)
            if handled and not pending and not self._busy:
                return
            time.sleep(0.0002)

    def _reply(self, servo: EmulatedServo, params: bytes = b"", error: int = 0) -> list[bytes]:
        if servo.faults.no_reply or not servo.present:
            return []
        if servo.faults.drop_replies > 0:
            servo.faults.drop_replies -= 1
            return []
        data = bytearray(p2.status(servo.servo_id, error | servo.error_byte, params))
        if servo.faults.corrupt_crc:
            data[-1] ^= 0xFF
        return [bytes(data)]

    def _handle(self, incoming: p2.Packet) -> list[bytes]:
        for servo in self.servos.values():
            if incoming.servo in (servo.servo_id, p2.BROADCAST):
                servo.packets_seen += 1
        target = self.servos.get(incoming.servo)
        params = incoming.params
        instruction = incoming.instruction
        if instruction == p2.PING:
            targets = list(self.servos.values()) if incoming.servo == p2.BROADCAST else [target] if target else []
            return [r for servo in targets for r in self._reply(
                servo, servo.model.model_number.to_bytes(2, "little") + bytes([servo.firmware]))]
        if instruction == p2.SYNC_WRITE:
            address, length = int.from_bytes(params[0:2], "little"), int.from_bytes(params[2:4], "little")
            for at in range(4, len(params), 1 + length):
                written = self.servos.get(params[at])
                if written is not None and written.present:
                    written.write(address, params[at + 1:at + 1 + length])
            return []
        if instruction == p2.SYNC_READ:
            address, length = int.from_bytes(params[0:2], "little"), int.from_bytes(params[2:4], "little")
            replies: list[bytes] = []
            for servo_id in params[4:]:
                asked = self.servos.get(servo_id)
                if asked is not None:
                    replies += self._reply(asked, asked.read(address, length))
            return replies
        if incoming.servo == p2.BROADCAST and instruction == p2.WRITE:  # every servo, no reply
            for servo in self.servos.values():
                if servo.present:
                    servo.write(int.from_bytes(params[0:2], "little"), params[2:])
            return []
        if target is None:
            return []
        if instruction == p2.READ:
            address, length = int.from_bytes(params[0:2], "little"), int.from_bytes(params[2:4], "little")
            return self._reply(target, target.read(address, length))
        if instruction == p2.WRITE:
            target.write(int.from_bytes(params[0:2], "little"), params[2:])
            return self._reply(target)
        return self._reply(target, error=p2.ERROR_INSTRUCTION)


def line_speed_matches(fd: int, baud: int | None) -> bool:
    """Whether the pty's line speed (set by the host's serial library on its end) is ``baud`` [bit/s]: a real servo
    hears only its own baud rate. True when ``baud`` is None or the speed is not a standard one termios names
    (pyserial sets those through BOTHER, which a pty does not report)."""
    import termios

    if baud is None:
        return True
    constant = getattr(termios, f"B{baud}", None)
    try:
        speed = termios.tcgetattr(fd)[4]
    except termios.error:
        return True
    return constant is None or speed in (constant, getattr(termios, "BOTHER", -1))


class VirtualClock:
    """Virtual time [s] shared by emulated servos (their ``clock``) and the host loop that drives them (run-hw's
    pacing: ``run_hardware(config, clock=virtual, sleep=virtual.sleep)``): a control period passes in no wall time,
    so the servos see an exactly periodic host however loaded the machine. ``sleep`` first lets the emulator take
    every packet sent (:meth:`BusEmulator.drain` up to a packet of ``last``: run-hw's cycle ends with its goal SYNC
    WRITE), so a goal written in a cycle acts in that cycle, as on a real bus.
    """

    def __init__(self, start: float = 1000.0, last: int | None = p2.SYNC_WRITE) -> None:
        self.now = start
        self.last = last
        self.bus: BusEmulator | None = None
        """The emulator to drain before time moves on."""

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        if self.bus is not None:
            self.bus.drain(self.last)
        self.now += max(0.0, seconds)


def serve_promptly() -> None:
    """Raise the calling thread's scheduling priority where the system allows it (as root: nice −10).

    A real servo answers within its return delay whatever the host computer is doing; an emulator thread on a
    loaded test machine can be left waiting for a CPU longer than the host's packet timeout, and run-hw then rightly
    reports "no reply". Running the emulator ahead of other work keeps it a servo; without the permission nothing
    changes.
    """
    import os
    import threading

    with contextlib.suppress(OSError, AttributeError):
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), -10)
