"""The compiled ``log.csv`` formatter writes exactly what Python's ``%`` writes (shc_cli/record/csv_kernels.py).

Every value the kernel formats is compared with CPython's own ``'%.6g' % x`` / ``'%.4f' % x`` (its correctly rounded
``dtoa``): random floats of every magnitude and random bit patterns, decimal-looking and dyadic numbers (ties),
the special values. Where the kernel declines (−1), the row goes to Python — the block test checks the whole text.
"""

from __future__ import annotations

import io
import math
import struct
from enum import Enum, IntEnum

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shc_cli.record import csv_kernels
from shc_cli.record.csv_rows import RowBlock

BUFFER = np.zeros(64, dtype=np.uint8)

SPECIAL = [0.0, -0.0, math.nan, -math.nan, math.inf, -math.inf, 1e-300, -1e-300, 5e-324, 2.2250738585072014e-308,
           1.7976931348623157e308, 1e300, 1.015625, 1234565.0, 999999.5, 9999995.0, 999999.0, 1e6, 1e5, 99999.95,
           0.0001, 0.00001, 9.999995e-5, 9.9999949e-5, 1e-39, 1e49, 9.99999e48, 1e-4, 123456.5, 0.5, 2.5, 1.0,
           -1.0, 1e16, 1e22, 1e23, 123456789.0, 0.1, 0.2, 0.3, 1 / 3, 2 / 3, math.pi, -math.e]


def python_g6(x: float) -> str:
    """What ``log.csv`` had row by row: CPython's ``%`` formatting."""
    return "%.6g" % x  # noqa: UP031 (the formatting under comparison)


def python_f4(x: float) -> str:
    return "%.4f" % x  # noqa: UP031


def kernel_g6(x: float) -> str | None:
    end = csv_kernels.write_g6(x, BUFFER, 0)
    return None if end < 0 else BUFFER[:end].tobytes().decode()


def kernel_f4(x: float) -> str | None:
    end = csv_kernels.write_f4(x, BUFFER, 0)
    return None if end < 0 else BUFFER[:end].tobytes().decode()


def random_floats(count: int, seed: int) -> list[float]:
    """Normal values scaled over 10⁻⁴⁵…10⁵⁰, random bit patterns, decimals with few digits, dyadic fractions
    (exact ties at the 6th significant digit), integers."""
    rng = np.random.default_rng(seed)
    n = count // 6
    parts = [rng.normal(0.0, 1.0, n) * 10.0 ** rng.integers(-45, 50, n),
             np.frombuffer(rng.bytes(8 * n), dtype=np.float64),
             np.round(rng.normal(0.0, 100.0, n) * 10.0 ** (k := rng.integers(0, 8, n))) / 10.0 ** k,
             rng.integers(0, 2**24, n) / 2.0 ** rng.integers(0, 40, n),
             rng.integers(-10**9, 10**9, n).astype(float),
             rng.normal(0.0, 1.0, n)]
    return [float(x) for x in np.concatenate(parts)]


@pytest.mark.parametrize("seed", [0, 1])
def test_g6_matches_python_on_random_floats(seed: int) -> None:
    declined = 0
    values = random_floats(120_000, seed)
    for x in values + SPECIAL:
        got = kernel_g6(x)
        if got is None:
            declined += 1
            continue
        assert got == python_g6(x), repr(x)
    # it declines only ties, near-ties and magnitudes outside 1e-39…1e49 (most random bit patterns): few of the rest
    assert declined < 0.25 * len(values)


def test_g6_declines_exact_ties_and_formats_the_rest_of_the_specials() -> None:
    assert kernel_g6(1.015625) is None  # 101562.5 ×10⁻⁵ exactly: Python rounds half to even → 1.01562
    assert kernel_g6(1234565.0) is None
    assert kernel_g6(5e-324) is None  # subnormal
    assert [kernel_g6(x) for x in (0.0, -0.0, math.nan, -math.nan, math.inf, -math.inf)] == \
        ["0", "-0", "nan", "nan", "inf", "-inf"]
    assert [kernel_g6(x) for x in (1e-5, 0.0001, 123456.0, 1e6, 999999.6, 1e-39 * 1.5, 9.9e48)] == \
        ["1e-05", "0.0001", "123456", "1e+06", "1e+06", "1.5e-39", "9.9e+48"]


FAST_EXAMPLES = 300
"""Hypothesis examples of each property in the fast suite; the ``_thoroughly`` twins (slow) draw 2000–3000."""


def _from_bits(bits: int) -> float:
    """The float whose IEEE 754 bit pattern is ``bits``."""
    return float(struct.unpack("<d", struct.pack("<Q", bits))[0])


FLOATS = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
BIT_PATTERNS = st.integers(min_value=0, max_value=2**64 - 1)


@given(FLOATS)
@settings(max_examples=FAST_EXAMPLES, deadline=None)
def test_g6_property(x: float) -> None:
    got = kernel_g6(x)
    assert got is None or got == python_g6(x), repr(x)  # None: declined, Python's % formats it


@pytest.mark.slow
@given(FLOATS)
@settings(max_examples=3000, deadline=None)
def test_g6_property_thoroughly(x: float) -> None:
    got = kernel_g6(x)
    assert got is None or got == python_g6(x), repr(x)  # None: declined, Python's % formats it


@given(BIT_PATTERNS)
@settings(max_examples=FAST_EXAMPLES, deadline=None)
def test_g6_property_on_bit_patterns(bits: int) -> None:
    x = _from_bits(bits)
    got = kernel_g6(x)
    assert got is None or got == python_g6(x), repr(x)


@pytest.mark.slow
@given(BIT_PATTERNS)
@settings(max_examples=3000, deadline=None)
def test_g6_property_on_bit_patterns_thoroughly(bits: int) -> None:
    x = _from_bits(bits)
    got = kernel_g6(x)
    assert got is None or got == python_g6(x), repr(x)


def test_f4_matches_python() -> None:
    rng = np.random.default_rng(3)
    times = [float(c) * 0.01 for c in range(0, 400_000, 7)] + [float(c) * 0.0025 for c in range(0, 100_000, 3)]
    values = times + [float(x) for x in rng.normal(0.0, 1e3, 50_000)] + [
        float(x) for x in rng.integers(0, 2**24, 50_000) / 2.0 ** rng.integers(0, 20, 50_000)] + [
        -0.0, -0.00001, 0.00005, 2.5e-5, 999999.99999, 1e6, math.nan, math.inf]
    declined = 0
    for x in values:
        got = kernel_f4(x)
        if got is None:
            declined += 1
            continue
        assert got == python_f4(x), repr(x)
    assert all(kernel_f4(t) is not None for t in times)  # a run's times never fall back
    assert kernel_f4(0.03125) is None and kernel_f4(1e6) is None and kernel_f4(math.nan) is None


@given(st.floats(min_value=-2e6, max_value=2e6))
@settings(max_examples=FAST_EXAMPLES, deadline=None)
def test_f4_property(x: float) -> None:
    got = kernel_f4(x)
    assert got is None or got == python_f4(x), repr(x)


@pytest.mark.slow
@given(st.floats(min_value=-2e6, max_value=2e6))
@settings(max_examples=2000, deadline=None)
def test_f4_property_thoroughly(x: float) -> None:
    got = kernel_f4(x)
    assert got is None or got == python_f4(x), repr(x)


class Robot(IntEnum):
    PACKED = 0
    RUNNING = 1


class Walk(IntEnum):  # equal to Robot's members by value: each name column keeps its own codes
    STARTING = 0
    MOVING = 1


class Other(Enum):
    ÜBER = "x"


def test_block_writes_what_percent_formatting_writes() -> None:
    """A block with ordinary rows, rows the kernel leaves to Python (a tie, a subnormal, a huge time) and names
    of two IntEnums that compare equal: the text is the row-by-row ``%`` text."""
    columns = 7
    row_format = ",".join(["%d", "%.4f", *["%.6g"] * columns, "%s", "%s", "%s"]) + "\n"
    block = RowBlock(columns, 3, row_format, capacity=5)
    rng = np.random.default_rng(5)
    handle, expected = io.StringIO(), []
    pool = random_floats(600, 9) + SPECIAL
    for cycle in range(23):
        values = [pool[int(i)] for i in rng.integers(0, len(pool), columns)]
        if cycle == 4:
            values[2] = 1.015625
        time = 1e7 if cycle == 9 else cycle * 0.01
        names = (Robot(cycle % 2), Walk(cycle % 2), Other.ÜBER)
        row = block.add(handle, cycle, time, tuple(block.code(k, name) for k, name in enumerate(names)))
        row[:] = values
        expected.append(row_format % (cycle, time, *values, *(name.name for name in names)))
        if cycle == 11:
            block.drain(handle)
    block.drain(handle)
    assert handle.getvalue() == "".join(expected)
