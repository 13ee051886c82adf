"""The actuator fit's start: a grid over the lag tau and the dead zone, the gain (and the zero's
gain) and the gauge's zero by linear least squares in each cell, the cell of least residual
taken.

The grid is searched cell by cell with numpy's least squares (``cell``). Most cells are far from
the least, and a compiled pass (``approximate_rss``: the normal equations' coefficients and sum of
squares, with a bound on its rounding) says so for all of them at once; only the cells it cannot
tell from the least are searched cell by cell, in grid order, so that the start is the one the
full search gives.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from patchgen.identify.lsq import FitError

MIN_TAU_S = 1e-4  # s: the fit's floor for the lag (a shorter one is a gain at any sample rate used)
GRID_TAUS, GRID_DEAD_ZONES = 18, 14  # lags from 0.2 ms to 5 s, dead zones to 90 % of the command
TIE = 1e-6  # relative: cells this close to the least sum of squares are searched cell by cell
CONDITION = 1e8  # so is a cell whose normal equations (columns scaled to one) are worse conditioned


def dead_zone(u: np.ndarray, half_width: float) -> np.ndarray:
    """The command after the dead zone: u - w above w, u + w below -w, 0 between."""
    return np.where(u > half_width, u - half_width, np.where(u < -half_width, u + half_width, 0.0))


@nb.njit(cache=True)
def dead_value(x, half_width):
    """dead_zone of one value."""
    return x - half_width if x > half_width else (x + half_width if x < -half_width else 0.0)


def lag_state(v: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """The lag 1 / (tau s + 1) of v held over each interval, sampled before each update, from rest at v[0]."""
    out = np.empty(len(v))
    lag_filter(np.ascontiguousarray(v, dtype=float), np.exp(-dt / tau), out)
    return out


@nb.njit(cache=True)
def lag_filter(v, a, out):
    """scipy.signal.lfilter([0, 1 - a], [1, -a], v, zi=[v[0]]) into out, its transposed direct form
    operation for operation (the same bits, without its call's overhead)."""
    b0, b1, a1 = 0.0, 1.0 - a, -a
    z = v[0]
    for k in range(v.size):
        out[k] = z + b0 * v[k]
        z = v[k] * b1 - out[k] * a1


def previous(v: np.ndarray) -> np.ndarray:
    """v delayed one sample (the command held over the interval that ends at each sample)."""
    return np.concatenate([v[:1], v[:-1]])


def cell(v: np.ndarray, f: np.ndarray, dt: float, tau: float, with_zero: bool) -> tuple[float, np.ndarray]:
    """The residual sum of squares and the coefficients (K_U[, K_Z], F0) of one cell, v the command
    after its dead zone."""
    y = lag_state(v, dt, tau)
    cols = [y, (previous(v) - y) / tau, np.ones_like(y)] if with_zero else [y, np.ones_like(y)]
    A = np.column_stack(cols)
    c, *_ = np.linalg.lstsq(A, f, rcond=None)
    return float(np.sum((A @ c - f) ** 2)), c


@nb.njit(cache=True)
def _columns(V, f, a, tau, with_zero, G, b, ff):
    """For each row v of V: the cell's columns x = (the lag's state y, (previous v - y) / tau with
    the zero, 1) run sample by sample, their products into G, with f into b, and f'f into ff."""
    for r in range(V.shape[0]):
        y, prev = V[r, 0], V[r, 0]
        syy = syz = sy = szz = sz = syf = szf = sf = sff = 0.0
        for s in range(f.size):
            z = (prev - y) / tau if with_zero else 0.0
            syy += y * y
            syz += y * z
            sy += y
            szz += z * z
            sz += z
            syf += y * f[s]
            szf += z * f[s]
            sf += f[s]
            sff += f[s] * f[s]
            prev = V[r, s]
            y = a * y + (1.0 - a) * prev
        ff[r] = sff
        if with_zero:
            G[r, 0, 0], G[r, 0, 1], G[r, 0, 2], b[r, 0] = syy, syz, sy, syf
            G[r, 1, 0], G[r, 1, 1], G[r, 1, 2], b[r, 1] = syz, szz, sz, szf
            G[r, 2, 0], G[r, 2, 1], G[r, 2, 2], b[r, 2] = sy, sz, f.size, sf
        else:
            G[r, 0, 0], G[r, 0, 1], b[r, 0] = syy, sy, syf
            G[r, 1, 0], G[r, 1, 1], b[r, 1] = sy, f.size, sf


def approximate_rss(V: np.ndarray, f: np.ndarray, dt: float, tau: float, with_zero: bool
                    ) -> tuple[np.ndarray, np.ndarray]:
    """About ``cell``'s sum of squares for each row of V at once, and a bound on its rounding.

    The coefficients c solve the normal equations (columns scaled to one); the sum of squares at
    them, f'f - 2 c'b + c'G c, is never below the least-squares minimum and above it by the
    square of their rounding. Its own rounding, the sums' over n samples and the expansion's, is
    within 2 n eps (f'f + 2 sum |c_i| sqrt(G_ii f'f) + (sum |c_i| sqrt(G_ii))^2) (Cauchy-Schwarz
    for the sums of |x_i f| and |x_i x_j|). inf where the normal equations are too
    ill-conditioned to say."""
    k = 3 if with_zero else 2
    G, b, ff = np.zeros((V.shape[0], k, k)), np.zeros((V.shape[0], k)), np.zeros(V.shape[0])
    _columns(V, f, math.exp(-dt / tau), tau, with_zero, G, b, ff)
    d = np.sqrt(np.maximum(np.einsum("rii->ri", G), 1e-300))
    scaled = G / (d[:, :, None] * d[:, None, :])
    coef = (np.linalg.pinv(scaled) @ (b / d)[:, :, None])[:, :, 0] / d
    rss = ff - 2 * np.einsum("ri,ri->r", coef, b) + np.einsum("ri,rij,rj->r", coef, G, coef)
    reach = np.einsum("ri,ri->r", np.abs(coef), d)
    gamma = 2 * f.size * np.finfo(float).eps
    bound = gamma * (ff + 2 * reach * np.sqrt(ff) + reach ** 2)
    ok = np.linalg.cond(scaled) < CONDITION
    return np.where(ok, rss, np.inf), np.where(ok, bound, np.inf)


def grid_start(u: np.ndarray, f: np.ndarray, dt: float, with_zero: bool) -> np.ndarray:
    """(K_U, K_Z, tau, dz, F0) of the grid's best cell: the first in grid order (lags, then dead
    zones) of least residual."""
    umax = float(np.max(np.abs(u)))
    taus, dzs = np.geomspace(2 * MIN_TAU_S, 5.0, GRID_TAUS), np.linspace(0, 0.9 * umax, GRID_DEAD_ZONES)
    V = np.array([dead_zone(u, dz) for dz in dzs])
    approx, bound = np.array([approximate_rss(V, f, dt, tau, with_zero) for tau in taus]).transpose(1, 0, 2)
    finite = np.isfinite(approx)
    high = np.min((approx + bound)[finite]) if np.any(finite) else np.inf
    best = (np.inf, None)
    for i, j in zip(*np.nonzero(~finite | (approx - bound <= high * (1 + TIE)))):
        rss, c = cell(V[j], f, dt, taus[i], with_zero)
        if rss < best[0]:
            best = (rss, (c[0], c[1] if with_zero else 0.0, taus[i], dzs[j], c[-1]))
    if best[1] is None:
        raise FitError("no start for the fit: the force is not finite against any lag and dead zone")
    return np.array(best[1])
