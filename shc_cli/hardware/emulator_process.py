"""An emulated servo bus served by a process of its own, and the emulators for a robot's servo map.

A real bus does not share the host's CPU; an emulator thread does, and beside a busy test worker it can be kept
waiting longer than the host's packet timeout (run-hw then rightly reports "no reply"). :class:`EmulatorProcess`
runs :class:`~shc_cli.hardware.emulator.BusEmulator` (Protocol 2.0) or
:class:`~shc_cli.hardware.emulator_protocol1.Protocol1Emulator` (Protocol 1.0, Feetech) in a spawned process, so
it has an interpreter (and a GIL) to itself; the test asks it for goals, positions and torque, and injects faults,
over a pipe. :func:`robot_emulators` builds one emulator per bus of a robot's ``[hardware.servos]``.
"""

from __future__ import annotations

import contextlib
import multiprocessing
from typing import TYPE_CHECKING, Any, Literal

from shc_cli.hardware.bus import HardwareError
from shc_cli.hardware.models import MODELS

if TYPE_CHECKING:
    from multiprocessing.connection import Connection

    from shc_cli.hardware.emulator import BusEmulator
    from shc_cli.hardware.emulator_protocol1 import Protocol1Emulator
    from shc_cli.spec.robot import Robot

Kind = Literal["protocol2", "protocol1"]


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


def _serve(connection: Connection, servos: dict[int, str], options: dict[str, Any]) -> None:
    """The child: start the emulator, send its port, then answer the parent's requests until "stop"."""
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
                connection.send(("ok", _answer(emulator, request, args)))
            except Exception as error:  # the parent raises it: a wrong request must not end the emulator
                connection.send(("error", f"{request}: {type(error).__name__}: {error}"))
    finally:
        emulator.stop()


def _answer(emulator: Any, request: str, args: list[Any]) -> Any:
    """One request of the parent (see :class:`EmulatorProcess`'s methods)."""
    if request in ("goal", "position", "torque_on"):
        return getattr(emulator, request)(*args)
    if request == "packets":
        with emulator.lock if hasattr(emulator, "lock") else _Null():
            return [(p.servo, p.instruction, bytes(p.params)) for p in emulator.packets[args[0]:]]
    if request == "fault":
        servo_id, name, value = args
        setattr(emulator.faults(servo_id), name, value)
        return None
    if request == "protect":
        emulator.protect(*args)
        return None
    if request == "set":  # control-table item: (id, address, value)
        servo_id, address, value = args
        with emulator.lock:
            emulator.servos[servo_id].set(address, value)
            if address == emulator.servos[servo_id].addr["position"]:
                emulator.servos[servo_id].position = float(value)
        return None
    raise ValueError(f"unknown request {request!r}")


class _Null:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


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
        return bool(self._ask("torque_on", servo_id))

    def packets(self, start: int = 0) -> list[tuple[int, int, bytes]]:
        """Instruction packets received from the ``start``-th on: (id, instruction, parameters)."""
        return list(self._ask("packets", start))

    def fault(self, servo_id: int, name: str, value: Any) -> None:
        """Set one of the servo's :class:`Faults` fields."""
        self._ask("fault", servo_id, name, value)

    def protect(self, servo_id: int, bits: int = 32) -> None:
        self._ask("protect", servo_id, bits)

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
