"""The Kalman filters whose innovations give the coast-down's and the free swing's likelihoods,
compiled (numba, cached on disk as patchgen's simulation kernels are; small matrices in plain loops).

The bench's random forces are band-limited (patchgen.profiles.bench: flat to ``bandwidth_Hz``, a
first-order process as the simulator draws it), so each filter carries the random force as a
state of its own: an Ornstein-Uhlenbeck process d' = -lam d + white noise of intensity q, with
lam = 4 x bandwidth (the equivalent noise bandwidth of a first-order process is lam / 4 Hz).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

_JIT = {"cache": True, "error_model": "numpy"}
TAYLOR_TERMS = 14  # of the matrix exponential, after scaling the matrix to a norm below 1/2
FIT_RATE_HZ = 50.0  # the filters run at most this fast: a swing of about 1 Hz or a coast of seconds loses nothing


def blocks(dt: float, *series: np.ndarray) -> tuple[float, list[np.ndarray]]:
    """The series averaged over blocks of k samples, k the most that keeps FIT_RATE_HZ (each block
    stands at its centre; the last part block is dropped), and the new step k dt. Averaging lowers
    the sensor noise k-fold in variance and leaves the slow motion as it was (a 1 Hz swing's
    amplitude by 4e-4 at 50 Hz)."""
    k = max(1, int(1.0 / (dt * FIT_RATE_HZ) + 1e-9))
    n = series[0].size // k
    return dt * k, [x[:n * k].reshape(n, k).mean(axis=1) for x in series]


@nb.njit(**_JIT)
def _mul(A, B):
    n, k, m = A.shape[0], A.shape[1], B.shape[1]
    out = np.zeros((n, m))
    for i in range(n):
        for j in range(m):
            acc = 0.0
            for c in range(k):
                acc += A[i, c] * B[c, j]
            out[i, j] = acc
    return out


@nb.njit(**_JIT)
def expm(M):
    """exp(M) by scaling, a Taylor series and squaring."""
    n = M.shape[0]
    norm = 0.0
    for i in range(n):
        row = 0.0
        for j in range(n):
            row += abs(M[i, j])
        norm = max(norm, row)
    s = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0.5 else 0
    A = M / 2.0 ** s
    out = np.eye(n)
    term = np.eye(n)
    for k in range(1, TAYLOR_TERMS + 1):
        term = _mul(term, A) / k
        out += term
    for _ in range(s):
        out = _mul(out, out)
    return out


@nb.njit(**_JIT)
def _propagate(Phi, P, T, Q):
    """P <- Phi P Phi' + Q in place, for 3 x 3 (T is scratch): the filter's covariance one step on."""
    for i in range(3):
        for j in range(3):
            T[i, j] = Phi[i, 0] * P[0, j] + Phi[i, 1] * P[1, j] + Phi[i, 2] * P[2, j]
    for i in range(3):
        for j in range(3):
            P[i, j] = T[i, 0] * Phi[j, 0] + T[i, 1] * Phi[j, 1] + T[i, 2] * Phi[j, 2] + Q[i, j]


@nb.njit(**_JIT)
def coast_nll(z, w, dt, a, fs, rho, q, lam, r1, r2, offset, z0, w0, fs_sign, nfix, pred, contrib):
    """-log-likelihood (without its constant) of a coast-down's pot (z) and tachometer (w) voltages:
    z' = rho w, w' = -a w - fs + d, d' = -lam d + noise of intensity q (the random force), read with
    noise variances r1, r2 and the tachometer's offset, from (z0, w0, d stationary). The tachometer's
    predictions go into pred, each sample's term into contrib.

    With nfix > 0 the restricted likelihood (REML): the first nfix of (z0, w0, offset, fs / fs_sign),
    which enter linearly, are integrated out (0.5 log det of their information is added), so that
    the noise levels are not biased low by fitting them."""
    M = np.zeros((5, 5))
    M[0, 1], M[1, 1], M[1, 2], M[2, 2] = rho, -a, 1.0, -lam
    M[1, 3], M[1, 4] = -fs, -fs_sign
    E = expm(M * dt)
    Phi = np.ascontiguousarray(E[:3, :3])
    V = np.zeros((6, 6))
    V[0, 1], V[1, 1], V[1, 2], V[2, 2] = -rho, a, -1.0, lam
    V[3, 3], V[4, 3], V[4, 4], V[5, 4], V[5, 5] = 0.0, rho, -a, 1.0, -lam
    V[2, 5] = q
    W = expm(V * dt)
    Q = _mul(Phi, np.ascontiguousarray(W[:3, 3:]))
    for i in range(3):
        for j in range(i):
            Q[i, j] = Q[j, i] = 0.5 * (Q[i, j] + Q[j, i])
    x = np.array([z0, w0, 0.0])
    P = np.zeros((3, 3))
    P[2, 2] = q / (2 * lam)
    X = np.zeros((3, 4))  # the state's sensitivity to (z0, w0, offset, fs)
    X[0, 0], X[1, 1] = 1.0, 1.0
    info = np.zeros((4, 4))
    E2 = np.zeros((2, 4))
    K = np.zeros((3, 2))
    T = np.zeros((3, 3))
    xn = np.zeros(3)
    total = 0.0
    for t in range(z.size):
        s11, s12, s22 = P[0, 0] + r1, P[0, 1], P[1, 1] + r2
        det = s11 * s22 - s12 * s12
        i11, i12, i22 = s22 / det, -s12 / det, s11 / det
        pred[t] = x[1] + offset
        e1, e2 = z[t] - x[0], w[t] - pred[t]
        contrib[t] = 0.5 * (math.log(det) + e1 * (i11 * e1 + i12 * e2) + e2 * (i12 * e1 + i22 * e2))
        total += contrib[t]
        for i in range(3):
            K[i, 0] = P[i, 0] * i11 + P[i, 1] * i12
            K[i, 1] = P[i, 0] * i12 + P[i, 1] * i22
            x[i] += K[i, 0] * e1 + K[i, 1] * e2
        if nfix > 0:
            for c in range(4):
                E2[0, c], E2[1, c] = X[0, c], X[1, c] + (1.0 if c == 2 else 0.0)
            for c in range(nfix):
                for c2 in range(nfix):
                    info[c, c2] += (E2[0, c] * (i11 * E2[0, c2] + i12 * E2[1, c2])
                                    + E2[1, c] * (i12 * E2[0, c2] + i22 * E2[1, c2]))
            for i in range(3):
                for c in range(4):
                    X[i, c] -= K[i, 0] * E2[0, c] + K[i, 1] * E2[1, c]
            for c in range(4):
                for i in range(3):
                    T[i, 0] = Phi[i, 0] * X[0, c] + Phi[i, 1] * X[1, c] + Phi[i, 2] * X[2, c]
                for i in range(3):
                    X[i, c] = T[i, 0] + (E[i, 4] if c == 3 else 0.0)
        for i in range(3):
            for j in range(3):
                P[i, j] -= K[i, 0] * P[0, j] + K[i, 1] * P[1, j]
        for i in range(3):
            xn[i] = E[i, 3] + Phi[i, 0] * x[0] + Phi[i, 1] * x[1] + Phi[i, 2] * x[2]
        x[0], x[1], x[2] = xn[0], xn[1], xn[2]
        _propagate(Phi, P, T, Q)
    if nfix > 0:
        block = info[:nfix, :nfix]
        if not np.all(np.isfinite(block)):
            return np.inf
        det = np.linalg.det(block)
        total += 0.5 * math.log(det) if det > 0 else np.inf
    return total


@nb.njit(**_JIT)
def _swing_rhs(phi, om, tau, beta, w2, gam, lam):
    return om, -beta * om - w2 * math.sin(phi) - gam * np.sign(om) + tau, -lam * tau


@nb.njit(**_JIT)
def swing_step(phi, om, tau, beta, w2, gam, lam, dt):
    """One RK4 step of B.5 about hanging with a Coulomb term and a random torque tau (per unit of
    inertia) that relaxes at lam: phi'' = -beta phi' - w2 sin(phi) - gam sgn(phi') + tau."""
    a1, b1, c1 = _swing_rhs(phi, om, tau, beta, w2, gam, lam)
    a2, b2, c2 = _swing_rhs(phi + 0.5 * dt * a1, om + 0.5 * dt * b1, tau + 0.5 * dt * c1, beta, w2, gam, lam)
    a3, b3, c3 = _swing_rhs(phi + 0.5 * dt * a2, om + 0.5 * dt * b2, tau + 0.5 * dt * c2, beta, w2, gam, lam)
    a4, b4, c4 = _swing_rhs(phi + dt * a3, om + dt * b3, tau + dt * c3, beta, w2, gam, lam)
    return (phi + dt / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4), om + dt / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4),
            tau + dt / 6.0 * (c1 + 2 * c2 + 2 * c3 + c4))


@nb.njit(**_JIT)
def swing_free(n, dt, beta, w2, phi0, om0, out):
    """The noise-free swing from (phi0, om0): n samples of phi into out."""
    phi, om, tau = phi0, om0, 0.0
    for t in range(n):
        out[t] = phi
        phi, om, tau = swing_step(phi, om, tau, beta, w2, 0.0, 0.0, dt)


@nb.njit(**_JIT)
def _swing_noise(beta, w2, lam, q, dt):
    """Q of one step for the torque's white noise: q int_0^dt v v' ds, v(s) = exp(F s) G with F
    linearised hanging (cos(phi) = 1: the swing's angle reaches Q only at dt^4), G = (0, 0, 1)."""
    F = np.zeros((3, 3))
    F[0, 1], F[1, 0], F[1, 1], F[1, 2], F[2, 2] = 1.0, -w2, -beta, 1.0, -lam
    c = np.zeros((5, 3))
    c[0, 2] = 1.0
    for k in range(1, 5):
        for i in range(3):
            acc = 0.0
            for j in range(3):
                acc += F[i, j] * c[k - 1, j]
            c[k, i] = acc / k
    Q = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            acc = 0.0
            for a in range(5):
                for b in range(5):
                    acc += c[a, i] * c[b, j] * dt ** (a + b + 1) / (a + b + 1)
            Q[i, j] = q * acc
    return Q


@nb.njit(**_JIT)
def swing_nll(y, dt, beta, w2, gam, lam, q, r, gain, offset, phi0, om0, pred, contrib):
    """-log-likelihood of the angle pot's voltage y = gain phi + offset + e (variance r) for the
    swing (swing_step) whose random torque is an Ornstein-Uhlenbeck process of intensity q
    (extended Kalman filter; the torque starts from its stationary spread). Predictions into
    pred, each sample's term into contrib.

    The covariance P and the transition Phi are held in scalars (registers), each entry computed
    by the same operations in the same order as the 3 x 3 products written out in _propagate."""
    x0, x1, x2 = phi0, om0, 0.0
    p00, p01, p02, p10, p11, p12, p20, p21, p22 = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, q / (2 * lam)
    Q = _swing_noise(beta, w2, lam, q, dt)
    q00, q01, q02, q10, q11, q12, q20, q21, q22 = (Q[0, 0], Q[0, 1], Q[0, 2], Q[1, 0], Q[1, 1], Q[1, 2],
                                                   Q[2, 0], Q[2, 1], Q[2, 2])
    # Phi = I + F dt + (F dt)^2 / 2 + (F dt)^3 / 6 with F = [[0, 1, 0], [a, -beta, 1], [0, 0, -lam]],
    # a = -w2 cos(phi): its entries are polynomials in a, written out (F^2, F^3 by hand)
    h1, h2, h3 = dt, dt * dt / 2.0, dt ** 3 / 6.0
    b, l_ = -beta, -lam
    bb, bl, ll, b3, l3 = b * b, b + l_, l_ * l_, b ** 3, l_ ** 3
    bbl = b * l_
    phi02 = 0.0 + 0.0 * h1 + 1.0 * h2 + bl * h3
    phi12 = 0.0 + 1.0 * h1 + bl * h2
    phi20 = 0.0 + 0.0 * h1 + 0.0 * h2 + 0.0 * h3
    phi21 = 0.0 + 0.0 * h1 + 0.0 * h2 + 0.0 * h3
    phi22 = 1.0 + l_ * h1 + ll * h2 + l3 * h3
    total = 0.0
    for t in range(y.size):
        pred[t] = gain * x0 + offset
        s = gain * gain * p00 + r
        e = y[t] - pred[t]
        contrib[t] = 0.5 * (math.log(s) + e * e / s)
        total += contrib[t]
        k0, k1, k2 = p00 * gain / s, p10 * gain / s, p20 * gain / s
        x0 += k0 * e
        x1 += k1 * e
        x2 += k2 * e
        r0, r1, r2 = gain * p00, gain * p01, gain * p02
        p00 -= k0 * r0
        p10 -= k1 * r0
        p20 -= k2 * r0
        p01 -= k0 * r1
        p11 -= k1 * r1
        p21 -= k2 * r1
        p02 -= k0 * r2
        p12 -= k1 * r2
        p22 -= k2 * r2
        a = -w2 * math.cos(x0)
        ab = a * b
        phi00 = 1.0 + 0.0 * h1 + a * h2 + ab * h3
        phi01 = 0.0 + 1.0 * h1 + b * h2 + (a + bb) * h3
        phi10 = 0.0 + a * h1 + ab * h2 + (a * a + a * b * b) * h3
        phi11 = 1.0 + b * h1 + (a + bb) * h2 + (2 * a * b + b3) * h3
        phi12_t = phi12 + (a + bb + bbl + ll) * h3
        x0, x1, x2 = swing_step(x0, x1, x2, beta, w2, gam, lam, dt)
        # P <- Phi P Phi' + Q, as _propagate
        t00 = phi00 * p00 + phi01 * p10 + phi02 * p20
        t01 = phi00 * p01 + phi01 * p11 + phi02 * p21
        t02 = phi00 * p02 + phi01 * p12 + phi02 * p22
        t10 = phi10 * p00 + phi11 * p10 + phi12_t * p20
        t11 = phi10 * p01 + phi11 * p11 + phi12_t * p21
        t12 = phi10 * p02 + phi11 * p12 + phi12_t * p22
        t20 = phi20 * p00 + phi21 * p10 + phi22 * p20
        t21 = phi20 * p01 + phi21 * p11 + phi22 * p21
        t22 = phi20 * p02 + phi21 * p12 + phi22 * p22
        p00 = t00 * phi00 + t01 * phi01 + t02 * phi02 + q00
        p01 = t00 * phi10 + t01 * phi11 + t02 * phi12_t + q01
        p02 = t00 * phi20 + t01 * phi21 + t02 * phi22 + q02
        p10 = t10 * phi00 + t11 * phi01 + t12 * phi02 + q10
        p11 = t10 * phi10 + t11 * phi11 + t12 * phi12_t + q11
        p12 = t10 * phi20 + t11 * phi21 + t12 * phi22 + q12
        p20 = t20 * phi00 + t21 * phi01 + t22 * phi02 + q20
        p21 = t20 * phi10 + t21 * phi11 + t22 * phi12_t + q21
        p22 = t20 * phi20 + t21 * phi21 + t22 * phi22 + q22
    return total


@nb.njit(**_JIT)
def swing_nll_many(y, dt, lam, gain, P, pred, contrib, out):
    """swing_nll at each row of P, (beta, w2, offset, phi0, om0, log q, log r[, gam]), into out: the
    many points of a finite-difference gradient or curvature in one call. pred and contrib hold
    the last row's."""
    for i in range(P.shape[0]):
        gam = P[i, 7] if P.shape[1] > 7 else 0.0
        out[i] = swing_nll(y, dt, P[i, 0], P[i, 1], gam, lam, math.exp(P[i, 5]), math.exp(P[i, 6]), gain, P[i, 2],
                           P[i, 3], P[i, 4], pred, contrib)


@nb.njit(**_JIT)
def coast_nll_many(z, w, dt, lam, sign, nfix, P, pred, contrib, out):
    """coast_nll at each row of P, (a, rho, z0, w0, offset, log q, log r1, log r2[, f]) with f (0
    without) the Coulomb friction in the coast's direction ``sign``, into out. pred and contrib
    hold the last row's."""
    for i in range(P.shape[0]):
        f = P[i, 8] if P.shape[1] > 8 else 0.0
        out[i] = coast_nll(z, w, dt, P[i, 0], f * sign, P[i, 1], math.exp(P[i, 5]), lam, math.exp(P[i, 6]),
                           math.exp(P[i, 7]), P[i, 4], P[i, 2], P[i, 3], sign, nfix, pred, contrib)
