"""An emulated servo bus served by a process of its own, and the emulators for a robot's servo map.

A real bus does not share the host's CPU; an emulator thread does, and beside a busy test worker it can be kept
waiting longer than the host's packet timeout (run-hw then rightly reports "no reply"). :class:`EmulatorProcess`
runs :class:`~shc_cli.hardware.emulator.BusEmulator` (Protocol 2.0) or
:class:`~shc_cli.hardware.emulator_protocol1.Protocol1Emulator` (Protocol 1.0, Feetech) in a spawned process, so
it has an interpreter (and a GIL) to itself; the test asks it for goals, positions, torque, control-table bytes
and the packets it heard, and injects faults, over a pipe. :func:`promptly` puts the host (the run-hw the test
starts) ahead of other work too. Every test that runs ``shc run-hw``, ``shc ros --backend bus`` or ``shc hw`` in
real time serves its bus this way (one emulator implementation: the process serves the same classes a thread
would). :func:`robot_emulators` builds one emulator per bus of a robot's ``[hardware.servos]``.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
from collections.abc import Iterator
from typing import TYPE_CHECKING, Any, Literal, NamedTuple

from shc_cli.hardware.bus import HardwareError
from shc_cli.hardware.models import MODELS

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from shc_cli.hardware.emulator import BusEmulator
    from shc_cli.hardware.emulator_protocol1 import Protocol1Emulator
    from shc_cli.spec.robot import Robot

Kind = Literal["protocol2", "protocol1"]


class Heard(NamedTuple):
    """An instruction packet the emulator received."""

    servo: int
    instruction: int
    params: bytes


def make_emulator(servos: dict[int, str], **options: Any) -> BusEmulator | Protocol1Emulator:
    """The emulator for ``servos`` (id → model name): Protocol 2.0 models on a :class:`BusEmulator` (options
    ``baud``, ``return_delay``), Protocol 1.0 and Feetech models on a :class:`Protocol1Emulator` (its options)."""
    from shc_cli.hardware.emulator import BusEmulator
    from shc_cli.hardware.emulator_protocol1 import EMULATED_MODELS, Protocol1Emulator

    families = {MODELS[name].family if name in MODELS else "?" for name in servos.values()}
    if families <= {"protocol2"}:
        return BusEmulator(servos, return_delay=options.get("return_delay", 0.0), baud=options.get("baud"),
                           dynamics=options.get("dynamics"), current_noise_ma=options.get("current_noise_ma", 0.0))
    missing = sorted({name for name in servos.values() if name not in EMULATED_MODELS})
    if missing:
        raise HardwareError(f"no emulator for {', '.join(missing)} (emulated: {', '.join(EMULATED_MODELS)} and "
                            "the Protocol 2.0 models)")
    return Protocol1Emulator(servos, **options)


def robot_emulators(robot: Robot, baud: int | None = None, dynamics: bool = False
                    ) -> list[BusEmulator | Protocol1Emulator]:
    """One emulator per bus of the robot's servo map (bus 0 first), at the robot's baud rate, its servos at the
    zero of the servo map (``zero_ticks`` or the middle of the range); not started. ``dynamics``: the servos move as
    the robot's ``[servo]`` model (load-free joints, :mod:`shc_cli.backends.servo_joint`), not a first-order lag."""
    hardware = robot.hardware
    if not hardware.servos:
        raise HardwareError(f"{robot.name}: no [hardware.servos] table to emulate")
    buses: dict[int, dict[int, str]] = {}
    zeros: dict[int, dict[int, int]] = {}
    for servo in hardware.servos.values():
        name = servo.model or hardware.model
        buses.setdefault(servo.bus, {})[servo.id] = name
        model = MODELS.get(name)
        if servo.zero_ticks is not None:
            zeros.setdefault(servo.bus, {})[servo.id] = servo.zero_ticks
        elif model is not None:
            zeros.setdefault(servo.bus, {})[servo.id] = model.centre
    rate = baud or hardware.baud
    out = []
    for bus in range(max(buses) + 1):
        servos = buses.get(bus, {})
        families = {MODELS[name].family for name in servos.values() if name in MODELS}
        options: dict[str, Any] = {"baud": rate}
        if dynamics:
            options["dynamics"] = robot.servo
        if families - {"protocol2"}:
            options.update(check_baud=True, positions=zeros.get(bus, {}))
        out.append(make_emulator(servos, **options))
    return out


@contextlib.contextmanager
def promptly() -> Iterator[None]:
    """The calling thread, and the processes it starts meanwhile (they inherit its niceness), ahead of other work
    where the system allows it (nice −10 as root, :func:`~shc_cli.hardware.emulator.serve_promptly`), then back to
    its niceness. A robot's computer runs its run-hw alone; on a loaded test machine a starved run-hw reports "no
    reply" though the reply is waiting: the Dynamixel SDK reads the port, then checks its ≈ 34 ms packet timeout,
    and a host kept off the CPU between the two times out without reading again."""
    from shc_cli.hardware.emulator import serve_promptly

    thread = threading.get_native_id()
    niceness = os.getpriority(os.PRIO_PROCESS, thread)
    serve_promptly()
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            os.setpriority(os.PRIO_PROCESS, thread, niceness)


def _serve(connection: Connection, servos: dict[int, str], options: dict[str, Any]) -> None:
    """The child: start the emulator, send its port, then answer the parent's requests until "stop". The cyclic
    garbage collector is off: the child makes little cyclic garbage, and a full collection of its growing packet log
    would hold up the emulator thread."""
    import gc

    gc.disable()
    emulator = make_emulator(servos, **options).start()
    connection.send(emulator.port)
    try:
        while True:
            try:
                request, *args = connection.recv()
            except EOFError:
                return
            if request == "stop":
                connection.send(None)
                return
            try:
                with _lock(emulator):
                    answer = _answer(emulator, request, args)
                connection.send(("ok", answer))
            except Exception as error:  # the parent raises it: a wrong request must not end the emulator
                connection.send(("error", f"{request}: {type(error).__name__}: {error}"))
    finally:
        emulator.stop()


def _lock(emulator: Any) -> Any:
    """The lock the emulator's thread holds while it handles a packet (a request sees no packet half-handled)."""
    return emulator.lock if hasattr(emulator, "lock") else emulator._lock


def _answer(emulator: Any, request: str, args: list[Any]) -> Any:
    """One request of the parent (see :class:`EmulatorProcess`'s methods), under the emulator's lock."""
    if request in ("goal", "position", "torque_on"):
        return getattr(emulator, request)(*args)
    if request == "ids":
        return sorted(emulator.servos)
    if request == "packets":
        return [(p.servo, p.instruction, bytes(p.params)) for p in emulator.packets[args[0]:]]
    if request == "packet_count":
        return len(emulator.packets)
    if request == "table":  # raw control-table bytes: (id, address, length)
        servo_id, address, length = args
        table = emulator.servos[servo_id].table
        if address < 0 or address + length > len(table):
            raise ValueError(f"bytes {address}..{address + length - 1} are outside the table ({len(table)} bytes)")
        return bytes(table[address:address + length])
    if request == "poke":  # raw control-table bytes written: (id, address, data)
        servo_id, address, data = args
        table = emulator.servos[servo_id].table
        if address < 0 or address + len(data) > len(table):
            raise ValueError(f"bytes {address}..{address + len(data) - 1} are outside the table ({len(table)} bytes)")
        table[address:address + len(data)] = data
        return None
    if request == "fault":
        servo_id, name, value = args
        faults = emulator.faults(servo_id)
        if not hasattr(faults, name):
            raise AttributeError(f"no fault {name!r} (faults: {', '.join(vars(faults))})")
        setattr(faults, name, value)
        return len(emulator.packets)
    if request == "vanish":
        servo_id, = args
        emulator.faults(servo_id).vanish_after_packets = emulator.servos[servo_id].packets_seen
        return len(emulator.packets)
    if request == "protect":
        emulator.protect(*args)
        return len(emulator.packets)
    if request == "set":  # control-table item: (id, address, value)
        servo_id, address, value = args
        emulator.servos[servo_id].set(address, value)
        if address == emulator.servos[servo_id].addr["position"]:
            emulator.servos[servo_id].position = float(value)
        return None
    raise ValueError(f"unknown request {request!r}")


class EmulatorProcess:
    """An emulator (:func:`make_emulator`'s arguments) served by a spawned process: ``with EmulatorProcess(...) as
    bus:`` gives ``bus.port``; the methods ask the emulator over a pipe."""

    def __init__(self, servos: dict[int, str], **options: Any) -> None:
        context = multiprocessing.get_context("spawn")
        self._connection, child = context.Pipe()
        self._process = context.Process(target=_serve, args=(child, servos, options), daemon=True,
                                        name="servo-emulator")
        self.port = ""

    def start(self) -> EmulatorProcess:
        self._process.start()
        if not self._connection.poll(60.0):
            self._process.kill()
            raise RuntimeError("the emulator process did not start")
        self.port = self._connection.recv()
        return self

    def _ask(self, *request: Any) -> Any:
        self._connection.send(request)
        answer = self._connection.recv()
        if request[0] == "stop":
            return answer
        status, value = answer
        if status == "error":
            raise RuntimeError(f"the emulator refused {value}")
        return value

    def goal(self, servo_id: int) -> int:
        """The servo's Goal Position [ticks]."""
        return int(self._ask("goal", servo_id))

    def position(self, servo_id: int) -> int:
        """The servo's present position [ticks]."""
        return int(self._ask("position", servo_id))

    def torque_on(self, servo_id: int) -> bool:
        """Whether the servo's Torque Enable is set."""
        return bool(self._ask("torque_on", servo_id))

    def ids(self) -> list[int]:
        """The ids of the emulated servos, ascending."""
        return list(self._ask("ids"))

    def packets(self, start: int = 0) -> list[Heard]:
        """Instruction packets received from the ``start``-th on: (id, instruction, parameters)."""
        return [Heard(*packet) for packet in self._ask("packets", start)]

    def packet_count(self) -> int:
        """How many instruction packets the emulator has received."""
        return int(self._ask("packet_count"))

    def table(self, servo_id: int, address: int, length: int = 1) -> bytes:
        """``length`` bytes of the servo's control table from ``address`` (little-endian, as on the wire)."""
        return bytes(self._ask("table", servo_id, address, length))

    def poke(self, servo_id: int, address: int, data: bytes) -> None:
        """Write bytes into the servo's control table directly, unchecked (a servo set up wrongly before the run)."""
        self._ask("poke", servo_id, address, bytes(data))

    def fault(self, servo_id: int, name: str, value: Any) -> int:
        """Set one of the servo's ``Faults`` fields (:class:`shc_cli.hardware.emulator.Faults`, Protocol 2.0;
        :class:`shc_cli.hardware.emulator_protocol1.Faults`); returns :meth:`packet_count` at that moment."""
        return int(self._ask("fault", servo_id, name, value))

    def vanish(self, servo_id: int) -> int:
        """The servo answers nothing from now on (unplugged mid-run); returns :meth:`packet_count` at that moment."""
        return int(self._ask("vanish", servo_id))

    def protect(self, servo_id: int, bits: int = 32) -> int:
        """The servo's protection trips (Protocol 1.0 / Feetech; overload by default); returns
        :meth:`packet_count` at that moment."""
        return int(self._ask("protect", servo_id, bits))

    def set(self, servo_id: int, address: int, value: int) -> None:
        """Write a control-table item directly (Protocol 1.0 / Feetech emulators; the present position moves the
        servo there)."""
        self._ask("set", servo_id, address, value)

    def stop(self) -> None:
        if self._process.is_alive():
            with contextlib.suppress(EOFError, OSError, BrokenPipeError):
                self._ask("stop")
            self._process.join(timeout=5.0)
        if self._process.is_alive():
            self._process.kill()

    def __enter__(self) -> EmulatorProcess:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
