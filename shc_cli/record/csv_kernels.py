"""Compiled CSV row formatting for ``log.csv``: Python's ``%d``, ``%.4f`` and ``%.6g``, byte for byte.

A ``log.csv`` row has ~166 numbers; CPython formats each through its correctly rounded ``dtoa`` (≈ 0.2 µs a value,
≈ 30 µs a row, a sixth of a MuJoCo control cycle). These kernels write a block of rows into a byte buffer in one
call. They are exact where they answer and say so where they cannot:

* a number is scaled by a power of ten so that its significant digits are the integer part of ``p``
  (``p = |x|·10^s`` in [10⁵, 10⁶) for ``%.6g``, ``|x|·10⁴`` for ``%.4f``), with at most two roundings
  (10^k is exact in binary64 for k ≤ 22): ``p`` is within 2.5·10⁻¹⁶ relative of the exact value, < 10⁻⁹ absolute;
* the rounded digits are ``floor(p)`` or ``floor(p) + 1`` by whether ``p``'s fraction is below or above ½. When the
  fraction lies within :data:`TIE_MARGIN` of ½ (the exact value may be a tie, or on the other side of it), or the
  number is outside the scaled range (|x| < 10⁻³⁹ or ≥ 10⁴⁹, subnormals, ``%.4f`` of 10⁶ or more), the kernel gives
  the row back to Python (its ``end`` is not advanced and its ``hard`` flag is set) and the caller formats that row
  with ``%`` as before. Ties (e.g. 1.015625 → ``1.01562``, round-half-even) are exactly such rows.

The output of ``%.6g`` follows C's ``%g`` (which Python's ``%`` implements): the exponent ``X`` of the rounded value
chooses fixed notation for −4 ≤ X < 6, else ``d.ddddde±XX`` (at least two exponent digits); trailing zeros and a
bare decimal point are removed; ``nan`` (either sign), ``inf``, ``-inf``, ``0``, ``-0``.
``tests/test_csv_kernels.py`` compares every path against Python's own formatting over many random floats.
"""

from __future__ import annotations

import math

import numpy as np

from shc_cli.model.jit import njit

TIE_MARGIN = 1e-9
"""How close to ½ the scaled ``%.6g`` fraction may come before Python decides (4× the worst scaling error)."""
TIE_MARGIN_F4 = 1e-5
"""The same for ``%.4f`` (|x| < 10⁶: ``p`` < 10¹⁰, one rounding ≤ 10⁻⁶ absolute)."""
POW10 = np.array([float(10**k) for k in range(23)])
"""10^k, k = 0…22: exact in binary64."""
VALUE_WIDTH = 14
"""Bytes a ``%.6g`` value and its comma take at most (``-1.23457e-39,``: 13)."""
ROW_EXTRA = 48
"""Bytes of a row besides its values and state names at most (``%d`` cycle, ``%.4f`` time, commas, newline)."""

_COMMA, _MINUS, _PLUS, _DOT, _ZERO, _E, _NEWLINE = 44, 45, 43, 46, 48, 101, 10
_TEN, _NOUGHT, _DIGIT_ZERO = np.uint64(10), np.uint64(0), np.uint64(_ZERO)
_MILLION, _HUNDRED_THOUSAND = np.uint64(1000000), np.uint64(100000)
_HUNDRED, _ONE, _TWO = np.uint64(100), np.uint64(1), np.uint64(2)
_PAIRS = np.frombuffer("".join(f"{k:02d}" for k in range(100)).encode(), dtype=np.uint8).copy()
"""The significant digits are unsigned: numba's ``%`` and ``//`` of signed integers add Python's sign corrections
(≈ 1 µs of a 165-value row)."""


@njit(cache=True)
def _scaled(a, s):  # type: ignore[no-untyped-def]
    """``a·10^s`` with at most two roundings; −1 when |s| > 44 (out of the exact range)."""
    if s >= 0:
        if s > 44:
            return -1.0
        if s > 22:
            return (a * POW10[22]) * POW10[s - 22]
        return a * POW10[s]
    k = -s
    if k > 44:
        return -1.0
    if k > 22:
        return (a / POW10[22]) / POW10[k - 22]
    return a / POW10[k]


@njit(cache=True)
def _write_int(n, out, pos):  # type: ignore[no-untyped-def]
    """``%d`` of ``n`` at ``pos``; the position after it."""
    if n < 0:
        out[pos] = _MINUS
        pos += 1
        n = -n
    if n == 0:
        out[pos] = _ZERO
        return pos + 1
    digits = 0
    m = n
    while m > 0:
        digits += 1
        m //= 10
    end = pos + digits
    for i in range(digits):
        out[end - 1 - i] = _ZERO + n % 10
        n //= 10
    return end


@njit(cache=True)
def write_g6(x, out, pos):  # type: ignore[no-untyped-def]
    """``%.6g`` of ``x`` at ``pos``: the position after it, or −1 (nothing valid written) when Python must decide."""
    if x != x:
        out[pos], out[pos + 1], out[pos + 2] = 110, 97, 110  # nan
        return pos + 3
    if math.copysign(1.0, x) < 0.0:
        out[pos] = _MINUS
        pos += 1
    a = abs(x)
    if a == 0.0:
        out[pos] = _ZERO
        return pos + 1
    if a == math.inf:
        out[pos], out[pos + 1], out[pos + 2] = 105, 110, 102  # inf
        return pos + 3
    if a < 1e-39 or a >= 1e49:
        return -1
    # floor(log10 a), or one less, from the binary exponent and the chord of log10 over the mantissa (a log10
    # call costs more than the whole estimate); the range checks below correct it, exactly as before
    mantissa, exponent2 = math.frexp(a)  # a = mantissa·2^exponent2, mantissa in [½, 1)
    e = math.floor((exponent2 - 2 + 2.0 * mantissa) * 0.3010299956639812)
    p = _scaled(a, 5 - e)
    if p < 1e5:
        e -= 1
        p = _scaled(a, 5 - e)
    elif p >= 1e6:
        e += 1
        p = _scaled(a, 5 - e)
    if p < 1e5 or p >= 1e6:
        return -1
    whole = math.floor(p)
    fraction = p - whole
    if abs(fraction - 0.5) < TIE_MARGIN:
        return -1
    d = np.uint64(whole) + np.uint64(1 if fraction > 0.5 else 0)
    if d == _MILLION:
        d = _HUNDRED_THOUSAND
        e += 1
    used = 6
    while used > 1 and d % _TEN == _NOUGHT:  # trailing zeros go
        d //= _TEN
        used -= 1
    if -4 <= e < 6:
        if e < 0:
            out[pos], out[pos + 1] = _ZERO, _DOT
            pos += 2
            for _ in range(-e - 1):
                out[pos] = _ZERO
                pos += 1
            return _write_digits(d, used, out, pos)
        if used <= e + 1:  # an integer: its digits, then zeros
            pos = _write_digits(d, used, out, pos)
            for _ in range(e + 1 - used):
                out[pos] = _ZERO
                pos += 1
            return pos
        return _write_point(d, used, e + 1, out, pos)
    pos = _write_digits(d, 1, out, pos) if used == 1 else _write_point(d, used, 1, out, pos)
    out[pos] = _E
    out[pos + 1] = _MINUS if e < 0 else _PLUS
    pos += 2
    exponent = -e if e < 0 else e  # < 100: |x| is within [1e-39, 1e49)
    out[pos] = _ZERO + exponent // 10
    out[pos + 1] = _ZERO + exponent % 10
    return pos + 2


@njit(cache=True)
def _write_point(d, used, whole, out, pos):  # type: ignore[no-untyped-def]
    """The ``used`` digits of ``d`` with a decimal point after the first ``whole`` (< ``used``) of them."""
    end = _write_digits(d, used, out, pos + 1)
    for i in range(whole):  # the whole part one place to the left, then the point
        out[pos + i] = out[pos + 1 + i]
    out[pos + whole] = _DOT
    return end


@njit(cache=True)
def _write_digits(d, used, out, pos):  # type: ignore[no-untyped-def]
    """The ``used`` digits of ``d`` (which has that many) at ``pos``, two at a time; the position after them."""
    end = pos + used
    i = end
    while d >= _HUNDRED:
        q = d // _HUNDRED
        r = (d - q * _HUNDRED) * _TWO
        out[i - 1] = _PAIRS[r + _ONE]
        out[i - 2] = _PAIRS[r]
        i -= 2
        d = q
    if d >= _TEN:
        r = d * _TWO
        out[i - 1] = _PAIRS[r + _ONE]
        out[i - 2] = _PAIRS[r]
    else:
        out[i - 1] = _DIGIT_ZERO + d
    return end


@njit(cache=True)
def write_f4(x, out, pos):  # type: ignore[no-untyped-def]
    """``%.4f`` of ``x`` at ``pos``: the position after it, or −1 when Python must decide (|x| ≥ 10⁶, not finite,
    near a tie)."""
    if x != x:
        return -1
    if math.copysign(1.0, x) < 0.0:
        out[pos] = _MINUS
        pos += 1
    a = abs(x)
    if a >= 1e6:
        return -1
    p = a * 1e4
    whole = math.floor(p)
    fraction = p - whole
    if abs(fraction - 0.5) < TIE_MARGIN_F4:
        return -1
    r = int(whole) + (1 if fraction > 0.5 else 0)
    pos = _write_int(r // 10000, out, pos)
    out[pos] = _DOT
    r %= 10000
    for i in range(4):
        out[pos + 4 - i] = _ZERO + r % 10
        r //= 10
    return pos + 5


@njit(cache=True)
def format_rows(cycles, times, values, states, names, name_starts, rows, out, ends, hard):  # type: ignore[no-untyped-def]
    """Rows ``cycle,t,values…,states…\\n`` (``%d``, ``%.4f``, ``%.6g`` each, the state names as they are) into
    ``out``.

    Args:
        cycles, times: per row (``int64``, ``float64``).
        values: ``(capacity, columns)`` float64, the first ``rows`` rows used.
        states: ``(capacity, k)`` int64 indices into the names table.
        names: the names' bytes (uint8), name ``i`` is ``names[name_starts[i]:name_starts[i + 1]]``.
        rows: rows to write.
        out: uint8 buffer, large enough (:data:`VALUE_WIDTH` per value, :data:`ROW_EXTRA` and the names per row).
        ends: per row, the buffer position after it (a row Python must write takes no bytes).
        hard: per row, 1 when Python must write it, else 0.

    Returns:
        bytes written.
    """
    pos = 0
    columns = values.shape[1]
    for i in range(rows):
        start = pos
        failed = False
        pos = _write_int(cycles[i], out, pos)
        out[pos] = _COMMA
        pos = write_f4(times[i], out, pos + 1)
        if pos < 0:
            failed = True
        else:
            for j in range(columns):
                out[pos] = _COMMA
                pos = write_g6(values[i, j], out, pos + 1)
                if pos < 0:
                    failed = True
                    break
        if failed:
            pos = start
            ends[i] = pos
            hard[i] = 1
            continue
        for k in range(states.shape[1]):
            out[pos] = _COMMA
            pos += 1
            code = states[i, k]
            for b in range(name_starts[code], name_starts[code + 1]):
                out[pos] = names[b]
                pos += 1
        out[pos] = _NEWLINE
        pos += 1
        ends[i] = pos
        hard[i] = 0
    return pos
