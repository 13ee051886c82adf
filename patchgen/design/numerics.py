"""A design stage that fails numerically, reported as bad input naming the field behind it.

Every figure of a spec lies within its bounds, yet some combinations are too far apart for double
precision (a pendulum whose friction dwarfs its inertia, weights a trillion apart): LAPACK then
finds no solution, a matrix is singular to working precision, or numpy warns of an overflow.
Inside ``failing_as`` such a failure (a LinAlgError, or a RuntimeWarning or LinAlgWarning, made
errors there) becomes one InputError naming the stage's field, instead of a traceback or a
warning printed beside the result.
"""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
from scipy.linalg import LinAlgWarning

from patchgen.inputs.errors import InputError


@contextmanager
def failing_as(source: str, field: str, stage: str) -> Iterator[None]:
    """Numerical failure inside the block as InputError(source, field, ...)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            warnings.simplefilter("error", LinAlgWarning)
            yield
    except (np.linalg.LinAlgError, RuntimeWarning, LinAlgWarning) as exc:
        raise InputError(source, field, f"{stage} fails numerically ({_first_line(exc)}): these figures are too "
                         "far apart for double precision") from None


def _first_line(exc: Exception) -> str:
    text = str(exc).strip().splitlines()
    return text[0].rstrip(".") if text else type(exc).__name__
