"""Nonlinear least squares whose covariance comes from the residuals themselves.

A bench recording's residuals are not white: the random force on the cart and a sensor's
band-limited noise colour them, so the textbook covariance s^2 (J'J)^-1 would give intervals too
narrow. The residuals are a stationary series and the sensitivities J the model's own, so the
scores J_t r_t have the covariance S = sum J_t J_u' gamma(t - u), gamma the residuals'
autocovariance, of the ARMA(1,1) shape a first-order random force under white noise gives; the
sandwich (J'J)^-1 S (J'J)^-1 is the parameters' covariance. For scores that are not of that form
(a likelihood's), the long-run covariance with Bartlett weights (Newey & West, Econometrica
1987) over Andrews' AR(1) plug-in lag (Econometrica 1991).

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


def arma11_autocovariance(r: np.ndarray) -> tuple[float, float, float]:
    """gamma(0), gamma(1) and the decay rho of an ARMA(1,1) autocovariance (gamma(k) = gamma(1)
    rho^(k-1) for k >= 1) matched to the residuals' first three sample autocovariances: the shape of
    a first-order random force seen through white sensor or gauge noise. rho is 0 (white noise)
    when the residuals show no positive, decaying correlation."""
    x = r - r.mean()
    n = x.size
    g = [float(x[k:] @ x[:n - k]) / n for k in range(3)]
    rho = g[2] / g[1] if g[1] > 0 and g[2] > 0 else 0.0
    if not 0.0 < rho < 1.0:
        rho, g[1] = 0.0, max(g[1], 0.0)
    return g[0], g[1], min(rho, 0.999)


def sandwich_meat(jac: np.ndarray, r: np.ndarray) -> np.ndarray:
    """sum over t, u of J_t J_u' gamma(t - u): the scores' covariance when the residuals are a
    stationary series with autocovariance gamma and the sensitivities J are the model's, not random.

    gamma is the ARMA(1,1) shape fitted to the residuals' first autocovariances
    (arma11_autocovariance), summed until rho^k falls below CORRELATION_FLOOR^1.5 (1e-6). Summing
    the residuals' own sample autocovariances instead would be biased low: least squares leaves the
    residuals orthogonal to J, so their correlation along J is what the fit removed.
    """
    n = r.size
    g0, g1, rho = arma11_autocovariance(r)
    out = g0 * (jac.T @ jac)
    if g1 <= 0:
        return out
    reach = 1 if rho == 0 else math.ceil(1.5 * math.log(CORRELATION_FLOOR) / math.log(rho))
    gk = g1
    for k in range(1, int(min(max(reach, 1), MAX_LAG_FRACTION * n)) + 1):
        c = jac[k:].T @ jac[:-k]
        out += gk * (c + c.T)
        gk *= rho
    return out


class FitError(ValueError):
    """A fit that cannot give an estimate with an interval (the caller names the recording)."""


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
        bounds: tuple = (-np.inf, np.inf), covariance: bool = True) -> LsqFit:
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
    covariance : bool
        Without, the fit alone (a start for another fit): its covariance is NaN, the residuals'
        long sums of autocovariance not taken.

    Returns
    -------
    LsqFit
        The fit.
    """
    p0 = np.asarray(p0, float)
    scale = np.asarray(scale, float)
    lo, hi = np.broadcast_to(bounds[0], p0.shape), np.broadcast_to(bounds[1], p0.shape)
    p0 = np.clip(p0, lo + 1e-12 * scale, hi - 1e-12 * scale)
    if not (np.all(np.isfinite(p0)) and np.all(np.isfinite(scale)) and np.all(scale > 0)
            and np.all(np.isfinite(residual(p0)))):
        raise FitError("the model cannot be evaluated at its start (no finite residuals)")
    res = least_squares(residual, p0, x_scale=scale, bounds=bounds, diff_step=1e-6, method="trf",
                        xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)
    p = res.x
    r = residual(p)
    jac = _jacobian(residual, p, scale)
    if not (np.all(np.isfinite(r)) and np.all(np.isfinite(jac))):
        raise FitError("the model cannot be evaluated around its best fit (no finite residuals)")
    if not covariance:
        return LsqFit(p, np.full((p.size, p.size), np.nan), r, jac)
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
