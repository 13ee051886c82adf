"""Loop margins at the plant input, for loops that may be open-loop unstable, found without a grid.

The loop is T(s) = C (sI - A)^-1 B + D with the loop closed as u = -k T u (k = 1 nominal).

- The loop is first balanced (a diagonal similarity, so that A, B and C have comparable rows and
  columns) and measured in its own frequency scale w0, so that its realisation and its units of
  time do not change the answer; every tolerance below is relative (to w0, |A|, |T| or a pole's
  own roundoff), none is in rad/s.
- Gain crossovers |T(jw)| = 1 are the imaginary-axis eigenvalues of the Hamiltonian matrix of
  1 - T(-s) T(s) (Boyd, Balakrishnan and Kabamba 1989): every one, at any frequency.
- Phase crossovers (T(jw) real) are the imaginary-axis invariant zeros of T(s) - T(-s), an odd
  function of s: generalised eigenvalues of its system pencil.
- Each crossover is refined by Newton's method on T(jw) itself, which also turns away the roots
  that only roundoff makes (near w = 0, near poles at 0, where T is a difference of roundoff).
- Gain limits come from every k at which a closed-loop pole sits on the imaginary axis
  (T(jw) = -1/k, w >= 0), each interval checked by its closed-loop eigenvalues, so a lower gain
  margin (unstable open loop) and an upper one are both found exactly. A closed loop is stable
  when every pole lies left of the axis by more than roundoff may have moved it: a pole on the
  axis never is, a slow pole of a slow loop is.
- Phase and delay margins come from every gain crossover, as MATLAB's allmargin reports them.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.linalg as sla

AXIS_TOL = 1e-7  # relative to max(|v|, w0): an eigenvalue this close to the imaginary axis lies on it
UNIT_TOL = 1e-6  # relative: |T(0)| this close to 1 touches 1 at w = 0 (see _gain_crossovers)
EDGE_STEP = 1e-3  # relative: a gain limit is real when the gain this far past it is unstable
NEWTON_STEPS = 3  # at most: Newton's method on T(jw) takes a crossover from its eigenvalue (~1e-12 off
# on a well-scaled loop, ~1e-6 on an ill-conditioned realisation) to roundoff in two
NEWTON_TOL = 1e-3  # relative: a crossover's next Newton step is this small (roundoff in T leaves ~1e-5 on
# an ill-conditioned realisation), a root found only by roundoff steps by half its w or more
NEWTON_REACH = 0.5  # relative: a Newton walk that takes w down by this much heads for the root at w = 0
ROUNDOFF = 1e-15  # relative roundoff in a sum of terms of unit size (a few times the float epsilon)
POLE_SPLIT = 3.0  # times a pole's own roundoff (ROUNDOFF |A| times its condition number): the reach within
# which it may lie on the axis or at 0 (an integrator split by roundoff lies within 0.1 of it, every stable
# pole of the shipped loops over 800 times beyond it)
SPLIT_MAX = 1e-5  # relative to |A|: roundoff moves a pole by at most this, splitting a triple one by up
# to eps^(1/3) ~ 1e-5 (a double pole left unsplit has a condition number of 1e16 or infinite)
POLE_REACH = 100.0  # T(jw) near poles at 0 split by roundoff crosses the real axis at a few times their size
ROOT_TOL = 1e-4  # a crossover's residual after Newton's method: log |T| (gain) or arg T off the real axis
# (phase, rad); roundoff in T leaves ~1e-5 on an ill-conditioned realisation, a pole of the loop far more


@dataclass(frozen=True)
class Margins:
    """The loop margins at the plant input: gain limits (factors), phase and delay margins."""

    stable: bool
    lower_gm: float | None  # factor (< 1), None if gain may go to zero
    upper_gm: float | None  # factor (> 1), None if infinite
    pm_deg: float | None
    pm_freq: float | None  # rad/s, the crossover that sets the phase margin
    delay_margin_s: float | None
    gain_crossovers: list[float] = field(default_factory=list)  # rad/s where |T| crosses 1
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


@dataclass(frozen=True)
class _Loop:
    """T(w0 s) = C (sI - A)^-1 B + D: the loop balanced, with frequencies in units of w0 (rad/s)."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: float
    w0: float


def _normalised(A, B, C, D=0.0) -> _Loop:
    """The loop (A, B, C, D) balanced and scaled to its own frequency w0, without roundoff.

    [[A, B], [C, 0]] is balanced by powers of two (its last row and column kept, so T is
    unchanged), and w0, a power of four near max(|A|, |B| |C|), divides A and B C: a loop
    realised in companion form or in other units of time then meets the same eigenvalue
    problems, up to roundoff, as a well-scaled realisation, and w0 is the scale of their
    roundoff (eigenvalues are found to about 1e-16 w0).
    """
    A = np.atleast_2d(np.asarray(A, float))
    n = A.shape[0] if A.size else 0
    A, B, C = A.reshape(n, n), np.asarray(B, float).reshape(n, 1), np.asarray(C, float).reshape(1, n)
    D = float(np.asarray(D).ravel()[0]) if np.size(D) else 0.0
    if n == 0:
        return _Loop(A, B, C, D, 1.0)
    _, (s, _) = sla.matrix_balance(np.block([[A, B], [C, np.zeros((1, 1))]]), permute=False, separate=True)
    d = s[:n] / s[n]
    A, B, C = A * d / d[:, None], B / d[:, None], C * d
    size = max(np.linalg.norm(A, 1), np.linalg.norm(B) * np.linalg.norm(C))
    w0 = 4.0 ** round(math.log(size, 4)) if size > 0 else 1.0
    return _Loop(A / w0, B / math.sqrt(w0), C / math.sqrt(w0), D, w0)


def _response(loop: _Loop, w: float) -> complex:
    """T(j w w0); infinite at a pole of the loop on the axis."""
    n = loop.A.shape[0]
    try:
        return complex((loop.C @ np.linalg.solve(1j * w * np.eye(n) - loop.A, loop.B))[0, 0]) + loop.D
    except np.linalg.LinAlgError:
        return complex(math.inf)


def _log_response(loop: _Loop, w: float) -> tuple[complex, complex, float]:
    """log T(j w w0), its derivative in w (d/dw T(jw) = -j C (jwI - A)^-2 B, over T) and the
    roundoff in T relative to |T| (ROUNDOFF times the terms of C x + D over their sum); infinite at
    a pole and at a zero of T."""
    M = 1j * w * np.eye(loop.A.shape[0]) - loop.A
    try:
        x = np.linalg.solve(M, loop.B)
        t = complex((loop.C @ x)[0, 0]) + loop.D
        slope = -1j * complex((loop.C @ np.linalg.solve(M, x))[0, 0])
    except np.linalg.LinAlgError:
        return complex(math.inf), 0j, math.inf
    if not np.isfinite(t) or t == 0:
        return complex(math.inf), 0j, math.inf
    return cmath.log(t), slope / t, ROUNDOFF * (float((np.abs(loop.C) @ np.abs(x))[0, 0]) + abs(loop.D)) / abs(t)


def _gain_part(log_t: complex, slope: complex) -> tuple[float, float]:
    """log |T| and its derivative: zero where |T| = 1."""
    return log_t.real, slope.real


def _phase_part(log_t: complex, slope: complex) -> tuple[float, float]:
    """arg T off the real axis (in [-pi/2, pi/2]) and its derivative: zero where T is real."""
    return log_t.imag - math.pi * round(log_t.imag / math.pi), slope.imag


def _newton(loop: _Loop, w: float, part) -> float | None:
    """The root w > 0 of part(log T(jw)) that Newton's method reaches from w, each step taken only
    while it shrinks the residual; None unless the residual is within ROOT_TOL, the next step
    within NEWTON_TOL of w, roundoff in T moves the root by less than that, and w has not fallen
    by NEWTON_REACH.

    A root found only by roundoff is not reached: split off a root at w = 0 or off a pole of the
    loop at 0 (which T(s) - T(-s) shares with T(-s)), Newton's method walks to w = 0; made by
    Markov parameters that are roundoff (C B of a loop that falls as 1/w^2), T there is the
    difference of terms 1e10 times its size and its phase hardly moves.
    """
    start = w
    log_t, slope, noise = _log_response(loop, w)
    r, dr = part(log_t, slope)
    for _ in range(NEWTON_STEPS):
        if not (math.isfinite(r) and math.isfinite(dr)) or dr == 0.0 or r / dr >= w:
            break
        log_t, slope, noise_next = _log_response(loop, w - r / dr)
        r_next, dr_next = part(log_t, slope)
        if not abs(r_next) < abs(r):
            break
        w, r, dr, noise = w - r / dr, r_next, dr_next, noise_next
    converged = (math.isfinite(dr) and dr != 0.0 and abs(r) <= ROOT_TOL
                 and max(abs(r), noise) <= NEWTON_TOL * abs(w * dr))
    return w if converged and w > (1.0 - NEWTON_REACH) * start else None


def _poles(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The eigenvalues of A and how far roundoff may have moved each: POLE_SPLIT times ROUNDOFF |A|
    over the cosine of its left and right eigenvectors (its condition number), at most SPLIT_MAX |A|.
    A pole split off a multiple one has a condition number to match: it lies within 0.1 of its
    reach; one of a multiple pole found unsplit has an infinite condition number, hence the cap."""
    p, left, right = sla.eig(A, left=True, right=True)
    with np.errstate(divide="ignore"):
        cond = 1.0 / np.abs(np.sum(left.conj() * right, axis=0))
    return p, np.linalg.norm(A, 1) * np.minimum(POLE_SPLIT * ROUNDOFF * cond, SPLIT_MAX)


def _stable(loop: _Loop, k: float) -> bool:
    """Whether u = -k T u is stable: every closed-loop pole left of the axis by more than roundoff
    may have moved it, so a pole on the axis (an integrator left in the loop) is never counted
    stable, in any realisation and at any scale, and a slow pole of a slow loop is."""
    if 1.0 + k * loop.D == 0.0:
        return False  # the loop is not well posed
    poles, reach = _poles(loop.A - (k / (1.0 + k * loop.D)) * (loop.B @ loop.C))
    return bool(np.all(poles.real < -reach))


def _distinct(ws) -> list[float]:
    """The frequencies ascending, each once: those within AXIS_TOL of each other (relative) are one."""
    out: list[float] = []
    for w in sorted(ws):
        if not out or w - out[-1] > AXIS_TOL * w:
            out.append(float(w))
    return out


def _axis_frequencies(values: np.ndarray) -> list[float]:
    """Frequencies w >= 0 (units of w0) of the values on the imaginary axis, each once, ascending."""
    v = values[np.isfinite(values)]
    return _distinct(abs(x.imag) for x in v[np.abs(v.real) <= AXIS_TOL * np.maximum(1.0, np.abs(v))])


def _gain_crossovers(loop: _Loop) -> list[float]:
    """Every w > 0 (units of w0) where |T(jw)| crosses 1: the imaginary-axis eigenvalues of the
    Hamiltonian of 1 - T(-s) T(s), each refined by Newton's method on log |T(jw)|.

    |T(jw)| is even in w, so where |T(0)| = 1 it only touches 1 at w = 0: that is no crossover, nor
    is a root with |T| within UNIT_TOL of 1 at 0 and half way to it (1 touched, not left).
    """
    A, B, C, D = loop.A, loop.B, loop.C, loop.D
    if A.shape[0] == 0 or D * D == 1.0:
        return []
    r = 1.0 / (1.0 - D * D)
    H = np.block([[A + r * D * (B @ C), r * (B @ B.T)],
                  [-C.T @ C - r * D * D * (C.T @ C), -A.T - r * D * (C.T @ B.T)]])
    unit = lambda w: abs(abs(_response(loop, w)) - 1.0) <= UNIT_TOL
    found = (_newton(loop, w, _gain_part) for w in _axis_frequencies(np.linalg.eigvals(H)))
    return _distinct(w for w in found if w is not None and not (unit(0.0) and unit(0.5 * w)))


def _zero_poles(A: np.ndarray) -> float | None:
    """The size of the loop's poles at 0 (the integrators, split by roundoff), None if it has none.

    A pole p is at 0 when |p| is within the reach of roundoff (see _poles): a size relative to w0
    alone would take a slow pole of an ill-conditioned realisation (|A| 1e7 times the pole) for an
    integrator, or miss a double integrator split to 1e-8 |A|.
    """
    p, reach = _poles(A)
    at_zero = np.abs(p) <= reach
    return float(np.abs(p[at_zero]).max()) if at_zero.any() else None


def _phase_crossovers(loop: _Loop) -> list[tuple[float, float]]:
    """Every w >= 0 (units of w0) where T(jw) is real and finite, with that value: the imaginary-axis
    zeros of T(s) - T(-s) = C (sI - A)^-1 B + C (sI + A)^-1 B, each refined by Newton's method on
    arg T, and w = 0.

    Where the loop has poles at 0 (see _zero_poles), w = 0 is not one, nor is a crossing within
    POLE_REACH times their size: there T(jw) crosses the real axis only because roundoff split them.
    """
    A, B, C = loop.A, loop.B, loop.C
    n = A.shape[0]
    if n == 0:
        return []
    M = np.block([[sla.block_diag(A, -A), np.vstack([B, B])], [np.hstack([C, C]), np.zeros((1, 1))]])
    zeros = sla.eigvals(M, sla.block_diag(np.eye(2 * n), np.zeros((1, 1))))
    found = [_newton(loop, w, _phase_part) for w in _axis_frequencies(zeros) if w > 0]
    split = _zero_poles(A)
    out = []
    for w in _distinct(([0.0] if split is None else []) + [w for w in found if w is not None
                                                            and (split is None or w > POLE_REACH * split)]):
        t = _response(loop, w)
        if np.isfinite(t):
            out.append((w, t.real))
    return out


def gain_crossovers(A, B, C, D: float = 0.0) -> list[float]:
    """Every w > 0 (rad/s) where |T(jw)| crosses 1 (see _gain_crossovers for w = 0)."""
    loop = _normalised(A, B, C, D)
    return [w * loop.w0 for w in _gain_crossovers(loop)]


def phase_crossovers(A, B, C, D: float = 0.0) -> list[tuple[float, float]]:
    """Every w >= 0 (rad/s) where T(jw) is real and finite, with that value."""
    loop = _normalised(A, B, C, D)
    return [(w * loop.w0, t) for w, t in _phase_crossovers(loop)]


def _gain_limits(loop: _Loop, stable: bool):
    """(lower, upper, phase crossovers in units of w0): the gains k at which a closed-loop pole
    crosses the imaginary axis, around k = 1."""
    crossings = _phase_crossovers(loop)
    ks = sorted({-1.0 / t for _, t in crossings if t < 0 and math.isfinite(-1.0 / t)})
    lower = upper = None
    if stable:
        edges = [0.0] + ks + [math.inf]
        for lo, hi in zip(edges[:-1], edges[1:]):
            if lo <= 1.0 <= hi:
                lower = lo if lo > 0 else None
                upper = hi if np.isfinite(hi) else None
                break
        # keep only real stability boundaries (a tangency of T to the axis is none)
        while lower is not None and _stable(loop, lower * (1 - EDGE_STEP)):
            below = [k for k in ks if k < lower]
            lower = below[-1] if below else None
        while upper is not None and _stable(loop, upper * (1 + EDGE_STEP)):
            above = [k for k in ks if k > upper]
            upper = above[0] if above else None
    return lower, upper, [w for w, t in crossings if t < 0 and w > 0]


def loop_margins(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: float = 0.0, gain_limits: bool = True) -> Margins:
    """Margins of the SISO loop T = (A, B, C, D) closed as u = -k T u, at k = 1.

    The answer does not depend on the realisation: any similarity transform of (A, B, C), or
    the same loop in other units of time, gives the same margins up to roundoff.

    Parameters
    ----------
    A, B, C : array_like
        The open loop broken at the plant input (n x n, n x 1, 1 x n).
    D : float
        Its feed-through (0 for a strictly proper loop).
    gain_limits : bool
        With False the gain margins and phase crossovers are left out (None, []): a check of
        stability and phase margin at half the cost.

    Returns
    -------
    Margins
        Lower and upper gain limits as factors (None where the gain may go to 0 or to infinity),
        phase margin (deg) at its crossover, delay margin (s), every gain crossover (w > 0: where
        |T(0)| = 1 the touch at w = 0 is not one) and every phase crossover with T(jw) < 0 (rad/s).
    """
    loop = _normalised(A, B, C, D)
    stable = _stable(loop, 1.0)
    lower = upper = None
    phase_x: list[float] = []
    if gain_limits:
        lower, upper, phase_x = _gain_limits(loop, stable)
    gain_x = _gain_crossovers(loop)
    pm = pm_w = delay = None
    if stable and gain_x:
        best = None
        for wc in gain_x:
            ang = math.degrees(np.angle(_response(loop, wc)))
            phi = (180.0 + ang + 180.0) % 360.0 - 180.0  # wrap to [-180, 180)
            if best is None or abs(phi) < abs(best[0]):
                best = (phi, wc)
            lag = math.radians((180.0 + ang) % 360.0) / (wc * loop.w0)
            delay = lag if delay is None else min(delay, lag)
        pm, pm_w = abs(best[0]), best[1] * loop.w0
    f = lambda v: None if v is None else float(v)
    w0 = loop.w0
    return Margins(stable, f(lower), f(upper), f(pm), f(pm_w), f(delay), [w * w0 for w in gain_x],
                   [w * w0 for w in phase_x])
