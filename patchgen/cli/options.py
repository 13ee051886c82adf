"""Option types the commands share: numbers that must be finite and in range, and seeds.

click's FloatRange lets ``nan`` through (every comparison with it is false) and has no upper
bound unless given one; ``FiniteFloat`` refuses nan and inf and checks both ends.
"""

from __future__ import annotations

import math

import click

SEED = click.IntRange(0, 2**63 - 1)  # numpy's generators take a non-negative 64-bit seed


class FiniteFloat(click.ParamType):
    """A finite float within [lo, hi]."""

    name = "number"

    def __init__(self, lo: float | None = None, hi: float | None = None):
        self.lo, self.hi = lo, hi

    def convert(self, value, param, ctx) -> float:
        if isinstance(value, float):
            x = value
        else:
            try:
                x = float(value)
            except (TypeError, ValueError):
                self.fail(f"{value!r} is not a number", param, ctx)
        if not math.isfinite(x):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        if (self.lo is not None and x < self.lo) or (self.hi is not None and x > self.hi):
            self.fail(f"{value!r} is not within {self.lo:g} to {self.hi:g}", param, ctx)
        return x
