"""Estimates with their 95 % intervals, the checks that say when data reject a model, and what one
test's fit hands on (estimates, checks, the traces its plot draws).

Every interval is ``value +/- Z95 x standard error`` unless an estimate says otherwise (a
noise level's comes from the chi-square distribution of its variance); ``method`` names where the
standard error comes from.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

Z95 = float(stats.norm.ppf(0.975))  # two-sided 95 %
REJECT_LEVEL = 0.01  # a model is rejected at 1 %: one bench in a hundred flagged wrongly, not one in twenty
Z_REJECT = float(stats.norm.ppf(1 - REJECT_LEVEL / 2))
MIN_DOF = 1.0  # Satterthwaite's degrees of freedom are not taken below one

# where standard errors come from, as the report names them
LSQ_HAC = "least squares; sandwich covariance from the residuals' autocovariance"
ML_KALMAN = "maximum likelihood (Kalman filter innovations); sandwich covariance (curvature and scores)"
OLS = "least squares (ordinary, t quantile)"
DELTA = "delta method on the stated measurement uncertainties"
WEIGHTED = "inverse-variance weighted mean of the recordings"
CHI2_AR1 = "sample variance; chi-square with the AR(1) noise's effective degrees of freedom"


@dataclass(frozen=True)
class Estimate:
    """A value with its 95 % interval [low, high], unit, method and the file(s) it comes from."""

    value: float
    low: float
    high: float
    unit: str
    method: str
    source: str = ""
    dof: float = math.inf  # the t distribution's degrees of freedom the interval took (inf: normal)
    std_error: float | None = None  # given when the interval is not value +/- quantile x se

    @property
    def se(self) -> float:
        """The standard error: as given, else the one the interval stands for."""
        if self.std_error is not None:
            return self.std_error
        return (self.high - self.low) / (2 * quantile(self.dof))

    def covers(self, truth: float) -> bool:
        """Whether ``truth`` lies inside the interval."""
        return self.low <= truth <= self.high

    def to_dict(self) -> dict:
        """The estimate as JSON-ready numbers and words."""
        out = {"value": self.value, "interval_95": [self.low, self.high], "unit": self.unit,
               "method": self.method, "source": self.source}
        if math.isfinite(self.dof):
            out["dof"] = self.dof
        return out


def quantile(dof: float) -> float:
    """The two-sided 95 % quantile of Student's t with ``dof`` degrees of freedom (normal for inf)."""
    return Z95 if not math.isfinite(dof) else float(stats.t.ppf(0.975, max(dof, MIN_DOF)))


def normal(value: float, se: float, unit: str, method: str, source: str = "", dof: float = math.inf) -> Estimate:
    """The estimate ``value +/- q se``, q the 95 % quantile of t with ``dof`` degrees of freedom."""
    se = abs(float(se))
    q = quantile(dof)
    return Estimate(float(value), float(value) - q * se, float(value) + q * se, unit, method, source,
                    max(dof, MIN_DOF))


def welch(parts: Sequence[tuple[float, float]]) -> float:
    """Welch-Satterthwaite: the degrees of freedom of a sum of independent variance parts, each
    (standard error, its degrees of freedom)."""
    total = sum(se * se for se, _ in parts)
    spread = sum(se ** 4 / dof for se, dof in parts if se > 0 and math.isfinite(dof))
    return total * total / spread if spread > 0 else math.inf


def delta(f: Callable[[np.ndarray], float], x: np.ndarray, cov: np.ndarray,
          rel_step: float = 1e-6) -> tuple[float, float]:
    """(f(x), its standard error) by the delta method: central differences of f at x, through cov."""
    x = np.asarray(x, float)
    grad = np.empty(x.size)
    for i in range(x.size):
        h = rel_step * max(abs(x[i]), math.sqrt(max(cov[i, i], 0.0)), 1e-12)
        up, dn = x.copy(), x.copy()
        up[i] += h
        dn[i] -= h
        grad[i] = (f(up) - f(dn)) / (2 * h)
    return float(f(x)), float(math.sqrt(max(grad @ cov @ grad, 0.0)))


@dataclass(frozen=True)
class Check:
    """A test of the model against the data: its statistic, the threshold past which the data
    reject the model (at REJECT_LEVEL), and what it means in words."""

    name: str
    statistic: float
    threshold: float
    rejected: bool
    text: str

    def to_dict(self) -> dict:
        """The check as JSON-ready values."""
        return {"name": self.name, "statistic": self.statistic, "threshold": self.threshold,
                "rejected": self.rejected, "text": self.text}


@dataclass(frozen=True)
class Parameter:
    """One value written to the profile or the plant table: its estimate when identified, else
    where it was taken from."""

    value: float | str
    unit: str
    estimate: Estimate | None = None
    origin: str = ""

    def to_dict(self) -> dict:
        """JSON-ready: value, unit, interval and method when identified, origin."""
        out = {"value": self.value, "unit": self.unit, "origin": self.origin}
        if self.estimate is not None:
            out.update(interval_95=[self.estimate.low, self.estimate.high], method=self.estimate.method)
        return out


@dataclass(frozen=True)
class Panel:
    """One panel of a fit plot: the measured trace, the fitted one (or none) against x."""

    x: np.ndarray
    measured: np.ndarray
    fitted: np.ndarray | None
    ylabel: str
    xlabel: str = "t (s)"
    points: bool = False
    fitted_x: np.ndarray | None = None  # where the fitted trace is drawn, when not at x


@dataclass
class TestFit:
    """What one test's fit found: estimates by name, checks, notes, the panels of its plot."""

    source: str
    test: str
    estimates: dict[str, Estimate]
    checks: list[Check] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    panels: list[Panel] = field(default_factory=list)
    title: str = ""

    def to_dict(self) -> dict:
        """The fit as JSON-ready values (no traces)."""
        return {"file": self.source, "test": self.test, "title": self.title,
                "estimates": {k: e.to_dict() for k, e in self.estimates.items()},
                "checks": [c.to_dict() for c in self.checks], "notes": list(self.notes)}


def combine(estimates: Sequence[Estimate]) -> tuple[Estimate, Check | None]:
    """Estimates of one quantity from several recordings: their inverse-variance weighted mean,
    and Cochran's Q test of whether they agree (None for a single estimate).

    Parameters
    ----------
    estimates : sequence of Estimate
        At least one, in the same unit.

    Returns
    -------
    Estimate, Check or None
        The combined estimate (sources joined) and the agreement check.
    """
    if len(estimates) == 1:
        return estimates[0], None
    v = np.array([e.value for e in estimates])
    se = np.array([max(e.se, 1e-300) for e in estimates])
    w = 1.0 / se ** 2
    mean = float(np.sum(w * v) / np.sum(w))
    q = float(np.sum(w * (v - mean) ** 2))
    limit = float(stats.chi2.ppf(1 - REJECT_LEVEL, len(v) - 1))
    share = w / np.sum(w)  # Welch-Satterthwaite: 1 / dof = sum (V / V_i)^2 / dof_i
    spread = float(np.sum(share ** 2 / np.array([e.dof for e in estimates])))
    dof = 1.0 / spread if spread > 0 else math.inf
    est = normal(mean, 1.0 / math.sqrt(np.sum(w)), estimates[0].unit, WEIGHTED,
                 ", ".join(dict.fromkeys(e.source for e in estimates)), dof)
    text = (f"the {len(v)} recordings disagree beyond their intervals (Cochran's Q {q:.3g} > {limit:.3g}): "
            "the bench changed between them, or the model misses something" if q > limit else
            f"the {len(v)} recordings agree (Cochran's Q {q:.3g} <= {limit:.3g})")
    return est, Check("agreement", q, limit, q > limit, text)


def abs_estimate(e: Estimate) -> Estimate:
    """The magnitude of a signed estimate (its interval reflected when the value is negative)."""
    return e if e.value >= 0 else Estimate(-e.value, -e.high, -e.low, e.unit, e.method, e.source, e.dof, e.std_error)


def combine_into(result, estimates: Sequence[Estimate], what: str) -> Estimate:
    """:func:`combine` for an identification (``result``: its checks and warnings): the agreement
    check is kept under ``what`` and, when the recordings disagree, said as a warning."""
    est, check = combine(estimates)
    if check is not None:
        result.checks.append(Check(f"{what}: {check.name}", check.statistic, check.threshold, check.rejected,
                                   f"{what}: {check.text}"))
        if check.rejected:
            result.warnings.append(f"{what}: {check.text}")
    return est
