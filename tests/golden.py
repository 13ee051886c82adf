"""Comparing written output with a stored golden file: structure exactly, numbers to a tolerance.

Floating-point results differ in their last digits across machines and library versions (BLAS,
LAPACK, numpy), so a golden file is never compared byte for byte.
"""

from __future__ import annotations

import math
from typing import Any


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
