"""A table of numbers as CSV text, each cell written as Python's ``%.<p>g`` writes it, compiled.

bench-test writes some 300 000 numbers per seed; Python formats them at about 0.2 us each. Here
each number's p significant digits are had from one correctly rounded multiplication or division
by a power of ten (exact up to 10^22): that product lies within 1.2e-16 of its value relative,
so for p up to MAX_PRECISION its rounding to an integer is the correctly rounded decimal unless it
lies within ``TIE`` of a half. Those few numbers (and any beyond the exact powers) take their
digits from Python's own ``%.<p-1>e``. The digits are then laid out by %g's rules: fixed
notation for exponents from -4 to p - 1, else exponential, trailing zeros dropped.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

TIE = 1e-5  # of a unit in the last digit: closer to a half than this, the digits are Python's
MAX_POWER = 22  # 10^k is exact in a double up to here
MAX_PRECISION = 10  # digits: the product's rounding (below 10^p x 1.2e-16 units) stays well inside TIE
POWERS = np.array([10.0 ** k for k in range(MAX_POWER + 1)])  # exact


@nb.njit(cache=True)
def _digits(values, precision, powers, digits, exponent, exact):
    """Each value's ``precision`` significant digits (an integer) and decimal exponent; exact[i]
    False where they must come from Python (a tie, or beyond the exact powers of ten)."""
    low, high = powers[precision - 1], powers[precision]
    for i in range(values.size):
        x = abs(values[i])
        digits[i], exponent[i], exact[i] = 0, 0, True
        if x == 0.0:
            continue
        e, m = int(math.floor(math.log10(x))), 0.0
        for _ in range(3):  # log10 may be a unit off near a power of ten
            k = precision - 1 - e
            if abs(k) > MAX_POWER:
                exact[i] = False
                break
            m = x * powers[k] if k >= 0 else x / powers[-k]
            if m < low:
                e -= 1
            elif m >= high:
                e += 1
            else:
                break
        else:
            exact[i] = False
        if not exact[i]:
            continue
        whole = math.floor(m)
        if abs(m - whole - 0.5) < TIE:
            exact[i] = False
            continue
        d = int(whole) + (1 if m - whole > 0.5 else 0)
        if d >= high:
            d, e = int(low), e + 1
        digits[i], exponent[i] = d, e


@nb.njit(cache=True)
def _put(out, pos, src, start, stop):
    """src[start:stop] into out at pos; the new position."""
    for j in range(start, stop):
        out[pos] = src[j]
        pos += 1
    return pos


@nb.njit(cache=True)
def _cell(out, pos, negative, d, e, p, buf):
    """One number by %g's rules from its p digits d and exponent e (buf scratch); the new position."""
    if negative:
        out[pos] = 45
        pos += 1
    if d == 0:
        out[pos] = 48
        return pos + 1
    for j in range(p):  # the digits, and where the last one not zero stands
        buf[p - 1 - j] = 48 + d % 10
        d //= 10
    last = p - 1
    while buf[last] == 48:
        last -= 1
    if 0 <= e < p:
        pos = _put(out, pos, buf, 0, e + 1)
        if last > e:
            out[pos] = 46
            pos = _put(out, pos + 1, buf, e + 1, last + 1)
        return pos
    if -4 <= e < 0:
        out[pos], out[pos + 1] = 48, 46
        pos += 2
        for _ in range(-e - 1):
            out[pos] = 48
            pos += 1
        return _put(out, pos, buf, 0, last + 1)
    pos = _put(out, pos, buf, 0, 1)
    if last > 0:
        out[pos] = 46
        pos = _put(out, pos + 1, buf, 1, last + 1)
    out[pos], out[pos + 1] = 101, 45 if e < 0 else 43
    pos += 2
    a = abs(e)
    if a >= 100:
        out[pos] = 48 + a // 100
        pos += 1
    out[pos], out[pos + 1] = 48 + a // 10 % 10, 48 + a % 10
    return pos + 2


@nb.njit(cache=True)
def _render(values, digits, exponent, precisions, out):
    """The rows of values as lines of cells separated by ", ", the lines by newlines; the length."""
    pos = 0
    rows, cols = values.shape
    buf = np.empty(24, np.uint8)
    for r in range(rows):
        if r:
            out[pos] = 10
            pos += 1
        for c in range(cols):
            if c:
                out[pos], out[pos + 1] = 44, 32
                pos += 2
            negative = math.copysign(1.0, values[r, c]) < 0
            pos = _cell(out, pos, negative, digits[r, c], exponent[r, c], precisions[c], buf)
    return pos


def format_table(values: np.ndarray, precisions: tuple[int, ...]) -> str:
    """The rows of ``values`` as CSV lines, column c's cells as ``"%.<precisions[c]>g" % v`` writes
    them, separated by ", " (no newline after the last line).

    Parameters
    ----------
    values : ndarray
        The table (rows, columns) of finite numbers; a table with any other is formatted by Python.
    precisions : tuple of int
        Significant digits per column (a table with more than MAX_PRECISION anywhere is formatted
        by Python).

    Returns
    -------
    str
        The text, the same as Python's row by row.
    """
    values = np.ascontiguousarray(values, dtype=float)
    if not np.all(np.isfinite(values)) or max(precisions) > MAX_PRECISION:
        row = ", ".join(f"%.{p}g" for p in precisions)
        return "\n".join(row % tuple(r) for r in values.tolist())
    digits = np.empty(values.shape, np.int64)
    exponent = np.empty(values.shape, np.int64)
    exact = np.empty(values.shape, np.bool_)
    for c, p in enumerate(precisions):
        col = [np.empty(values.shape[0], t) for t in (np.int64, np.int64, np.bool_)]
        _digits(np.ascontiguousarray(values[:, c]), p, POWERS, *col)
        digits[:, c], exponent[:, c], exact[:, c] = col
    for r, c in zip(*np.nonzero(~exact)):
        mantissa, exp = (f"%.{precisions[c] - 1}e" % abs(values[r, c])).split("e")
        digits[r, c], exponent[r, c] = int(mantissa.replace(".", "")), int(exp)
    out = np.empty(values.shape[0] * (sum(precisions) + 12 * values.shape[1] + 1), np.uint8)
    n = _render(values, digits, exponent, np.array(precisions, np.int64), out)
    return out[:n].tobytes().decode("ascii")
