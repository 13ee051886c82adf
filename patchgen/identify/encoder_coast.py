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
from patchgen.identify.estimate import Z_REJECT
from patchgen.identify.filters import expm

_JIT = {"cache": True, "error_model": "numpy"}
NOISE = (3, 4)  # log q, log r among the fit's parameters
NOISE_FLOOR = 1e-6  # of the start's variance: the lowest a noise variance may reach


@nb.njit(**_JIT)
def position_nll(z, dt, a, fs, lam, q, r, z0, v0, contrib):
    """-log-likelihood (without its constant) of a coast's positions z read with variance r, from
    (z0, v0) and the random force at its stationary spread; fs is the Coulomb deceleration with the
    motion's sign. Each sample's term goes into contrib."""
    M = np.zeros((4, 4))
    M[0, 1], M[1, 1], M[1, 2], M[2, 2], M[1, 3] = 1.0, -a, 1.0, -lam, -fs
    E = expm(M * dt)
    V = np.zeros((6, 6))
    V[0, 1], V[1, 1], V[1, 2], V[2, 2] = -1.0, a, -1.0, lam
    V[4, 3], V[4, 4], V[5, 4], V[5, 5] = 1.0, -a, 1.0, -lam
    V[2, 5] = q
    W = expm(V * dt)
    Phi = np.ascontiguousarray(E[:3, :3])
    PhiT = np.ascontiguousarray(Phi.T)
    c = np.ascontiguousarray(E[:3, 3])
    Q = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for k in range(3):
                acc += W[3 + k, 3 + i] * W[k, 3 + j]
            Q[i, j] = acc
    for i in range(3):
        for j in range(i):
            Q[i, j] = Q[j, i] = 0.5 * (Q[i, j] + Q[j, i])
    x = np.array([z0, v0, 0.0])
    P = np.zeros((3, 3))
    P[2, 2] = q / (2 * lam)
    T = np.zeros((3, 3))
    K = np.zeros(3)
    total = 0.0
    for t in range(z.size):
        s = P[0, 0] + r
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
        x = Phi @ x + c
        P = Phi @ T @ PhiT + Q
    return total


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
