"""Loop margins at the plant input, for loops that may be open-loop unstable.

The loop is T(s) = C_L (sI - A_L)^-1 B_L with the loop closed as u = -k T u (k = 1 nominal).
Gain limits come from every k at which a closed-loop pole sits on the imaginary axis
(T(jw) = -1/k), each interval checked by its closed-loop eigenvalues, so a lower gain margin
(unstable open loop) and an upper one are both found exactly. Phase and delay margins come
from every gain crossover |T(jw)| = 1, as MATLAB's allmargin reports them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

_W_GRID = np.logspace(-5, 5, 6001)  # rad/s: every crossover of a cart-pendulum loop, 600 points a decade
MODAL_COND_MAX = 1e8  # eigenvector conditioning up to which the modal frequency response is accurate
DECAY_TOL = 1e-9  # 1/s: a closed-loop pole must lie this far left of the axis to count as stable
DC_W = 1e-9  # rad/s: the frequency standing in for w -> 0 (below every pole and zero of the loop)
REAL_TOL = 1e-6  # relative: T(DC_W) this close to the real axis is a phase crossover at w = 0
EDGE_STEP = 1e-3  # relative: a gain limit is real when the gain this far past it is unstable


@dataclass(frozen=True)
class Margins:
    """The loop margins at the plant input: gain limits (factors), phase and delay margins."""

    stable: bool
    lower_gm: float | None  # factor (< 1), None if gain may go to zero
    upper_gm: float | None  # factor (> 1), None if infinite
    pm_deg: float | None
    pm_freq: float | None  # rad/s, the crossover that sets the phase margin
    delay_margin_s: float | None
    gain_crossovers: list[float] = field(default_factory=list)  # rad/s where |T| = 1
    phase_crossovers: list[float] = field(default_factory=list)  # rad/s where T is real negative

    @property
    def lower_gm_db(self) -> float | None:
        """The lower gain limit in dB (negative), None when the gain may fall to zero."""
        return None if self.lower_gm is None else 20 * math.log10(self.lower_gm)

    @property
    def upper_gm_db(self) -> float | None:
        """The upper gain limit in dB, None when infinite."""
        return None if self.upper_gm is None else 20 * math.log10(self.upper_gm)

    def as_dict(self) -> dict:
        """Every field and the limits in dB, as plain values."""
        d = asdict(self)
        d["lower_gm_db"] = self.lower_gm_db
        d["upper_gm_db"] = self.upper_gm_db
        return d


def _freqresp(A, B, C, w: np.ndarray) -> np.ndarray:
    """C (jw I - A)^-1 B: in modal form when A is well diagonalisable (O(n) per frequency),
    else by a linear solve per frequency."""
    lam, V = np.linalg.eig(A)
    if np.linalg.cond(V) < MODAL_COND_MAX:
        c = (C @ V)[0]
        b = np.linalg.solve(V, B)[:, 0]
        return (c * b) @ (1.0 / (1j * w[None, :] - lam[:, None]))
    n = A.shape[0]
    M = 1j * w[:, None, None] * np.eye(n)[None] - A[None]
    x = np.linalg.solve(M, np.broadcast_to(B, (len(w), n, 1)))
    return (C @ x)[:, 0, 0]


def _stable(A, B, C, k: float) -> bool:
    return bool(np.max(np.linalg.eigvals(A - k * B @ C).real) < -DECAY_TOL)


def _roots(fun, w: np.ndarray, vals: np.ndarray) -> list[float]:
    """Sign changes of fun between neighbours of the grid w (vals = fun(w)), every one refined
    together by bisection until its bracket is two neighbouring floats (scipy.optimize, whose
    import alone costs a design 0.15 s, is not needed for this)."""
    i = np.nonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0)[0]
    lo, hi, sign_lo = w[i], w[i + 1], np.sign(vals[i])
    mid = 0.5 * (lo + hi)
    while np.any((mid > lo) & (mid < hi)):
        left = np.sign(fun(mid)) == sign_lo  # the root is above mid
        lo, hi = np.where(left, mid, lo), np.where(left, hi, mid)
        mid = 0.5 * (lo + hi)
    return [float(x) for x in mid]


def _gain_limits(A, B, C, T, Tw, stable: bool):
    """(lower, upper, phase crossovers): the gains k at which a closed-loop pole crosses the
    imaginary axis, around k = 1."""
    w = _W_GRID
    # phase crossovers: Im T = 0 with Re T < 0; also w -> 0
    phase_x = [x for x in _roots(lambda v: T(v).imag, w, Tw.imag) if T(np.array([x]))[0].real < 0]
    ks = [-1.0 / T(np.array([x]))[0].real for x in phase_x]
    t0 = _freqresp(A, B, C, np.array([DC_W]))[0]
    if abs(t0.imag) < REAL_TOL * max(1.0, abs(t0)) and t0.real < 0:
        ks.append(-1.0 / t0.real)
    # a real closed-loop pole through the origin: det(A - k B C) = 0
    ks = sorted(k for k in set(ks) if k > 0 and np.isfinite(k))
    lower = upper = None
    if stable:
        edges = [0.0] + ks + [math.inf]
        for lo, hi in zip(edges[:-1], edges[1:]):
            if lo <= 1.0 <= hi:
                lower = lo if lo > 0 else None
                upper = hi if np.isfinite(hi) else None
                break
        # confirm the interval edges are real stability boundaries (merge spurious ones)
        while lower is not None and _stable(A, B, C, lower * (1 - EDGE_STEP)):
            below = [k for k in ks if k < lower]
            lower = below[-1] if below else None
        while upper is not None and _stable(A, B, C, upper * (1 + EDGE_STEP)):
            above = [k for k in ks if k > upper]
            upper = above[0] if above else None
    return lower, upper, phase_x


def loop_margins(A: np.ndarray, B: np.ndarray, C: np.ndarray, gain_limits: bool = True) -> Margins:
    """Margins of the SISO loop (A, B, C) closed with unity negative feedback. With
    ``gain_limits=False`` the gain margins and phase crossovers are left out (None, []): a check
    of stability and phase margin at half the cost."""
    A, B, C = np.asarray(A, float), np.asarray(B, float).reshape(-1, 1), np.asarray(C, float).reshape(1, -1)
    stable = _stable(A, B, C, 1.0)
    lam, V = np.linalg.eig(A)
    modal = np.linalg.cond(V) < 1e8
    if modal:
        cm, bm = (C @ V)[0], np.linalg.solve(V, B)[:, 0]
        cb = cm * bm
        T = lambda w: cb @ (1.0 / (1j * np.atleast_1d(w)[None, :] - lam[:, None]))
    else:
        T = lambda w: _freqresp(A, B, C, np.atleast_1d(w))
    w = _W_GRID
    Tw = T(w)
    lower = upper = None
    phase_x = []
    if gain_limits:
        lower, upper, phase_x = _gain_limits(A, B, C, T, Tw, stable)
    gain_x = _roots(lambda v: np.abs(T(v)) - 1.0, w, np.abs(Tw) - 1.0)
    pm = pm_w = delay = None
    if stable and gain_x:
        best = None
        for wc in gain_x:
            ang = math.degrees(np.angle(T(np.array([wc]))[0]))
            phi = (180.0 + ang + 180.0) % 360.0 - 180.0  # wrap to [-180, 180)
            if best is None or abs(phi) < abs(best[0]):
                best = (phi, wc)
            lag = math.radians((180.0 + ang) % 360.0) / wc
            delay = lag if delay is None else min(delay, lag)
        pm, pm_w = abs(best[0]), best[1]
    f = lambda v: None if v is None else float(v)
    return Margins(stable, f(lower), f(upper), f(pm), f(pm_w), f(delay),
                   [float(x) for x in gain_x], [float(x) for x in phase_x])
