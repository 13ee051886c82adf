"""Maximum likelihood through the Kalman filter's innovations, for tests with a random force in them.

A coasting cart and a swinging pendulum are pushed about by the bench's random forces while they
are recorded: the deviation from the noise-free trajectory wanders for as long as the motion's
own time constant, and a fit of the noise-free trajectory would take that wander for information.
The filter follows the wander (process noise of density q on the acceleration) and the sensor
noise (variance r per sample); the negative log-likelihood of its innovations,
0.5 sum(log det S_k + e_k' S_k^-1 e_k), is minimised over the model's parameters and the noise
levels, and the inverse of its curvature at the minimum is the parameters' covariance.

The filters themselves are patchgen.identify.filters'.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize

from patchgen.identify import lsq

HESSIAN_STEP = 0.2  # central differences of the curvature step this many standard errors
NEWTON_STEPS = 4  # at most, after the quasi-Newton minimiser
NEWTON_DONE = 0.01  # standard errors: a Newton step shorter than this ends the polish
STEP_RANGE = (1e-6, 1e4)  # a difference step's variance, in the start's scales squared: a poor first curvature
# cannot shrink a step into rounding error
UNUSABLE = 1e300  # what the minimiser sees where the likelihood cannot be evaluated (a filter that diverged)
DOF_STEP = 0.5  # the largest step in a noise parameter (a log variance) when differentiating the covariance
FD_STEP = 1e-8  # the minimiser's forward-difference step, in the start's scales (L-BFGS-B's own default)


FitError = lsq.FitError


@dataclass(frozen=True)
class MlFit:
    """A maximum-likelihood fit: parameters, covariance (zero rows for those held at a bound) and,
    for the degrees of freedom of an interval (``dof``), the model-based covariance of the other
    parameters and its derivatives with respect to each noise parameter."""

    p: np.ndarray
    cov: np.ndarray
    nll: float
    model_cov: np.ndarray | None = None
    dcov: np.ndarray | None = None  # (noise parameters, n, n)
    noise: tuple[int, ...] = ()

    def se(self, i: int) -> float:
        """Standard error of parameter i."""
        return math.sqrt(max(self.cov[i, i], 0.0))

    def dof(self, grad: np.ndarray) -> float:
        """Satterthwaite's degrees of freedom of the variance of grad . p: 2 V^2 / var(V), var(V)
        from V's derivatives with respect to the noise parameters and their covariance; inf
        without noise parameters (the normal quantile)."""
        if self.dcov is None or not self.noise:
            return math.inf
        g = np.asarray(grad, float)
        v = float(g @ self.model_cov @ g)
        d = np.array([g @ dk @ g for dk in self.dcov])
        c = self.cov[np.ix_(self.noise, self.noise)]
        var = float(d @ c @ d)
        return 2 * v * v / var if var > 0 and v > 0 else math.inf

    def dof_of(self, i: int) -> float:
        """The degrees of freedom of parameter i's interval."""
        return self.dof(np.eye(self.p.size)[i])


def hessian(f_many: Callable[[np.ndarray], np.ndarray], p: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The curvature at p by central differences of steps h, of f_many (points in rows -> values),
    every point evaluated in one call."""
    k = p.size
    steps = [np.zeros(k) for _ in range(k)]
    for i in range(k):
        steps[i][i] = h[i]
    points = [p]
    for i in range(k):
        points += [p + steps[i], p - steps[i]]
        for j in range(i):
            points += [p + steps[i] + steps[j], p + steps[i] - steps[j], p - steps[i] + steps[j],
                       p - steps[i] - steps[j]]
    f = iter(f_many(np.array(points)))
    H = np.empty((k, k))
    f0 = next(f)
    for i in range(k):
        fp, fm = next(f), next(f)
        H[i, i] = (fp - 2 * f0 + fm) / h[i] ** 2
        for j in range(i):
            fpp, fpm, fmp, fmm = next(f), next(f), next(f), next(f)
            H[i, j] = H[j, i] = (fpp - fpm - fmp + fmm) / (4 * h[i] * h[j])
    return H


def ml_fit(nll: Callable[[np.ndarray], float], p0: np.ndarray, scale: np.ndarray,
           lower: np.ndarray | None = None, covariance: bool = True,
           per_sample: Callable[[np.ndarray], np.ndarray] | None = None, noise: tuple[int, ...] = (),
           nll_many: Callable[[np.ndarray], np.ndarray] | None = None) -> MlFit:
    """Minimise ``nll`` from p0 and invert its curvature.

    Parameters
    ----------
    nll : callable
        p -> negative log-likelihood.
    p0 : ndarray
        The start (a least-squares fit of the noise-free model, say).
    scale : ndarray
        About each parameter's standard error: the minimiser works in units of it, and the first
        curvature is taken with steps of HESSIAN_STEP of it.
    lower : ndarray, optional
        Lower bounds (a noise level's log); a parameter that ends on its bound is held there and
        gets no variance.
    covariance : bool
        Polish the minimum with Newton steps and return the covariance; without, the minimiser's
        result alone with a zero covariance (for a likelihood ratio).
    per_sample : callable, optional
        p -> each sample's term of the negative log-likelihood. With it the covariance is the
        sandwich H^-1 J H^-1, J the long-run covariance of the per-sample scores
        (patchgen.identify.lsq.long_run_covariance): it holds when the innovations are not
        white (a random force narrower in band than the filter assumes); without, H^-1.
    noise : tuple of int
        The noise parameters (log variances): the other parameters' intervals take Satterthwaite's
        degrees of freedom from how well these are known (MlFit.dof), as in a mixed model.
    nll_many : callable, optional
        Parameter points in rows -> their negative log-likelihoods, the same values as ``nll``'s:
        the many points of each finite-difference gradient and curvature go to it at once (one
        compiled call where there would be one Python call each).

    Returns
    -------
    MlFit
        The minimum and the covariance.
    """
    p0, scale = np.asarray(p0, float), np.asarray(scale, float)
    lo = np.full(p0.size, -np.inf) if lower is None else np.asarray(lower, float)
    z_lo = (lo - p0) / scale
    bounds = [(None if not math.isfinite(b) else b, None) for b in z_lo]
    seen: dict[bytes, float] = {}  # every point's value, by its bits: a point met again is not evaluated again

    def fz(z: np.ndarray) -> float:
        key = z.tobytes()
        if key not in seen:
            v = nll(p0 + scale * z)
            seen[key] = v if math.isfinite(v) else UNUSABLE
        return seen[key]

    def fz_many(Z: np.ndarray) -> np.ndarray:
        keys = [z.tobytes() for z in Z]
        new = [i for i, key in enumerate(keys) if key not in seen]
        if new:
            P = p0 + scale * Z[new]
            v = nll_many(P) if nll_many is not None else np.array([nll(p) for p in P])
            seen.update(zip((keys[i] for i in new), np.where(np.isfinite(v), v, UNUSABLE).tolist()))
        return np.array([seen[key] for key in keys])

    def gradient(z: np.ndarray) -> np.ndarray:
        """Forward differences from the value the minimiser has just had at z, as L-BFGS-B takes
        them itself: steps of FD_STEP, a relative step where z is so large that FD_STEP is lost to
        rounding, turned back where it would cross a lower bound."""
        f0 = fz(z)
        step = np.where((z + FD_STEP) - z == 0, math.sqrt(np.finfo(float).eps) * np.where(z >= 0, 1.0, -1.0)
                        * np.maximum(1.0, np.abs(z)), FD_STEP)
        step = np.where(z + step < z_lo, -step, step)
        points = np.tile(z, (z.size, 1))
        points[np.diag_indices(z.size)] = z + step
        return (fz_many(points) - f0) / ((z + step) - z)

    res = minimize(fz, np.zeros(p0.size), method="L-BFGS-B", jac=gradient, bounds=bounds,
                   options={"maxiter": 500, "ftol": 1e-10, "gtol": 1e-3, "maxcor": 20})
    z = res.x
    if not covariance:
        return MlFit(p0 + scale * z, np.zeros((p0.size, p0.size)), float(res.fun))
    h = np.full(p0.size, HESSIAN_STEP)
    for _ in range(NEWTON_STEPS):  # L-BFGS-B stops loosely on a long record: Newton steps on the curvature
        free = z > z_lo + 1e-6
        cov_free = np.linalg.pinv(hessian(fz_many, z, h)[np.ix_(free, free)])
        h[free] = HESSIAN_STEP * np.sqrt(np.clip(np.diag(cov_free), STEP_RANGE[0], STEP_RANGE[1]))
        idx = np.flatnonzero(free)
        f = fz_many(np.array([q for i in idx for q in (z + h[i] * np.eye(p0.size)[i],
                                                      z - h[i] * np.eye(p0.size)[i])]))
        grad = (f[0::2] - f[1::2]) / (2 * h[idx])
        move = -cov_free @ grad
        if not np.all(np.isfinite(move)) or np.max(np.abs(move)) < NEWTON_DONE:
            break
        trial = z.copy()
        trial[free] += np.clip(move, -5.0, 5.0)
        trial = np.maximum(trial, z_lo)
        if fz(trial) >= fz(z):
            break
        z = trial
    else:
        free = z > z_lo + 1e-6
        cov_free = np.linalg.pinv(hessian(fz_many, z, h)[np.ix_(free, free)])
    if per_sample is not None:
        idx = np.flatnonzero(free)
        scores = np.column_stack([(per_sample(p0 + scale * (z + h[i] * np.eye(p0.size)[i]))
                                   - per_sample(p0 + scale * (z - h[i] * np.eye(p0.size)[i]))) / (2 * h[i])
                                  for i in idx])
        sandwich = cov_free @ lsq.long_run_covariance(scores) @ cov_free
        # each variance the larger of the sandwich's and the curvature's: the long-run covariance
        # of the scores is itself estimated, and low by chance as often as the curvature is optimistic
        grow = np.sqrt(np.maximum(1.0, np.diag(cov_free) / np.maximum(np.diag(sandwich), 1e-300)))
        cov_free = sandwich * np.outer(grow, grow)
    if not np.all(np.isfinite(cov_free)):
        raise FitError("the likelihood cannot be evaluated around its best fit (a noise level at its floor?)")
    cov_z = np.zeros((p0.size, p0.size))
    cov_z[np.ix_(free, free)] = cov_free
    units = np.outer(scale, scale)
    noise = tuple(i for i in noise if free[i])
    model_cov = dcov = None
    if noise:
        rest = np.array([i for i in np.flatnonzero(free) if i not in noise])

        def block(zz: np.ndarray) -> np.ndarray:
            """The model-based covariance of the other parameters with the noise held at zz's."""
            def f_rest(X: np.ndarray) -> np.ndarray:
                full = np.tile(zz, (X.shape[0], 1))
                full[:, rest] = X
                return fz_many(full)

            out = np.zeros((p0.size, p0.size))
            out[np.ix_(rest, rest)] = np.linalg.pinv(hessian(f_rest, zz[rest], h[rest]))
            return out

        model_cov = block(z) * units
        dcov = np.zeros((len(noise), p0.size, p0.size))
        for j, k in enumerate(noise):
            step = min(math.sqrt(max(cov_z[k, k], 1e-12)), DOF_STEP / scale[k])
            up, dn = z.copy(), z.copy()
            up[k] += step
            dn[k] -= step
            dcov[j] = (block(up) - block(dn)) / (2 * step) * units / scale[k]
        if not (np.all(np.isfinite(dcov)) and np.all(np.isfinite(model_cov))):
            model_cov = dcov = None  # no degrees of freedom to be had: the normal quantile
    return MlFit(p0 + scale * z, cov_z * units, float(fz(z)), model_cov, dcov, noise)



def added_term(nll_with: Callable[[np.ndarray], float], fit: MlFit, start_scale: np.ndarray, scale: float,
               lower: np.ndarray, nll_many: Callable[[np.ndarray], np.ndarray] | None = None
               ) -> tuple[np.ndarray, float]:
    """The likelihood-ratio test of one added parameter (last in p), zero in ``fit``:
    z = sign x sqrt(2 (nll without - nll with)), about standard normal when the data need no such term.

    Parameters
    ----------
    nll_with : callable
        p -> negative log-likelihood with the added parameter last in p.
    fit : MlFit
        The fit without it.
    start_scale : ndarray
        The scales ``fit`` was started with (used where it holds a parameter at a bound).
    scale : float
        About the added parameter's standard error.
    lower : ndarray
        The lower bounds ``fit`` had.
    nll_many : callable, optional
        ``nll_with`` at many points at once (as ml_fit's).

    Returns
    -------
    ndarray, float
        The minimum with the term (to start its full fit from, when the term is kept), and z.
    """
    se = np.sqrt(np.clip(np.diag(fit.cov), 0.0, None))
    both = ml_fit(nll_with, np.append(fit.p, 0.0), np.append(np.where(se > 0, se, start_scale), scale),
                  np.append(lower, -np.inf), covariance=False, nll_many=nll_many)
    lr = 2.0 * (fit.nll - both.nll)
    return both.p, float(math.copysign(math.sqrt(max(lr, 0.0)), both.p[-1]))
