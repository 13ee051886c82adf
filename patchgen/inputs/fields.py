"""Field types every input model (spec, scenario, machine and bench profiles) is built from.

A value in an input file must be what its field declares: a number is a finite number (an
integer is accepted where a float is declared), never a string, a boolean, ``inf`` or ``nan``;
a flag is ``true`` or ``false``, never 1 or "yes". pydantic's lax mode would convert ``"3.5"``
or ``true`` into a number, so every input model validates in strict mode.

The bounds given with ``bounded`` carry a physical meaning (a cart between a gram and a tonne,
a sensor between a millivolt and a kilovolt per unit); docs/spec.md and docs/machines.md list
them with their reasons.
"""

from __future__ import annotations

import sys
from typing import Annotated, Any

from pydantic import AfterValidator, AllowInfNan, BaseModel, ConfigDict, Field, Strict


def _normal(v: float) -> float:
    if v != 0 and abs(v) < sys.float_info.min:
        raise ValueError(f"is too small to compute with (nonzero, below {sys.float_info.min:.3g}): use 0")
    return v


Real = Annotated[float, Strict(), AllowInfNan(False), AfterValidator(_normal)]
"""A finite float, zero or a normal number (an integer is accepted and becomes a float)."""

Int = Annotated[int, Strict()]
"""An integer (not a float, a string or a boolean)."""


class InputModel(BaseModel):
    """Base of every model read from a user's file: unknown fields are errors, values are not
    converted between types, and a read model does not change."""

    model_config = ConfigDict(extra="forbid", frozen=True, strict=True)


def bounded(lo: float | None = None, hi: float | None = None, *, open_lo: bool = False,
            default: Any = ..., description: str | None = None, **kw: Any) -> Any:
    """A pydantic Field with an inclusive range [lo, hi].

    Parameters
    ----------
    lo, hi : float, optional
        The limits; None leaves that side open.
    open_lo : bool
        Exclude ``lo`` itself (a duration that must be positive).
    default : object
        The default; none (required) unless given.
    description : str, optional
        Units and meaning, shown in the JSON schema.
    **kw
        Passed on to :func:`pydantic.Field`.
    """
    limits = {"gt" if open_lo else "ge": lo} if lo is not None else {}
    if hi is not None:
        limits["le"] = hi
    return Field(default, description=description, **limits, **kw)


def _zero_or_at_least(lo: float):
    def check(v: float) -> float:
        if 0 < v < lo:
            raise ValueError(f"must be 0 or at least {lo:g} (got {v:g})")
        return v
    return check


def zero_or_at_least(lo: float) -> AfterValidator:
    """A time constant that is either off (0) or long enough for the fixed-step simulator."""
    return AfterValidator(_zero_or_at_least(lo))


def magnitude(hi: float) -> Any:
    """A Real within [-hi, hi] (a signed quantity such as an initial velocity)."""
    return Annotated[Real, Field(ge=-hi, le=hi)]
