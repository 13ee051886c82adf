"""Nonlinear least squares whose covariance comes from the residuals themselves.

A bench recording's residuals are not white: the random force on the cart and a sensor's
band-limited noise colour them, so the textbook covariance s^2 (J'J)^-1 would give intervals too
narrow. The residuals are a stationary series and the sensitivities J the model's own, so the
scores J_t r_t have the covariance S = sum J_t J_u' gamma(t - u), gamma the residuals'
autocovariance, estimated from them as far as it reaches; the sandwich (J'J)^-1 S (J'J)^-1 is the
parameters' covariance. For scores that are not of that form (a likelihood's), the long-run
covariance with Bartlett weights (Newey & West, Econometrica 1987) over Andrews' AR(1) plug-in
lag (Econometrica 1991).

The same covariance gives a score (Lagrange multiplier) test of an added term: its sensitivity,
with the fitted parameters' sensitivities projected out, should not correlate with the residuals
if the model needs no such term.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

MAX_LAG_FRACTION = 0.25  # the Bartlett lag never exceeds a quarter of the samples
CORRELATION_FLOOR = 1e-4  # the residuals' autocorrelation is summed until an AR(1) would fall below this


def _bartlett(e: np.ndarray, lag: int) -> np.ndarray:
    out = e.T @ e
    for k in range(1, lag + 1):
        g = e[k:].T @ e[:-k]
        out += (1 - k / (lag + 1)) * (g + g.T)
    return out


def andrews_lag(e: np.ndarray) -> int:
    """The Bartlett kernel's lag for the columns of e (n x p), each taken as AR(1) with its own
    rho and sigma (Andrews 1991, eq. 6.4 and 5.3): 1.1447 (alpha n)^(1/3)."""
    n = e.shape[0]
    num = den = 0.0
    for x in e.T:
        var = float(x[:-1] @ x[:-1])
        if var <= 0:
            continue
        rho = min(max(float(x[1:] @ x[:-1]) / var, -0.97), 0.97)
        s4 = (float(x @ x) / n * (1 - rho * rho)) ** 2
        num += 4 * rho * rho * s4 / ((1 - rho) ** 6 * (1 + rho) ** 2)
        den += s4 / (1 - rho) ** 4
    alpha = num / den if den > 0 else 0.0
    return int(min(max(1, math.ceil(1.1447 * (alpha * n) ** (1 / 3))), MAX_LAG_FRACTION * n))


def long_run_covariance(scores: np.ndarray) -> np.ndarray:
    """n times the long-run covariance of the rows of ``scores`` (n x p): Bartlett weights over
    Andrews' lag (Newey & West 1987; Andrews 1991)."""
    s = scores - scores.mean(axis=0)
    return _bartlett(s, andrews_lag(s))


def residual_lags(r: np.ndarray) -> int:
    """How far the residuals' autocorrelation reaches: the lag at which an AR(1) with their lag-1
    autocorrelation has fallen below CORRELATION_FLOOR, twice over, at most MAX_LAG_FRACTION of n."""
    x = r - r.mean()
    den = float(x[:-1] @ x[:-1])
    rho = abs(float(x[1:] @ x[:-1]) / den) if den > 0 else 0.0
    if rho < 1e-3:
        return 1
    reach = math.log(CORRELATION_FLOOR) / math.log(min(rho, 0.999))
    return int(min(max(1, math.ceil(2 * reach)), MAX_LAG_FRACTION * r.size))


def sandwich_meat(jac: np.ndarray, r: np.ndarray) -> np.ndarray:
    """sum over t, u of J_t J_u' gamma(t - u): the scores' covariance when the residuals are a
    stationary series with autocovariance gamma (estimated from them, to residual_lags) and the
    sensitivities J are the model's, not random."""
    n = r.size
    x = r - r.mean()
    out = (x @ x / n) * (jac.T @ jac)
    for k in range(1, residual_lags(r) + 1):
        g = float(x[k:] @ x[:-k]) / n
        c = jac[k:].T @ jac[:-k]
        out += g * (c + c.T)
    return out


@dataclass(frozen=True)
class LsqFit:
    """A least-squares fit: parameters, their covariance, residuals (model - data), Jacobian."""

    p: np.ndarray
    cov: np.ndarray
    residuals: np.ndarray
    jac: np.ndarray

    def se(self, i: int) -> float:
        """Standard error of parameter i."""
        return math.sqrt(max(self.cov[i, i], 0.0))

    def score_test(self, sensitivity: np.ndarray) -> float:
        """The score test's z for an added term whose output sensitivity at zero is ``sensitivity``:
        about standard normal when the data need no such term."""
        g = np.asarray(sensitivity, float)
        coef, *_ = np.linalg.lstsq(self.jac, g, rcond=None)
        g = g - self.jac @ coef
        stat = float(g @ self.residuals)
        var = float(sandwich_meat(g[:, None], self.residuals)[0, 0])
        return stat / math.sqrt(var) if var > 0 else 0.0


def fit(residual: Callable[[np.ndarray], np.ndarray], p0: np.ndarray, scale: np.ndarray,
        bounds: tuple = (-np.inf, np.inf)) -> LsqFit:
    """Minimise sum(residual(p)^2) from p0, and the Newey-West covariance of the result.

    Parameters
    ----------
    residual : callable
        p -> model - data, one entry per sample.
    p0 : ndarray
        The start.
    scale : ndarray
        Typical size of each parameter's change (the solver's x_scale and difference steps).
    bounds : tuple
        Lower and upper bounds, as scipy.optimize.least_squares takes them.

    Returns
    -------
    LsqFit
        The fit.
    """
    p0 = np.asarray(p0, float)
    scale = np.asarray(scale, float)
    lo, hi = np.broadcast_to(bounds[0], p0.shape), np.broadcast_to(bounds[1], p0.shape)
    p0 = np.clip(p0, lo + 1e-12 * scale, hi - 1e-12 * scale)
    res = least_squares(residual, p0, x_scale=scale, bounds=bounds, diff_step=1e-6, method="trf",
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)
    p = res.x
    r = residual(p)
    jac = _jacobian(residual, p, scale)
    bread = np.linalg.pinv(jac.T @ jac)
    meat = sandwich_meat(jac, r)
    n, k = jac.shape
    cov = bread @ meat @ bread * n / max(n - k, 1)
    return LsqFit(p, cov, r, jac)


def _jacobian(residual: Callable[[np.ndarray], np.ndarray], p: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Central differences, each step a thousandth of the parameter's scale."""
    cols = []
    for i in range(p.size):
        h = 1e-3 * scale[i]
        up, dn = p.copy(), p.copy()
        up[i] += h
        dn[i] -= h
        cols.append((residual(up) - residual(dn)) / (2 * h))
    return np.column_stack(cols)
