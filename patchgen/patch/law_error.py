"""How far one control law is from another: the relative error of their frequency responses, at
given frequencies and its largest over a band, found exactly (no grid decides it).

A law here is a linear controller from the measurements y (s, theta, s_dot in SI) to the force u
(N), as patchgen.design.controller.Controller holds it: one row of responses G(jw), one per
measurement. The error of G against H, relative to a reference law R (the design's), is

    e(w) = |G(jw) - H(jw)| / |R(jw)|

with |.| the row's 2-norm: for thesis case 2's residualised patch 9 % at 10 rad/s, 50 % at 30 and
76 % at 100. Its largest value over a band is found as the H-infinity norm is (Boyd, Balakrishnan
and Kabamba 1989; Bruinsma and Steinbuch 1990): e(w) = g exactly where the scalar spectral function
Phi(s) = E(s) E(-s)^T - g^2 R(s) R(-s)^T, E = G - H, has a zero on the imaginary axis; between
consecutive such frequencies e - g keeps its sign, so the midpoints of the intervals above g give
a larger g, and the level rises until no interval is left.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from patchgen.design.controller import Controller

AXIS_TOL = 1e-4  # relative: a zero of Phi this near the axis is a crossing (a spurious one only splits an interval)
PEAK_RTOL = 1e-9  # the level stops rising once a midpoint beats it by less than this, relative
START_POINTS = 64  # a geometric grid over the band: the first level, its largest value
MAX_ROUNDS = 60  # each round at least doubles the digits of the level near its peak; far more than needed


@dataclass(frozen=True)
class LawError:
    """The relative error e(w) at given frequencies and its largest over a band (rad/s)."""

    band: tuple[float, float]
    at: tuple[tuple[float, float], ...]  # (w, e(w))
    peak: tuple[float, float]  # (w, e(w)) where e is largest over the band

    def as_dict(self) -> dict:
        """Plain JSON-ready values."""
        return {"band_rad_s": list(self.band), "at": [{"w_rad_s": w, "relative": e} for w, e in self.at],
                "peak": {"w_rad_s": self.peak[0], "relative": self.peak[1]}}


def difference(g: Controller, h: Controller) -> Controller:
    """G - H as one controller (the two side by side, same inputs)."""
    return Controller(g.states + h.states, sla.block_diag(g.Ac, h.Ac), np.vstack([g.Bc, h.Bc]),
                      np.hstack([g.Cc, -h.Cc]), g.Dc - h.Dc)


def response(c: Controller, w: np.ndarray) -> np.ndarray:
    """The response from each input to u at each frequency, shape (len(w), inputs)."""
    n = c.Ac.shape[0]
    out = np.empty((len(w), c.Dc.shape[1]), dtype=complex)
    for k, wk in enumerate(w):
        out[k] = (c.Dc + (c.Cc @ np.linalg.solve(1j * wk * np.eye(n) - c.Ac, c.Bc) if n else 0))[0]
    return out


def relative(e: Controller, ref: Controller, w: np.ndarray) -> np.ndarray:
    """|E(jw)| / |R(jw)| at each frequency (row 2-norms)."""
    return np.linalg.norm(response(e, w), axis=1) / np.linalg.norm(response(ref, w), axis=1)


def law_error(g: Controller, h: Controller, ref: Controller, band: tuple[float, float],
              at: tuple[float, ...]) -> LawError:
    """The error of ``g`` against ``h`` relative to ``ref``, at ``at`` and largest over ``band``.

    Parameters
    ----------
    g, h, ref : Controller
        Laws over the same inputs (SI); ``ref`` must not vanish on the band.
    band : (float, float)
        The frequencies (rad/s) the largest error is sought over, low < high.
    at : tuple of float
        Frequencies (rad/s) the error is given at.

    Returns
    -------
    LawError
        e at each of ``at``, and its largest over ``band`` with where it is.
    """
    e = difference(g, h)
    w = np.asarray(at, float)
    return LawError(band, tuple(zip(map(float, w), map(float, relative(e, ref, w)))), peak(e, ref, band))


def peak(e: Controller, ref: Controller, band: tuple[float, float]) -> tuple[float, float]:
    """(w, |E(jw)| / |R(jw)|) where the ratio is largest over ``band``: the level-set iteration of
    the module docstring from the best of START_POINTS geometric points."""
    lo, hi = band
    grid = np.geomspace(lo, hi, START_POINTS)
    vals = relative(e, ref, grid)
    k = int(np.argmax(vals))
    best_w, level = float(grid[k]), float(vals[k])
    for _ in range(MAX_ROUNDS):
        if level == 0.0:
            break
        edges = np.array(sorted({lo, hi, *crossings(e, ref, level, band)}))
        mids = np.sqrt(edges[:-1] * edges[1:])
        v = relative(e, ref, mids)
        j = int(np.argmax(v))
        if v[j] <= level * (1 + PEAK_RTOL):
            break
        best_w, level = float(mids[j]), float(v[j])
    return best_w, level


def crossings(e: Controller, ref: Controller, level: float, band: tuple[float, float]) -> list[float]:
    """Frequencies inside ``band`` where |E(jw)| = level |R(jw)|: the imaginary-axis zeros of
    Phi(s) = H(s) J H(-s)^T with H = [E, R] and J = diag(I, -level^2 I), from its system pencil."""
    m = e.Dc.shape[1]
    A = sla.block_diag(e.Ac, ref.Ac)
    B = sla.block_diag(e.Bc, ref.Bc)
    C = np.hstack([e.Cc, ref.Cc])
    D = np.hstack([e.Dc, ref.Dc])
    J = np.diag([1.0] * m + [-level * level] * m)
    # H(-s)^T = (-A^T, -C^T, B^T, D^T); J after it, then H
    A2, B2, C2, D2 = -A.T, -C.T, J @ B.T, J @ D.T
    n = A.shape[0]
    Aphi = np.block([[A, B @ C2], [np.zeros((n, n)), A2]])
    Bphi = np.vstack([B @ D2, B2])
    Cphi = np.hstack([C, D @ C2])
    Dphi = D @ D2
    M = np.block([[Aphi, Bphi], [Cphi, Dphi]])
    N = sla.block_diag(np.eye(2 * n), np.zeros((1, 1)))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = sla.eigvals(M, N)
    z = z[np.isfinite(z)]
    on = z[np.abs(z.real) <= AXIS_TOL * np.maximum(1.0, np.abs(z))]
    return sorted({float(abs(x.imag)) for x in on if band[0] < abs(x.imag) < band[1]})
