"""How many digits of each gain the design's inputs fix: the spread of the Riccati gains when every
input is perturbed at rounding level.

A gain on a nearly uncontrollable (or nearly unobservable) mode is fixed by the Riccati equation to
far fewer digits than a float carries: thesis-ch5's integral-of-theta gain to about three, because
the plant conserves a combination of its states. Its last printed digits then follow the machine's
arithmetic (its BLAS and LAPACK builds), not the design. Solving again with A, B and the weights
each moved by a few units in the last place, as a different build of the same libraries would, and
taking the largest change over several such solves, measures that directly; it is cheap (a few
Riccati solves) and needs no linearisation of the Riccati map, which a gain this ill-conditioned
would not honour.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

# each input entry is multiplied by (1 + u ROUNDING), u uniform in [-1, 1]: four units in the last
# place, the size of the differences between one BLAS/LAPACK build's result and another's
ROUNDING = 4 * np.finfo(float).eps
TRIALS = 6  # perturbed solves; the spread is the largest change seen
SEED = 20231  # fixed, so the same design reports the same spread
FULL_DIGITS = 15  # what a double carries: a gain determined this well is shown as fully determined
PRINTED_DIGITS = 6  # significant digits the report and the sheet print a gain with


@dataclass(frozen=True)
class GainSpread:
    """The largest change of each gain entry under rounding-level perturbations of its inputs.

    Attributes
    ----------
    K : ndarray
        Same shape as the LQR gain K (1 x n), absolute, in K's units.
    L : ndarray or None
        Same shape as the Kalman gain L (None for estimators without a Riccati equation).
    """

    K: np.ndarray
    L: np.ndarray | None = None

    def K_digits(self, K: np.ndarray) -> list[int]:
        """Significant digits fixed of each entry of K (row 0)."""
        return [significant_digits(float(k), float(s)) for k, s in zip(K[0], self.K[0])]


def gain_spread(gain_of: Callable[..., np.ndarray], inputs: tuple[np.ndarray, ...],
                symmetric: tuple[int, ...] = ()) -> np.ndarray:
    """The largest absolute change of ``gain_of(*inputs)`` over TRIALS rounding-level perturbations.

    Parameters
    ----------
    gain_of : callable
        Solves the Riccati equation for its inputs and returns the gain.
    inputs : tuple of ndarray
        The nominal inputs (A, B, Q, R or the filter's).
    symmetric : tuple of int
        Positions of the inputs that are symmetric (weights, covariances): perturbed symmetrically.

    Returns
    -------
    ndarray
        Shaped as the gain; inf where a perturbed solve fails or returns a non-finite gain.
    """
    base = gain_of(*inputs)
    rng = np.random.default_rng(SEED)
    worst = np.zeros_like(base, dtype=float)
    for _ in range(TRIALS):
        moved = []
        for i, m in enumerate(inputs):
            u = rng.uniform(-1.0, 1.0, m.shape)
            if i in symmetric:
                u = (u + u.T) / 2
            moved.append(m * (1.0 + ROUNDING * u))
        try:
            g = gain_of(*moved)
        except (np.linalg.LinAlgError, ValueError):
            return np.full_like(worst, np.inf)
        worst = np.maximum(worst, np.where(np.isfinite(g), np.abs(g - base), np.inf))
    return worst


def significant_digits(value: float, spread: float) -> int:
    """How many significant digits of ``value`` a spread fixes: 0 when the spread is as large as
    half the value (the gain is not determined beyond its size), FULL_DIGITS when it is nil."""
    if not math.isfinite(spread) or (spread > 0 and value == 0):
        return 0
    if spread == 0:
        return FULL_DIGITS
    rel = spread / abs(value)
    return 0 if rel >= 0.5 else min(FULL_DIGITS, int(math.floor(-math.log10(rel))))


def gain_text(value: float, spread: float, digits: int = PRINTED_DIGITS) -> tuple[str, bool]:
    """A gain as printed: ``digits`` significant digits, or only the digits the design fixes.

    Returns the text and whether it was cut (the flag the report and the sheet show). A gain that
    is not determined at all prints as ``0 ± bound``; a zero prints as 0, never -0.
    """
    fixed = significant_digits(value, spread)
    if fixed == 0:
        return f"0 ± {max(spread, abs(value)):.1e}", True
    text = f"{value:#.{min(digits, fixed)}g}"
    return text.rstrip(".") if float(text) != 0 else "0", fixed < digits
