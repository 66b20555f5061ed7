"""One control period of the MuJoCo world in one compiled call: the servo law, ``mj_step`` and the force sum of
every physics step, then the period's mean torque and speed and the servos' power.

:meth:`~shc_cli.backends.mujoco_.world.MujocoWorld.step` runs ``substeps`` (4) physics steps per control period;
in Python each paid the servo kernel's call, two ``perf_counter`` calls, the binding's ``mj_step`` call and a
NumPy addition, and the period's end a few NumPy operations and the power's kernel (≈ 12 µs per period over
MuJoCo's own time, ≈ 3 µs here). The kernels here run that loop in machine code and call MuJoCo's C ``mj_step``
directly on the raw ``mjModel*`` / ``mjData*`` (``model._address``, ``data._address``) through its address passed
as an integer (:func:`_guarded_step`), so numba caches them like every kernel of shc (a ``ctypes`` function baked
in as a global would not be cacheable). Each performs the operations of the Python code it replaces in the same
order — the servo laws are :mod:`shc_cli.backends.servo_kernels`' own functions — so every result is the same to the
last bit (``tests/test_mujoco_substeps.py``).

* **Timing**: each ``mj_step`` is timed with ``clock_gettime(clock)``, the clock of :func:`time.perf_counter`
  (``CLOCK_MONOTONIC`` on Linux), right before and after it, as the Python loop did: the world's ``physics_time``
  stays MuJoCo's own stepping time (the kernels return it in ns). It no longer includes the binding's call
  (argument conversion, the GIL's release, its error guard: ≈ 0.55 µs a step, ≈ 3 % of ``mj_step``'s time,
  ``benchmarks/bench_mujoco_period.py``).
* **Warnings** (``mju_warning``, e.g. an unstable simulation) reach MuJoCo's global log handler, hence the handler
  :func:`~shc_cli.backends.mujoco_.world.import_mujoco` installed, as from the Python binding.
* **Errors** (``mju_error``, which does not return; by default MuJoCo then prints, appends to ``MUJOCO_LOG.TXT``
  and exits the process): as the binding does, each ``mj_step`` runs under a thread-local log handler
  (:func:`_log_handler`) that jumps back (``setjmp``/``longjmp``) into the kernel with the message; the kernel
  stops and reports it, and the world raises the binding's ``mujoco.FatalError`` with the binding's text. Warnings
  pass through that handler to the global one.

The kernels hold the GIL while they step (≈ 0.1 ms a call; the binding released it inside ``mj_step``); MuJoCo's
warning handler takes it again, which the holding thread may.
"""

from __future__ import annotations

import ctypes
import logging
import time
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from shc_cli.backends.servo_kernels import firmware_torque, supply_power, velocity_motor, velocity_motor_force
from shc_cli.model.jit import njit

log = logging.getLogger(__name__)

CLOCK = int(getattr(time, "CLOCK_MONOTONIC", 1))
"""The clock of :func:`time.perf_counter` on Linux (``clock_gettime``'s id)."""
GUARD_BYTES = 2048
"""Size of a world's guard buffer: ``jmp_buf`` (≤ 512 bytes), the global log handler's address (8), an error's
function name (a pointer to MuJoCo's static text, 8) and subject (1024)."""
_JMP_BUF, _FORWARD, _FUNCTION, _MESSAGE = 0, 512, 520, 528
_MESSAGE_BYTES = 1024
_LOG_ERROR = 3
"""``mjLOG_ERROR`` (``mjtLogLevel``)."""
_SUBJECT, _FUNC = 8, 1040
"""Offsets of ``mjLogMessage.subject`` (after ``int level, topic``) and ``func`` (after ``subject`` and
``body``)."""

_I8P = ir.IntType(8).as_pointer()
_I32 = ir.IntType(32)
_I64 = ir.IntType(64)
_HANDLER = ir.FunctionType(ir.VoidType(), [_I8P])
"""``mjfLogHandler``: ``void (*)(const mjLogMessage*)``."""


CHECKED_VERSION = "4.0."
"""The MuJoCo release whose ``mjLogMessage`` layout (the offsets above) and private log-handler entry points the
kernels were written and tested against; with any other release the world steps from Python (the same results,
≈ 9 µs more a control period) rather than read a struct whose layout may have moved."""


class Entries(NamedTuple):
    """Addresses of MuJoCo's C functions the kernels call."""

    step: int
    """``mj_step``."""
    set_tls_log_handler: int
    """``_mjPRIVATE_setTlsLogHandler`` (what the Python binding uses to turn ``mju_error`` into an exception)."""
    global_log_handler: int
    """``_mjPRIVATE_getGlobalLogHandler``."""


def entries(mujoco: Any) -> Entries | None:
    """The C functions of the MuJoCo library the ``mujoco`` binding loaded, or None when they cannot be found
    (another platform's library name, another MuJoCo version), the release is not :data:`CHECKED_VERSION`, or
    numba's compiler is off (``NUMBA_DISABLE_JIT``): the world then steps from Python.

    The library is opened by its path in the package (the dynamic loader returns the copy already loaded); that it
    is the binding's copy is checked on the warning handler :func:`~shc_cli.backends.mujoco_.world.import_mujoco`
    installed through the binding (another copy would have none)."""
    from numba.core import config

    if getattr(config, "DISABLE_JIT", False):
        return None
    version = str(getattr(mujoco, "__version__", ""))
    if not version.startswith(CHECKED_VERSION):
        log.debug("MuJoCo %s: the physics steps from Python (the compiled period is checked on %s.*)", version,
                  CHECKED_VERSION)
        return None
    folder = Path(mujoco.__file__).parent
    for path in sorted(folder.glob("libmujoco.so*")):
        try:
            library = ctypes.CDLL(str(path))
            if not ctypes.c_void_p.in_dll(library, "mju_user_warning").value:
                continue
            return Entries(*(int(ctypes.cast(getattr(library, name), ctypes.c_void_p).value or 0) for name in
                             ("mj_step", "_mjPRIVATE_setTlsLogHandler", "_mjPRIVATE_getGlobalLogHandler")))
        except (OSError, AttributeError, ValueError) as error:
            log.debug("MuJoCo library %s: %s", path, error)
    return None


def _function(module: ir.Module, name: str, kind: ir.FunctionType, *attributes: str) -> ir.Function:
    """A C function of the process (libc) declared in ``module``."""
    function = cgutils.get_or_insert_function(module, kind, name)  # type: ignore[no-untyped-call]
    for attribute in attributes:
        function.attributes.add(attribute)
    return function


def _guard_pointer(module: ir.Module) -> ir.GlobalVariable:
    """The module's pointer to the guard buffer of the step running now (one step at a time: the GIL is held)."""
    name = "shc_mujoco_guard"
    if name in module.globals:
        return module.globals[name]
    guard = ir.GlobalVariable(module, _I8P, name)
    guard.linkage = "internal"
    guard.initializer = ir.Constant(_I8P, None)
    return guard


def _log_handler(module: ir.Module) -> ir.Function:
    """The thread-local log handler a step runs under: an error's subject into the guard buffer and ``longjmp``
    back to :func:`_guarded_step`; any other message to MuJoCo's global handler."""
    name = "shc_mujoco_log_handler"
    if name in module.globals:
        return module.globals[name]
    handler = ir.Function(module, _HANDLER, name)
    handler.linkage = "internal"
    message = handler.args[0]
    entry, error, forward, done = (handler.append_basic_block(label) for label in ("entry", "error", "forward",
                                                                                   "done"))
    builder = ir.IRBuilder(entry)
    guard = builder.load(_guard_pointer(module))
    level = builder.load(builder.bitcast(message, _I32.as_pointer()))
    builder.cbranch(builder.icmp_signed("==", level, ir.Constant(_I32, _LOG_ERROR)), error, forward)
    builder.position_at_end(error)
    function = builder.load(builder.bitcast(builder.gep(message, [ir.Constant(_I64, _FUNC)]), _I64.as_pointer()))
    builder.store(function, builder.bitcast(builder.gep(guard, [ir.Constant(_I64, _FUNCTION)]), _I64.as_pointer()))
    cgutils.raw_memcpy(builder, builder.gep(guard, [ir.Constant(_I64, _MESSAGE)]),
                       builder.gep(message, [ir.Constant(_I64, _SUBJECT)]), ir.Constant(_I64, _MESSAGE_BYTES - 1), 1)  # type: ignore[no-untyped-call]
    longjmp = _function(module, "longjmp", ir.FunctionType(ir.VoidType(), [_I8P, _I32]), "noreturn")
    builder.call(longjmp, [builder.gep(guard, [ir.Constant(_I64, _JMP_BUF)]), ir.Constant(_I32, 1)])
    builder.unreachable()
    builder.position_at_end(forward)
    slot = builder.bitcast(builder.gep(guard, [ir.Constant(_I64, _FORWARD)]), _I64.as_pointer())
    address = builder.load(slot)
    call = handler.append_basic_block("call")
    builder.cbranch(builder.icmp_unsigned("==", address, ir.Constant(_I64, 0)), done, call)
    builder.position_at_end(call)
    builder.call(builder.inttoptr(address, _HANDLER.as_pointer()), [message])
    # the warning handler ran Python, which may have let another thread step another world (and set the pointer)
    builder.store(guard, _guard_pointer(module))
    builder.branch(done)
    builder.position_at_end(done)
    builder.ret_void()
    return handler


def _guarded_step_typer(typingctx, entry_points, model, data, guard):  # type: ignore[no-untyped-def]
    """``mj_step(model, data)`` under :func:`_log_handler`; returns 0, or 1 when MuJoCo raised an error (its
    message is then in ``guard``). ``entry_points`` is :class:`Entries` as a tuple of ints, ``model`` and ``data``
    the addresses of ``mjModel`` and ``mjData``, ``guard`` a :data:`GUARD_BYTES`-byte ``uint8`` array."""
    signature = types.int32(entry_points, model, data, guard)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        module = builder.module
        step_address, set_address, global_address = (builder.extract_value(args[0], i) for i in range(3))
        buffer = context.make_array(signature.args[3])(context, builder, args[3]).data
        buffer = builder.bitcast(buffer, _I8P)
        builder.store(buffer, _guard_pointer(module))
        # the global handler now (the binding's warning handler behind it), for the warnings to pass through
        getter = builder.inttoptr(global_address, ir.FunctionType(_I8P, []).as_pointer())
        forward = builder.ptrtoint(builder.call(getter, []), _I64)
        builder.store(forward, builder.bitcast(builder.gep(buffer, [ir.Constant(_I64, _FORWARD)]), _I64.as_pointer()))
        setter = builder.inttoptr(set_address, ir.FunctionType(_I8P, [_I8P]).as_pointer())
        previous = builder.call(setter, [builder.bitcast(_log_handler(module), _I8P)])
        setjmp = _function(module, "_setjmp", ir.FunctionType(_I32, [_I8P]), "returns_twice")
        jumped = builder.call(setjmp, [builder.gep(buffer, [ir.Constant(_I64, _JMP_BUF)])])
        status = cgutils.alloca_once_value(builder, ir.Constant(_I32, 1))  # type: ignore[no-untyped-call]
        with builder.if_then(builder.icmp_signed("==", jumped, ir.Constant(_I32, 0))):
            step = builder.inttoptr(step_address, ir.FunctionType(ir.VoidType(), [_I8P, _I8P]).as_pointer())
            builder.call(step, [builder.inttoptr(args[1], _I8P), builder.inttoptr(args[2], _I8P)])
            builder.store(ir.Constant(_I32, 0), status)
        builder.call(setter, [previous])
        return builder.load(status)

    return signature, codegen


_guarded_step: Any = intrinsic(_guarded_step_typer)


def _clock_ns_typer(typingctx, clock):  # type: ignore[no-untyped-def]
    """``clock_gettime(clock)`` in ns (the clock :func:`time.perf_counter` reads)."""
    signature = types.int64(clock)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        timespec = ir.LiteralStructType([_I64, _I64])
        gettime = _function(builder.module, "clock_gettime", ir.FunctionType(_I32, [_I32, timespec.as_pointer()]))
        now = cgutils.alloca_once(builder, timespec)  # type: ignore[no-untyped-call]
        builder.call(gettime, [builder.trunc(args[0], _I32), now])
        seconds = builder.load(builder.gep(now, [ir.Constant(_I32, 0), ir.Constant(_I32, 0)]))
        nanoseconds = builder.load(builder.gep(now, [ir.Constant(_I32, 0), ir.Constant(_I32, 1)]))
        return builder.add(builder.mul(seconds, ir.Constant(_I64, 1_000_000_000)), nanoseconds)

    return signature, codegen


_clock_ns: Any = intrinsic(_clock_ns_typer)


@njit(cache=True)
def _step(pointers, guard, clock):  # type: ignore[no-untyped-def]
    """One ``mj_step`` timed: (ns inside it, 0 or 1 when MuJoCo raised an error). ``pointers``: ``mj_step``,
    ``_mjPRIVATE_setTlsLogHandler``, ``_mjPRIVATE_getGlobalLogHandler``, ``mjModel*``, ``mjData*``."""
    started = _clock_ns(clock)
    failed = _guarded_step((pointers[0], pointers[1], pointers[2]), pointers[3], pointers[4], guard)
    return _clock_ns(clock) - started, failed


@njit(cache=True)
def _step_summed(pointers, guard, clock, force, total):  # type: ignore[no-untyped-def]
    """:func:`_step`, then the actuator forces after it added to ``total`` (not when MuJoCo raised an error)."""
    spent, failed = _step(pointers, guard, clock)
    if not failed:
        for i in range(total.shape[0]):
            total[i] += force[i]
    return spent, failed


@njit(cache=True)
def _period_end(q, previous, control_period, substeps, total, supply, work, positions, torque, power):  # type: ignore[no-untyped-def]
    """The control period's means and power, as the Python loop computed them: ``positions`` = ``q``; the mean
    speed ``(q − previous) / control_period`` (``work[1]``); ``torque`` = ``total / substeps``; ``power`` =
    :func:`~shc_cli.backends.servo_kernels.supply_power` of them (``supply``: the friction, then its scalar
    arguments; ``work[2]``, ``work[3]`` take the motor torque and current)."""
    speed = work[1]
    for i in range(q.shape[0]):
        positions[i] = q[i]
        speed[i] = (positions[i] - previous[i]) / control_period
        torque[i] = total[i] / substeps
    supply_power(torque, speed, supply[0], supply[1], supply[2], supply[3], supply[4], supply[5], supply[6],
                 supply[7], supply[8], work[2], work[3], power)


@njit(cache=True)
def firmware_period(pointers, guard, clock, substeps, step, control_period, goals, q, v, integral, firmware, ctrl,  # type: ignore[no-untyped-def]
                    force, supply, work, previous, positions, torque, power):
    """A control period of a ``dynamixel`` servo: ``substeps`` physics steps, each setting ``ctrl`` to the firmware
    torque (:func:`~shc_cli.backends.servo_kernels.firmware_torque`, ``firmware`` its scalar arguments) of the state
    before the step and adding the actuator forces after it to the sum ``work[0]``; then :func:`_period_end`.
    Returns (ns inside ``mj_step``, 0 or 1 when MuJoCo raised an error: the outputs are then not written)."""
    total = work[0]
    total[:] = 0.0
    physics = 0
    for _ in range(substeps):
        firmware_torque(goals, q, v, step, integral, firmware[0], firmware[1], firmware[2], firmware[3], firmware[4],
                        firmware[5], firmware[6], firmware[7], firmware[8], ctrl)
        spent, failed = _step_summed(pointers, guard, clock, force, total)
        physics += spent
        if failed:
            return physics, 1
    _period_end(q, previous, control_period, substeps, total, supply, work, positions, torque, power)
    return physics, 0


@njit(cache=True)
def compliant_period(pointers, guard, clock, substeps, control_period, q, force, supply, work, previous,  # type: ignore[no-untyped-def]
                     positions, torque, power):
    """A control period of a ``pd`` servo (a position actuator: no law per step): ``substeps`` physics steps, the
    actuator forces summed into ``work[0]``; then :func:`_period_end`. Returns as :func:`firmware_period`."""
    total = work[0]
    total[:] = 0.0
    physics = 0
    for _ in range(substeps):
        spent, failed = _step_summed(pointers, guard, clock, force, total)
        physics += spent
        if failed:
            return physics, 1
    _period_end(q, previous, control_period, substeps, total, supply, work, positions, torque, power)
    return physics, 0


@njit(cache=True)
def velocity_period(pointers, guard, clock, substeps, control_period, goals, q, v, motor, ctrl, supply, work,  # type: ignore[no-untyped-def]
                    previous, positions, torque, power):
    """A control period of PyBullet's velocity motor (``position`` servos; ``motor``: gain, keep, no-load speed,
    ``kv``, stall torque): ``substeps`` physics steps, each setting the speed target
    (:func:`~shc_cli.backends.servo_kernels.velocity_motor`) and adding the implicit actuator's force after it
    (:func:`~shc_cli.backends.servo_kernels.velocity_motor_force`) to ``work[0]``; then :func:`_period_end`.
    Returns as :func:`firmware_period`."""
    total = work[0]
    total[:] = 0.0
    physics = 0
    for _ in range(substeps):
        velocity_motor(goals, q, v, motor[0], motor[1], motor[2], ctrl)
        spent, failed = _step(pointers, guard, clock)
        physics += spent
        if failed:
            return physics, 1
        velocity_motor_force(ctrl, v, motor[3], motor[4], total)
    _period_end(q, previous, control_period, substeps, total, supply, work, positions, torque, power)
    return physics, 0


def guard_buffer() -> np.ndarray:
    """A world's guard buffer (see :func:`_guarded_step`)."""
    return np.zeros(GUARD_BYTES, dtype=np.uint8)


def error_message(guard: np.ndarray) -> str:
    """The message of the MuJoCo error a kernel reported, as the binding words it (``function: subject``)."""
    text = bytes(guard[_MESSAGE:_MESSAGE + _MESSAGE_BYTES]).split(b"\0", 1)[0].decode(errors="replace")
    function = int(guard[_FUNCTION:_FUNCTION + 8].view(np.uint64)[0])  # __func__: static text in MuJoCo's library
    return f"{ctypes.string_at(function).decode(errors='replace')}: {text}" if function else text
