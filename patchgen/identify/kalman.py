"""Maximum likelihood through the Kalman filter's innovations, for tests with a random force in them.

A coasting cart and a swinging pendulum are pushed about by the bench's random forces while they
are recorded: the deviation from the noise-free trajectory wanders for as long as the motion's
own time constant, and a fit of the noise-free trajectory would take that wander for information.
The filter follows the wander (process noise of density q on the acceleration) and the sensor
noise (variance r per sample); the negative log-likelihood of its innovations,
0.5 sum(log det S_k + e_k' S_k^-1 e_k), is minimised over the model's parameters and the noise
levels, and the inverse of its curvature at the minimum is the parameters' covariance.

The filters run compiled (numba, cached on disk as patchgen's simulation kernels are).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numba as nb
import numpy as np
from scipy.optimize import minimize

_JIT = {"cache": True, "error_model": "numpy"}
HESSIAN_STEP = 0.2  # central differences of the curvature step this many standard errors
NEWTON_STEPS = 4  # at most, after the quasi-Newton minimiser
NEWTON_DONE = 0.01  # standard errors: a Newton step shorter than this ends the polish


@nb.njit(**_JIT)
def coast_nll(z, w, dt, a, fs, rho, q, r1, r2, offset, z0, w0, pred):
    """-log-likelihood of a coast-down's pot (z) and tachometer (w) voltages for z' = rho w,
    w' = -a w - fs + white noise of density q, read with noise variances r1, r2 and the
    tachometer's offset, from (z0, w0) known; the predicted tachometer voltage into pred."""
    e = math.exp(-a * dt)
    m1 = -math.expm1(-a * dt) / a  # (1 - e) / a
    m2 = -math.expm1(-2 * a * dt) / (2 * a)  # (1 - e^2) / (2 a)
    f12, f22 = rho * m1, e
    g1, g2 = -fs * rho * (dt - m1) / a, -fs * m1
    q22 = q * m2
    q12 = q * rho / a * (m1 - m2)
    q11 = q * rho * rho / (a * a) * (dt - 2 * m1 + m2)
    x1, x2 = z0, w0
    p11, p12, p22 = 0.0, 0.0, 0.0
    total = 0.0
    for t in range(z.size):
        pred[t] = x2 + offset
        s11, s12, s22 = p11 + r1, p12, p22 + r2
        det = s11 * s22 - s12 * s12
        e1, e2 = z[t] - x1, w[t] - pred[t]
        total += 0.5 * (math.log(det) + (s22 * e1 * e1 - 2 * s12 * e1 * e2 + s11 * e2 * e2) / det)
        # K = P S^-1
        i11, i12, i22 = s22 / det, -s12 / det, s11 / det
        k11, k12 = p11 * i11 + p12 * i12, p11 * i12 + p12 * i22
        k21, k22 = p12 * i11 + p22 * i12, p12 * i12 + p22 * i22
        x1 += k11 * e1 + k12 * e2
        x2 += k21 * e1 + k22 * e2
        # P - K P (P symmetric; K P = P S^-1 P)
        n11 = p11 - (k11 * p11 + k12 * p12)
        n12 = p12 - (k11 * p12 + k12 * p22)
        n22 = p22 - (k21 * p12 + k22 * p22)
        # propagate: Phi = [[1, f12], [0, f22]]
        x1, x2 = x1 + f12 * x2 + g1, f22 * x2 + g2
        p11 = n11 + 2 * f12 * n12 + f12 * f12 * n22 + q11
        p12 = f22 * (n12 + f12 * n22) + q12
        p22 = f22 * f22 * n22 + q22
    return total


@nb.njit(**_JIT)
def _swing_rhs(phi, om, beta, w2, gam):
    return om, -beta * om - w2 * math.sin(phi) - gam * np.sign(om)


@nb.njit(**_JIT)
def swing_step(phi, om, beta, w2, gam, dt):
    """One RK4 step of B.5 about hanging, with a Coulomb term: phi'' = -beta phi' - w2 sin(phi) - gam sgn(phi')."""
    k1a, k1b = _swing_rhs(phi, om, beta, w2, gam)
    k2a, k2b = _swing_rhs(phi + 0.5 * dt * k1a, om + 0.5 * dt * k1b, beta, w2, gam)
    k3a, k3b = _swing_rhs(phi + 0.5 * dt * k2a, om + 0.5 * dt * k2b, beta, w2, gam)
    k4a, k4b = _swing_rhs(phi + dt * k3a, om + dt * k3b, beta, w2, gam)
    return (phi + dt / 6.0 * (k1a + 2 * k2a + 2 * k3a + k4a), om + dt / 6.0 * (k1b + 2 * k2b + 2 * k3b + k4b))


@nb.njit(**_JIT)
def swing_free(n, dt, beta, w2, gam, phi0, om0, out):
    """The noise-free swing from (phi0, om0): n samples of phi into out."""
    phi, om = phi0, om0
    for t in range(n):
        out[t] = phi
        phi, om = swing_step(phi, om, beta, w2, gam, dt)


@nb.njit(**_JIT)
def swing_nll(y, dt, beta, w2, gam, q, r, gain, offset, phi0, om0, pred):
    """-log-likelihood of the angle pot's voltage y = gain phi + offset + e (var r) for the swing
    B.5 with white angular acceleration of density q (extended Kalman filter); predictions into pred."""
    phi, om = phi0, om0
    p11, p12, p22 = 0.0, 0.0, 0.0
    q11, q12, q22 = q * dt ** 3 / 3.0, q * dt ** 2 / 2.0, q * dt
    total = 0.0
    for t in range(y.size):
        pred[t] = gain * phi + offset
        s = gain * gain * p11 + r
        e = y[t] - pred[t]
        total += 0.5 * (math.log(s) + e * e / s)
        k1, k2 = p11 * gain / s, p12 * gain / s
        phi += k1 * e
        om += k2 * e
        p11, p12, p22 = p11 - k1 * gain * p11, p12 - k1 * gain * p12, p22 - k2 * gain * p12
        # the linearised step: F = [[0, 1], [-w2 cos(phi), -beta]], Phi = I + F dt + F^2 dt^2 / 2
        a = -w2 * math.cos(phi)
        f11, f12 = 1.0 + 0.5 * a * dt * dt, dt - 0.5 * beta * dt * dt
        f21, f22 = a * dt - 0.5 * a * beta * dt * dt, 1.0 - beta * dt + 0.5 * (a + beta * beta) * dt * dt
        phi, om = swing_step(phi, om, beta, w2, gam, dt)
        n11 = f11 * (f11 * p11 + f12 * p12) + f12 * (f11 * p12 + f12 * p22) + q11
        n12 = f21 * (f11 * p11 + f12 * p12) + f22 * (f11 * p12 + f12 * p22) + q12
        n22 = f21 * (f21 * p11 + f22 * p12) + f22 * (f21 * p12 + f22 * p22) + q22
        p11, p12, p22 = n11, n12, n22
    return total


@dataclass(frozen=True)
class MlFit:
    """A maximum-likelihood fit: parameters, covariance (zero rows for those held at a bound)."""

    p: np.ndarray
    cov: np.ndarray
    nll: float

    def se(self, i: int) -> float:
        """Standard error of parameter i."""
        return math.sqrt(max(self.cov[i, i], 0.0))


def hessian(f: Callable[[np.ndarray], float], p: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The curvature of f at p by central differences of steps h."""
    k = p.size
    H = np.empty((k, k))
    f0 = f(p)
    for i in range(k):
        e_i = np.zeros(k)
        e_i[i] = h[i]
        H[i, i] = (f(p + e_i) - 2 * f0 + f(p - e_i)) / h[i] ** 2
        for j in range(i):
            e_j = np.zeros(k)
            e_j[j] = h[j]
            H[i, j] = H[j, i] = (f(p + e_i + e_j) - f(p + e_i - e_j) - f(p - e_i + e_j)
                                 + f(p - e_i - e_j)) / (4 * h[i] * h[j])
    return H


def ml_fit(nll: Callable[[np.ndarray], float], p0: np.ndarray, scale: np.ndarray,
           lower: np.ndarray | None = None, covariance: bool = True) -> MlFit:
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

    Returns
    -------
    MlFit
        The minimum and the covariance.
    """
    p0, scale = np.asarray(p0, float), np.asarray(scale, float)
    lo = np.full(p0.size, -np.inf) if lower is None else np.asarray(lower, float)
    z_lo = (lo - p0) / scale
    bounds = [(None if not math.isfinite(b) else b, None) for b in z_lo]
    fz = lambda z: nll(p0 + scale * z)
    res = minimize(fz, np.zeros(p0.size), method="L-BFGS-B", bounds=bounds,
                   options={"maxiter": 500, "ftol": 1e-10, "gtol": 1e-3, "maxcor": 20})
    z = res.x
    if not covariance:
        return MlFit(p0 + scale * z, np.zeros((p0.size, p0.size)), float(res.fun))
    h = np.full(p0.size, HESSIAN_STEP)
    for _ in range(NEWTON_STEPS):  # L-BFGS-B stops loosely on a long record: Newton steps on the curvature
        free = z > z_lo + 1e-6
        cov_free = np.linalg.pinv(hessian(fz, z, h)[np.ix_(free, free)])
        h[free] = HESSIAN_STEP * np.sqrt(np.clip(np.diag(cov_free), 1e-12, 1e6))
        grad = np.array([(fz(z + h[i] * np.eye(p0.size)[i]) - fz(z - h[i] * np.eye(p0.size)[i])) / (2 * h[i])
                         for i in np.flatnonzero(free)])
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
        cov_free = np.linalg.pinv(hessian(fz, z, h)[np.ix_(free, free)])
    cov_z = np.zeros((p0.size, p0.size))
    cov_z[np.ix_(free, free)] = cov_free
    return MlFit(p0 + scale * z, cov_z * np.outer(scale, scale), float(fz(z)))



def added_term(nll_with: Callable[[np.ndarray], float], fit: MlFit, start_scale: np.ndarray, scale: float,
               lower: np.ndarray) -> tuple[np.ndarray, float]:
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

    Returns
    -------
    ndarray, float
        The minimum with the term (to start its full fit from, when the term is kept), and z.
    """
    se = np.sqrt(np.clip(np.diag(fit.cov), 0.0, None))
    both = ml_fit(nll_with, np.append(fit.p, 0.0), np.append(np.where(se > 0, se, start_scale), scale),
                  np.append(lower, -np.inf), covariance=False)
    lr = 2.0 * (fit.nll - both.nll)
    return both.p, float(math.copysign(math.sqrt(max(lr, 0.0)), both.p[-1]))
