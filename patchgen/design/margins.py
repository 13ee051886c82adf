"""Loop margins at the plant input, for loops that may be open-loop unstable, found without a grid.

The loop is T(s) = C (sI - A)^-1 B + D with the loop closed as u = -k T u (k = 1 nominal).

- Gain crossovers |T(jw)| = 1 are the imaginary-axis eigenvalues of the Hamiltonian matrix of
  1 - T(-s) T(s) (Boyd, Balakrishnan and Kabamba 1989): every one, at any frequency.
- Phase crossovers (T(jw) real) are the imaginary-axis invariant zeros of T(s) - T(-s), an odd
  function of s: generalised eigenvalues of its system pencil.
- Gain limits come from every k at which a closed-loop pole sits on the imaginary axis
  (T(jw) = -1/k, w >= 0), each interval checked by its closed-loop eigenvalues, so a lower gain
  margin (unstable open loop) and an upper one are both found exactly.
- Phase and delay margins come from every gain crossover, as MATLAB's allmargin reports them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np
import scipy.linalg as sla

DECAY_TOL = 1e-9  # 1/s: a closed-loop pole must lie this far left of the axis to count as stable
AXIS_TOL = 1e-7  # relative: an eigenvalue this close to the imaginary axis lies on it
REAL_TOL = 1e-6  # relative: T(jw) this close to the real axis is real (a phase crossover)
UNIT_TOL = 1e-6  # relative: |T(jw)| this close to 1 is a gain crossover
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


def _response(A, B, C, D: float, w: float) -> complex:
    """T(jw); infinite at a pole of the loop on the axis."""
    n = A.shape[0]
    try:
        return complex((C @ np.linalg.solve(1j * w * np.eye(n) - A, B))[0, 0]) + D
    except np.linalg.LinAlgError:
        return complex(math.inf)


def _closed_loop(A, B, C, D: float, k: float) -> np.ndarray:
    """The closed loop's A for u = -k T u: A - k B (1 + k D)^-1 C."""
    return A - (k / (1.0 + k * D)) * (B @ C)


def _stable(A, B, C, D: float, k: float) -> bool:
    if 1.0 + k * D == 0.0:
        return False  # the loop is not well posed
    return bool(np.max(np.linalg.eigvals(_closed_loop(A, B, C, D, k)).real, initial=-math.inf) < -DECAY_TOL)


def _axis_frequencies(values: np.ndarray) -> list[float]:
    """Frequencies w >= 0 of the values on the imaginary axis, each once, ascending."""
    v = values[np.isfinite(values)]
    on = v[np.abs(v.real) <= AXIS_TOL * np.maximum(1.0, np.abs(v))]
    out: list[float] = []
    for w in sorted(abs(x.imag) for x in on):
        if not out or w - out[-1] > AXIS_TOL * max(1.0, w):
            out.append(float(w))
    return out


def gain_crossovers(A, B, C, D: float = 0.0) -> list[float]:
    """Every w >= 0 with |T(jw)| = 1, from the Hamiltonian of 1 - T(-s) T(s)."""
    if A.shape[0] == 0 or D * D == 1.0:
        return []
    r = 1.0 / (1.0 - D * D)
    H = np.block([[A + r * D * (B @ C), r * (B @ B.T)],
                  [-C.T @ C - r * D * D * (C.T @ C), -A.T - r * D * (C.T @ B.T)]])
    found = []
    for w in _axis_frequencies(np.linalg.eigvals(H)):
        t = _response(A, B, C, D, w)
        if np.isfinite(t) and abs(abs(t) - 1.0) <= UNIT_TOL:
            found.append(w)
    return found


def phase_crossovers(A, B, C, D: float = 0.0) -> list[tuple[float, float]]:
    """Every w >= 0 where T(jw) is real and finite, with that value: the imaginary-axis zeros of
    T(s) - T(-s) = C (sI - A)^-1 B + C (sI + A)^-1 B."""
    n = A.shape[0]
    if n == 0:
        return []
    Ab = sla.block_diag(A, -A)
    M = np.block([[Ab, np.vstack([B, B])], [np.hstack([C, C]), np.zeros((1, 1))]])
    N = sla.block_diag(np.eye(2 * n), np.zeros((1, 1)))
    zeros = sla.eigvals(M, N)
    found = []
    for w in sorted(set(_axis_frequencies(zeros)) | {0.0}):
        t = _response(A, B, C, D, w)
        if np.isfinite(t) and abs(t.imag) <= REAL_TOL * max(1.0, abs(t)):
            found.append((w, t.real))
    return found


def _gain_limits(A, B, C, D: float, stable: bool):
    """(lower, upper, phase crossovers): the gains k at which a closed-loop pole crosses the
    imaginary axis, around k = 1."""
    crossings = phase_crossovers(A, B, C, D)
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
        while lower is not None and _stable(A, B, C, D, lower * (1 - EDGE_STEP)):
            below = [k for k in ks if k < lower]
            lower = below[-1] if below else None
        while upper is not None and _stable(A, B, C, D, upper * (1 + EDGE_STEP)):
            above = [k for k in ks if k > upper]
            upper = above[0] if above else None
    return lower, upper, [w for w, t in crossings if t < 0 and w > 0]


def loop_margins(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: float = 0.0, gain_limits: bool = True) -> Margins:
    """Margins of the SISO loop T = (A, B, C, D) closed as u = -k T u, at k = 1.

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
        phase margin (deg) at its crossover, delay margin (s), every gain crossover and every
        phase crossover with T(jw) < 0 (rad/s).
    """
    A = np.atleast_2d(np.asarray(A, float))
    n = A.shape[0] if A.size else 0
    A = A.reshape(n, n)
    B, C, D = np.asarray(B, float).reshape(n, 1), np.asarray(C, float).reshape(1, n), float(np.asarray(D).ravel()[0]
                                                                                       if np.size(D) else 0.0)
    stable = _stable(A, B, C, D, 1.0)
    lower = upper = None
    phase_x: list[float] = []
    if gain_limits:
        lower, upper, phase_x = _gain_limits(A, B, C, D, stable)
    gain_x = gain_crossovers(A, B, C, D)
    pm = pm_w = delay = None
    if stable and gain_x:
        best = None
        for wc in gain_x:
            ang = math.degrees(np.angle(_response(A, B, C, D, wc)))
            phi = (180.0 + ang + 180.0) % 360.0 - 180.0  # wrap to [-180, 180)
            if best is None or abs(phi) < abs(best[0]):
                best = (phi, wc)
            if wc > 0:
                lag = math.radians((180.0 + ang) % 360.0) / wc
                delay = lag if delay is None else min(delay, lag)
        pm, pm_w = abs(best[0]), best[1]
    f = lambda v: None if v is None else float(v)
    return Margins(stable, f(lower), f(upper), f(pm), f(pm_w), f(delay), gain_x, phase_x)
