"""The numbers in a recording: plain decimal notation only, and within what a bench can show.

A cell is ``[+-]digits[.digits][e[+-]digits]`` (ASCII, surrounded by spaces or tabs at most).
Python's ``float`` also reads ``1_000``, ``nan``, ``infinity`` and non-ASCII digits, and a TOML
file may write ``0x10``, ``1_000`` or ``inf``: none of them is how a recorder writes a sample, and
``-0_3488`` read as -3488 would be a wrong mark, not an error, so all are refused.

Each unit has a plausible bound on the size of a sample (``LIMITS``): the bench is an analog
computer, a cart on a one-metre track and a force gauge. A number beyond it is a unit slip or a
corrupt file, and refusing it keeps every sum of squares finite. A channel whose largest sample is
below ``RESOLUTION`` of its unit holds nothing a sensor could resolve.
"""

from __future__ import annotations

import math
import re

import numba as nb
import numpy as np

PLAIN = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")

# unit -> (largest |sample|, why): generous beside the bench, far inside what sums of squares hold
LIMITS = {
    "V": (1e3, "a kilovolt: no analog computer or sensor of the bench reads more"),
    "N": (1e4, "ten kilonewtons: a tonne's weight, beyond any cart's force gauge"),
    "m": (20.0, "twenty metres: the longest track a plant takes"),
    "rad": (2 * math.pi, "a full turn: every protractor mark lies within it"),
    "s": (1e6, "a million seconds: eleven days"),
    "counts": (2.0 ** 31, "a 32-bit counter's range"),
}
RESOLUTION = 1e-9  # of the unit: a channel that never reaches a nanovolt (nanonewton, ...) holds no signal
MIN_SAMPLE_INTERVAL_S = 1e-6  # 1 MHz: faster than any bench recorder


def plain_number(cell: str) -> float | None:
    """The value of a cell in plain decimal notation, else None."""
    text = cell.strip(" \t")
    return float(text) if PLAIN.fullmatch(text) else None


def not_plain(text: str) -> str:
    """What a cell that is not a plain number is not: a finite number (nan, inf) or plain notation."""
    try:
        finite = math.isfinite(float(text))
    except ValueError:
        finite = True
    return ("a finite number" if not finite else
            "a number in plain decimal notation (digits, one point, an optional exponent)")


def unit_problem(unit: str, x: np.ndarray) -> tuple[int, str] | None:
    """The first sample beyond its unit's bound and what is wrong with it (None: all within)."""
    limit, why = LIMITS.get(unit, (None, ""))
    big = float(np.max(np.abs(x))) if x.size else 0.0
    if limit is not None and big > limit:
        k = int(np.argmax(np.abs(x) > limit))
        return k, f"{x[k]:.4g} {unit} is beyond {limit:g} {unit} ({why}): a unit slip or a corrupt file?"
    return None


def signal_problem(unit: str, x: np.ndarray) -> str | None:
    """A channel used for a fit whose every sample is below RESOLUTION of its unit (None: it has one)."""
    big = float(np.max(np.abs(x))) if x.size else 0.0
    if 0 < big < RESOLUTION:
        return (f"every sample is below {RESOLUTION:g} {unit} (largest {big:.3g}): no sensor resolves that; "
                "is the column in another unit?")
    return None


def whole_counts(x: np.ndarray) -> str | None:
    """An encoder's column whose samples are not all whole counts (None: they are)."""
    off = np.flatnonzero(x != np.round(x))
    if off.size:
        return f"sample {off[0] + 1} is {x[off[0]]:.6g}, not a whole count: an encoder counts in integers"
    return None


CLIP_RUN = 5  # samples held at exactly the extreme that make a flat top ...
CLIP_CONTRAST = 3  # ... when no value inside the range is held a third as long


def _runs(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Runs of equal consecutive samples: (start, length, value)."""
    edge = np.flatnonzero(np.diff(x) != 0) + 1
    start = np.concatenate([[0], edge])
    length = np.diff(np.concatenate([start, [x.size]]))
    return start, length, x[start]


def flat_top(x: np.ndarray, settles: bool = False) -> tuple[int, int, float] | None:
    """A clipped channel's longest flat top: (first sample, samples held, value), else None.

    A measured voltage or force carries noise, so it never repeats its largest (or smallest) value
    sample after sample unless a recorder or amplifier held it at its limit. A run at the extreme is
    a flat top when it lasts CLIP_RUN samples and no interior value (a coarse converter's level) is
    held a CLIP_CONTRAST-th as long. With ``settles`` (a cart that comes to rest at the end of its
    coast, read by a coarse converter) a run that ends the recording does not count."""
    if x.size < 2 * CLIP_RUN or x.min() == x.max():
        return None  # a constant channel is refused as one (patchgen.identify.sensors)
    start, length, value = _runs(x)
    inner = (value > x.min()) & (value < x.max())
    longest_inner = int(length[inner].max()) if np.any(inner) else 0
    at_edge = ~inner & ((start + length < x.size) | (not settles))
    if not np.any(at_edge):
        return None
    k = int(np.argmax(np.where(at_edge, length, 0)))
    if length[k] >= CLIP_RUN and length[k] >= CLIP_CONTRAST * longest_inner:
        return int(start[k]), int(length[k]), float(value[k])
    return None


EXACT_DIGITS = 2 ** 53  # a decimal mantissa up to this is a double exactly ...
EXACT_POWERS = np.array([10.0 ** k for k in range(23)])  # ... and so is 10^k up to 10^22


@nb.njit(cache=True)
def read_plain(text: np.ndarray, ncols: int, out: np.ndarray) -> int:
    """Read ``text`` (ASCII codes) as lines of exactly ncols cells, each a plain number (PLAIN)
    with spaces or tabs about it, separated by commas; the lines separated by newlines, no
    newline after the last: PLAIN's language by its automaton in one pass (a regular expression
    over a whole recording takes tens of milliseconds).

    The values go into ``out`` (row by row, as many as it holds). A mantissa of at most 2^53 and
    a power of ten of at most 10^22 are both exact doubles, so one multiplication or division
    gives the correctly rounded value, the one ``float`` gives (Clinger 1990); a number beyond
    that is left to ``float``.

    Returns
    -------
    int
        0 when the text is not such lines, 1 when every value is in ``out``, 2 when some value
        needs ``float``.
    """
    # 0 before a number, 1 after its sign, 2 integer digits, 3 a point after digits and any
    # digits after it, 4 a point without digits before it, 5 digits after such a point,
    # 6 after e, 7 after the exponent's sign, 8 exponent digits, 9 spaces after a number
    state, col, k, status = 0, 0, 0, 1
    negative, mantissa, digits, fraction, power, power_negative = False, 0, 0, 0, 0, False
    for i in range(text.size + 1):
        c = text[i] if i < text.size else 10  # the text ends as a line does
        if c == 32 or c == 9:
            if state == 0 or state == 9:
                continue
            if state == 2 or state == 3 or state == 5 or state == 8:
                state = 9
                continue
            return 0
        if 48 <= c <= 57:
            if state <= 5:
                if state <= 2:
                    state = 2
                elif state == 4:
                    state = 5
                if state == 3 or state == 5:
                    fraction += 1
                if mantissa > 0 or c > 48:
                    digits += 1
                    if digits <= 18:
                        mantissa = 10 * mantissa + (c - 48)
            elif state <= 8:
                state = 8
                power = min(10 * power + (c - 48), 100000)
            else:
                return 0
        elif c == 46:
            if state <= 1:
                state = 4
            elif state == 2:
                state = 3
            else:
                return 0
        elif c == 43 or c == 45:
            if state == 0:
                state, negative = 1, c == 45
            elif state == 6:
                state, power_negative = 7, c == 45
            else:
                return 0
        elif c == 101 or c == 69:
            if state == 2 or state == 3 or state == 5:
                state = 6
            else:
                return 0
        elif c == 44 or c == 10:
            if not (state == 2 or state == 3 or state == 5 or state == 8 or state == 9):
                return 0
            if c == 44:
                if col == ncols - 1:
                    return 0
                col += 1
            else:
                if col != ncols - 1:
                    return 0
                col = 0
            e10 = (-power if power_negative else power) - fraction
            if digits > 18 or mantissa > EXACT_DIGITS or abs(e10) > 22:
                status = 2
            elif k < out.size:
                v = mantissa * EXACT_POWERS[e10] if e10 >= 0 else mantissa / EXACT_POWERS[-e10]
                out[k] = -v if negative else v
            k += 1
            state, negative, mantissa, digits, fraction, power, power_negative = 0, False, 0, 0, 0, 0, False
        else:
            return 0
    return status
