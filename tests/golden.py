"""Comparing written output with a stored golden file: structure exactly, numbers to a tolerance.

Floating-point results differ in their last digits across machines and library versions (BLAS,
LAPACK, numpy), so a golden file is never compared byte for byte.
"""

from __future__ import annotations

import math
import re
from typing import Any

# a number as text writes it: sign, digits, decimals, exponent
NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def assert_matches(got: Any, want: Any, rtol: float, atol: float, where: str = "$") -> None:
    """Raise AssertionError at the first place where ``got`` and ``want`` differ: keys, lengths,
    strings, integers and booleans exactly; floats within ``atol + rtol * |want|``."""
    if isinstance(want, dict):
        assert isinstance(got, dict), f"{where}: expected an object, got {type(got).__name__}"
        assert sorted(got) == sorted(want), f"{where}: keys {sorted(got)} != {sorted(want)}"
        for k in want:
            assert_matches(got[k], want[k], rtol, atol, f"{where}.{k}")
    elif isinstance(want, list):
        assert isinstance(got, list), f"{where}: expected a list, got {type(got).__name__}"
        assert len(got) == len(want), f"{where}: length {len(got)} != {len(want)}"
        for i, (g, w) in enumerate(zip(got, want)):
            assert_matches(g, w, rtol, atol, f"{where}[{i}]")
    elif isinstance(want, float) and not isinstance(want, bool):
        assert isinstance(got, (int, float)) and not isinstance(got, bool), f"{where}: {got!r} is not a number"
        assert math.isfinite(got) == math.isfinite(want), f"{where}: {got!r} != {want!r}"
        assert abs(got - want) <= atol + rtol * abs(want), f"{where}: {got!r} != {want!r} (rtol {rtol}, atol {atol})"
    else:
        assert type(got) is type(want) and got == want, f"{where}: {got!r} != {want!r}"


def assert_text_matches(got: str, want: str, rtol: float, atol: float, where: str = "text") -> None:
    """Text equal to ``want`` but for its numbers, each within ``atol + rtol * |want|``: the words,
    markup and layout exactly, the figures to a tolerance."""
    got_words, want_words = NUMBER.split(got), NUMBER.split(want)
    got_nums, want_nums = NUMBER.findall(got), NUMBER.findall(want)
    assert len(got_nums) == len(want_nums), f"{where}: {len(got_nums)} numbers != {len(want_nums)}"
    for i, (g, w) in enumerate(zip(got_words, want_words)):
        assert g == w, f"{where}: text differs before number {i}: {g[-60:]!r} != {w[-60:]!r}"
    for i, (g, w) in enumerate(zip(got_nums, want_nums)):
        assert abs(float(g) - float(w)) <= atol + rtol * abs(float(w)), f"{where}: number {i}: {g} != {w}"
