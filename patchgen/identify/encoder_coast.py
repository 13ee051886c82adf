"""The coast-down's decay from an encoder's position alone, by maximum likelihood through a Kalman filter.

The cart coasts as in patchgen.identify.friction, z' = v, v' = -a v - f sgn(v) + d, with the random
force d an Ornstein-Uhlenbeck process of intensity q relaxing at lam (patchgen.identify.filters);
the encoder reads z to its count (variance r, about a count squared over twelve). The filter's
innovations give the likelihood; the parameters a, z0, v0, log q, log r (and f, when the data show
it) come from patchgen.identify.kalman.ml_fit, its sandwich covariance and Satterthwaite's degrees
of freedom. A least-squares fit of the position would see the random force as a drift its
residuals cannot describe (a position perturbed by a random force does not return), and its
intervals would be several times too narrow.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from patchgen.identify import kalman
from patchgen.identify.estimate import ML_KALMAN, Z_REJECT, Check, normal
from patchgen.identify.filters import expm

_JIT = {"cache": True, "error_model": "numpy"}
NOISE = (3, 4)  # log q, log r among the fit's parameters
NOISE_FLOOR = 1e-6  # of the start's variance: the lowest a noise variance may reach


@nb.njit(**_JIT)
def driven_nll(z, u, dt, a, k, lam, q, r, z0, v0, pred, contrib):
    """-log-likelihood (without its constant) of the positions z (a cart's, an arm's angle) read
    with variance r, the body driven by k u[t] held from sample t to t + 1 (a motor's voltage, a
    Coulomb deceleration), from (z0, v0) and the random acceleration at its stationary spread
    (intensity q, relaxing at lam). Each sample's prediction goes into pred, its term into contrib.
    The products of 3 x 3 matrices are written out: numba's ``@`` on them costs some twenty times
    more in this loop."""
    M = np.zeros((4, 4))
    M[0, 1], M[1, 1], M[1, 2], M[2, 2], M[1, 3] = 1.0, -a, 1.0, -lam, 1.0
    E = expm(M * dt)
    V = np.zeros((6, 6))
    V[0, 1], V[1, 1], V[1, 2], V[2, 2] = -1.0, a, -1.0, lam
    V[4, 3], V[4, 4], V[5, 4], V[5, 5] = 1.0, -a, 1.0, -lam
    V[2, 5] = q
    W = expm(V * dt)
    Phi = np.ascontiguousarray(E[:3, :3])
    c = np.ascontiguousarray(E[:3, 3])  # the state's response to a unit acceleration held over a step
    Q = np.ascontiguousarray(W[3:, 3:].T) @ np.ascontiguousarray(W[:3, 3:])  # Van Loan's: the noise over a step
    Q = 0.5 * (Q + Q.T)
    x = np.array([z0, v0, 0.0])
    P = np.zeros((3, 3))
    P[2, 2] = q / (2 * lam)
    T, R = np.zeros((3, 3)), np.zeros((3, 3))
    K = np.zeros(3)
    total = 0.0
    for t in range(z.size):
        s = P[0, 0] + r
        pred[t] = x[0]
        e = z[t] - x[0]
        contrib[t] = 0.5 * (math.log(s) + e * e / s)
        total += contrib[t]
        for i in range(3):
            K[i] = P[i, 0] / s
        for i in range(3):
            x[i] += K[i] * e
        for i in range(3):
            for j in range(3):
                T[i, j] = P[i, j] - K[i] * P[0, j]
        x0, x1, x2, ku = x[0], x[1], x[2], k * u[t]
        for i in range(3):
            x[i] = Phi[i, 0] * x0 + Phi[i, 1] * x1 + Phi[i, 2] * x2 + c[i] * ku
        for i in range(3):  # P <- Phi T Phi' + Q, through Phi T in R
            for j in range(3):
                R[i, j] = Phi[i, 0] * T[0, j] + Phi[i, 1] * T[1, j] + Phi[i, 2] * T[2, j]
        for i in range(3):
            for j in range(3):
                P[i, j] = R[i, 0] * Phi[j, 0] + R[i, 1] * Phi[j, 1] + R[i, 2] * Phi[j, 2] + Q[i, j]
    return total


@nb.njit(**_JIT)
def position_nll(z, dt, a, fs, lam, q, r, z0, v0, contrib):
    """-log-likelihood (without its constant) of a coast's positions z read with variance r, from
    (z0, v0) and the random force at its stationary spread; fs is the Coulomb deceleration with the
    motion's sign. Each sample's term goes into contrib. A coast is ``driven_nll`` with the
    Coulomb term as its constant input."""
    return driven_nll(z, np.full(z.size, -fs), dt, a, 1.0, lam, q, r, z0, v0, np.empty(z.size), contrib)


def fit_position(z: np.ndarray, dt: float, sign: float, lam: float, start: tuple[float, float], r0: float
                 ) -> tuple[kalman.MlFit, float, np.ndarray]:
    """The coast's decay from its positions.

    Parameters
    ----------
    z : ndarray
        The positions (m) from the moment the cart runs free.
    dt : float
        The step (s).
    sign : float
        The motion's direction (+1 or -1).
    lam : float
        The random force's relaxation rate (1/s): 4 x its bandwidth.
    start : tuple of float
        A start for a (1/s) and v0 (m/s).
    r0 : float
        The encoder's read variance (m^2): a count squared over twelve.

    Returns
    -------
    MlFit, float, ndarray
        The fit (a, z0, v0, log q, log r and, when the data show it, f in m/s^2), the
        likelihood-ratio z of Coulomb friction, and each sample's term at the fit.
    """
    contrib = np.empty(z.size)
    z = np.ascontiguousarray(z, dtype=float)

    def nll(p: np.ndarray) -> float:
        f = p[5] * sign if p.size > 5 else 0.0
        return float(position_nll(z, dt, p[0], f, lam, math.exp(p[3]), math.exp(p[4]), p[1], p[2], contrib))

    def many(P: np.ndarray) -> np.ndarray:
        return np.array([nll(p) for p in P])

    def terms(p: np.ndarray) -> np.ndarray:
        nll(p)
        return contrib.copy()

    a0, v0 = start
    speed = np.diff(z) / dt
    model = v0 * np.exp(-a0 * dt * np.arange(speed.size))
    var_v = max(float(np.var(speed - model)), 1e-12)
    q0 = 2 * a0 * lam * (a0 + lam) * var_v
    p0 = np.array([a0, z[0], v0, math.log(q0), math.log(r0)])
    s0 = np.array([0.01 * a0, math.sqrt(r0), 0.01 * abs(v0), 0.3, 0.3])
    lower = np.array([1e-6, -np.inf, -np.inf, math.log(NOISE_FLOOR * q0), math.log(NOISE_FLOOR * r0)])
    fit = kalman.ml_fit(nll, p0, s0, lower, per_sample=terms, noise=NOISE, nll_many=many)
    f_scale = 0.1 * max(fit.p[0], 1e-3) * abs(fit.p[2])
    both, zc = kalman.added_term(nll, fit, s0, f_scale, lower, many)
    if zc > Z_REJECT:
        se = np.sqrt(np.diag(fit.cov))
        fit = kalman.ml_fit(nll, both, np.append(np.where(se > 0, se, s0), f_scale), np.append(lower, -np.inf),
                            per_sample=terms, noise=NOISE, nll_many=many)
    nll(fit.p)
    return fit, zc, contrib.copy()


def coast_estimates(fit: kalman.MlFit, zc: float, source: str, decay: str, coulomb_unit: str, what: str
                    ) -> tuple[dict, list, np.ndarray]:
    """What a coast's fit (fit_position's) gives: the decay (named ``decay``, 1/s) and, when the
    likelihood-ratio z says so, the Coulomb deceleration (``coulomb``, in ``coulomb_unit``); the
    check that says which (``what``: the friction's kind of push, "force" or "torque"); and the
    free coast's parameters (z0, v0, a and f when kept)."""
    coulomb = zc > Z_REJECT  # friction opposes the motion: a negative f is no friction
    checks = [Check("Coulomb friction", zc, Z_REJECT, coulomb,
                    f"likelihood-ratio z = {zc:.3g} for a constant friction {what}: " +
                    ("the data show Coulomb friction (not in patchgen's plant, which is viscous)" if coulomb
                     else "viscous friction alone"))]
    est = {decay: normal(fit.p[0], fit.se(0), "1/s", ML_KALMAN, source, fit.dof_of(0))}
    if coulomb:
        est["coulomb"] = normal(fit.p[5], fit.se(5), coulomb_unit, ML_KALMAN, source, fit.dof_of(5))
    return est, checks, (fit.p[:3] if not coulomb else np.append(fit.p[:3], fit.p[5]))
