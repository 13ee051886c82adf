"""Nonlinear least squares whose covariance comes from the residuals themselves.

A bench recording's residuals are not white: the random force on the cart and a sensor's
band-limited noise colour them, so the textbook covariance s^2 (J'J)^-1 would give intervals too
narrow. The sandwich (J'J)^-1 S (J'J)^-1 with S the long-run covariance of the scores J_t r_t,
estimated with Bartlett weights (Newey & West, Econometrica 1987) over a lag chosen by Andrews'
AR(1) plug-in rule (Econometrica 1991), gives intervals that hold for coloured residuals.

The same long-run variance gives a score (Lagrange multiplier) test of an added term: its
sensitivity, with the fitted parameters' sensitivities projected out, should not correlate with
the residuals if the model needs no such term.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

MAX_LAG_FRACTION = 0.25  # the Bartlett lag never exceeds a quarter of the samples


def andrews_lag(r: np.ndarray) -> int:
    """The Bartlett kernel's lag for a series with lag-1 autocorrelation rho (Andrews 1991, AR(1)
    plug-in): 1.1447 (alpha n)^(1/3), alpha = 4 rho^2 / ((1 - rho)^2 (1 + rho)^2)."""
    n = r.size
    x = r - r.mean()
    den = float(x @ x)
    rho = float(x[1:] @ x[:-1]) / den if den > 0 else 0.0
    rho = min(max(rho, -0.99), 0.99)
    alpha = 4 * rho * rho / ((1 - rho) ** 2 * (1 + rho) ** 2)
    return int(min(max(1, math.ceil(1.1447 * (alpha * n) ** (1 / 3))), MAX_LAG_FRACTION * n))


def long_run_covariance(scores: np.ndarray, lag: int) -> np.ndarray:
    """sum over |k| <= lag of (1 - |k| / (lag + 1)) Gamma_k of the rows of ``scores`` (n x p)."""
    s = scores - scores.mean(axis=0)
    out = s.T @ s
    for k in range(1, lag + 1):
        g = s[k:].T @ s[:-k]
        out += (1 - k / (lag + 1)) * (g + g.T)
    return out


@dataclass(frozen=True)
class LsqFit:
    """A least-squares fit: parameters, their covariance, residuals (model - data), Jacobian, lag."""

    p: np.ndarray
    cov: np.ndarray
    residuals: np.ndarray
    jac: np.ndarray
    lag: int

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
        var = float(long_run_covariance((g * self.residuals)[:, None], self.lag)[0, 0])
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
    lag = andrews_lag(r)
    bread = np.linalg.pinv(jac.T @ jac)
    meat = long_run_covariance(jac * r[:, None], lag)
    n, k = jac.shape
    cov = bread @ meat @ bread * n / max(n - k, 1)
    return LsqFit(p, cov, r, jac, lag)


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
