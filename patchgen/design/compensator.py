"""The compensator as one LTI system, its minimal realisation and its reduced orders.

A Kalman compensator is built as an estimator of the physical states followed by state feedback,
plus the integral states (patchgen.design.lqg). As a law it is one system from the measurements
y = (s, theta, s_dot) to the force u, and that is what a machine has to realise. This module gives:

- the integral part split off: the integral states' poles (at the spec's tiny leaks, taken as 0,
  as the patch does) decoupled from the rest by a Sylvester equation; however many integral
  states the design has, their law is u_I = (R / s) y, one integrator of a weighted sum of the
  measurements (R = C2 B2, a 1 x m row);
- the rest, stable, in balanced coordinates (Hankel singular values; the minimal realisation
  drops the states whose value is rounding noise);
- orders below the minimal one: states faster than the machine can patch are residualised first
  (their steady state, exact at DC), then balanced truncation or singular perturbation of the
  remaining states, the integral part always kept.

Everything here is in SI units (m, rad, m/s in; N out); patchgen.patch.compensator_forms turns a
compensator into machine volts.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from patchgen.design.controller import Controller
from patchgen.design.lqg import Design, loop_with_controller
from patchgen.design.margins import Margins, loop_margins

# A compensator pole this close to 0 (rad/s) belongs to the integral states: the spec's leaks are
# 1e-5 to 2e-5 1/s and the patch wires pure integrators (patchgen.patch.realization).
INTEGRATOR_POLE = 1e-3
# A Hankel singular value below this fraction of the largest is a state nothing moves or nothing
# sees (rounding of the Riccati and Lyapunov solutions, about 1e-16 times a few condition numbers).
MINIMAL_HSV = 1e-9


@dataclass(frozen=True)
class Compensator:
    """u = x_I + C x + D y with x_I' = R y (the integral part) and x' = A x + B y (the rest), SI.

    ``R`` is None when the design has no integral states. ``hsv`` are the Hankel singular values
    of the minimal stable part, largest first; ``method`` says how this order was reached.
    """

    inputs: tuple[str, ...]
    R: np.ndarray | None  # 1 x m
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    hsv: np.ndarray
    method: str = "minimal"
    unstable: int = 0  # leading states of A that are the compensator's own unstable modes (kept, never reduced)

    @property
    def order(self) -> int:
        """States in all: the stable part's and one integrator for the integral part."""
        return self.A.shape[0] + (0 if self.R is None else 1)

    def controller(self) -> Controller:
        """As a :class:`Controller` (integral state first, named ``int``; the rest ``c1``...)."""
        n = self.A.shape[0]
        names = tuple(f"c{i + 1}" for i in range(n))
        if self.R is None:
            return Controller(names, self.A, self.B, self.C, self.D)
        A = sla.block_diag(np.zeros((1, 1)), self.A)
        B = np.vstack([self.R, self.B])
        C = np.hstack([np.ones((1, 1)), self.C])
        return Controller(("int",) + names, A, B, C, self.D)

    def freqresp(self, w: np.ndarray) -> np.ndarray:
        """Complex gain from each measurement to u at each frequency (rad/s), shape (len(w), m)."""
        n = self.A.shape[0]
        out = np.empty((len(w), len(self.inputs)), dtype=complex)
        for k, wk in enumerate(w):
            s = 1j * wk
            G = self.D + (self.C @ np.linalg.solve(s * np.eye(n) - self.A, self.B) if n else 0)
            if self.R is not None:
                G = G + self.R / s
            out[k] = G[0]
        return out


def compensator(design: Design) -> Compensator:
    """The design's compensator (u from y, SI) with its integral part split off, minimal.

    Parameters
    ----------
    design : Design
        A design with a controller (a Kalman estimator, say).

    Returns
    -------
    Compensator
        The stable part in balanced coordinates, its Hankel singular values, the integral part's
        row R.
    """
    ctl = design.controller
    if ctl is None:
        raise ValueError(f"{design.spec.name} has no compensator (plain state feedback)")
    ints = [i for i, s in enumerate(ctl.states) if s.startswith("int_")]
    rest = [i for i in range(len(ctl.states)) if i not in ints]
    A, B, C, D = ctl.Ac, ctl.Bc, ctl.Cc, ctl.Dc
    R = None
    if ints:
        A11, A12, A21, A22 = (A[np.ix_(rest, rest)], A[np.ix_(rest, ints)], A[np.ix_(ints, rest)],
                              A[np.ix_(ints, ints)])
        if np.abs(A21).max(initial=0.0) > 0:
            raise ValueError("the integral states are not integrators of the measurements alone")
        for name in (ctl.states[i] for i in ints):
            leak = getattr(design.spec.integrators, f"{name}_leak")
            if leak > INTEGRATOR_POLE:
                raise design.spec.error(f"integrators.{name}_leak", f"a leak of {leak:g} 1/s: the compensator's "
                                        f"integral part is patched as pure integrators, which it is only up to "
                                        f"{INTEGRATOR_POLE:g} 1/s (realization = 'states' leaves a leak out)")
        # z = x1 + X x2 decouples them: A11 X - X A22 = A12
        X = sla.solve_sylvester(A11, -A22, A12)
        B1 = B[rest] + X @ B[ints]
        C2 = C[:, ints] - C[:, rest] @ X
        R = C2 @ B[ints]
        A, B, C = A11, B1, C[:, rest]
    A, B, C, nu, hsv = _unstable_then_balanced(A, B, C, lambda re, im: re >= 0)
    return Compensator(tuple(design.model.measured), R, A, B, C, D.copy(), hsv, unstable=nu)


def _split(A: np.ndarray, B: np.ndarray, C: np.ndarray, first):
    """Coordinates in which A is block diagonal, the modes ``first(re, im)`` selects leading
    (ordered real Schur form, then a Sylvester equation for the coupling); returns (A, B, C, n_first)."""
    Tq, Z, n1 = sla.schur(A, output="real", sort=first)
    A, B, C = Tq, Z.T @ B, C @ Z
    if n1 in (0, A.shape[0]):
        return A, B, C, n1
    k = np.arange(A.shape[0]) < n1
    # x = Tm z with Tm = [[I, X], [0, I]] makes A block diagonal when A11 X - X A22 = -A12
    X = sla.solve_sylvester(A[np.ix_(k, k)], -A[np.ix_(~k, ~k)], -A[np.ix_(k, ~k)])
    Tm = np.eye(A.shape[0])
    Tm[np.ix_(k, ~k)] = X
    Ti = np.linalg.inv(Tm)
    return Ti @ A @ Tm, Ti @ B, C @ Tm, n1


def _unstable_then_balanced(A, B, C, unstable):
    """The modes ``unstable`` selects kept as they are, first; the rest balanced and minimal."""
    if A.shape[0] == 0:
        return A, B, C, 0, np.zeros(0)
    A, B, C, nu = _split(A, B, C, unstable)
    Ab, Bb, Cb, hsv = balanced(A[nu:, nu:], B[nu:], C[:, nu:])
    keep = int(np.sum(hsv > MINIMAL_HSV * hsv[0])) if len(hsv) else 0
    A = sla.block_diag(A[:nu, :nu], Ab[:keep, :keep])
    return A, np.vstack([B[:nu], Bb[:keep]]), np.hstack([C[:, :nu], Cb[:, :keep]]), nu, hsv[:keep]


def balanced(A: np.ndarray, B: np.ndarray, C: np.ndarray):
    """A stable system in balanced coordinates (square-root method), with its Hankel singular values.

    Returns
    -------
    (A, B, C, hsv)
        Gramians equal and diagonal in the returned coordinates; states whose singular value is
        zero to rounding are dropped (their coordinates cannot be inverted).
    """
    if A.shape[0] == 0:
        return A, B, C, np.zeros(0)
    if np.max(np.linalg.eigvals(A).real) >= 0:
        raise ValueError("balanced coordinates need a stable system")
    Wc = sla.solve_continuous_lyapunov(A, -B @ B.T)
    Wo = sla.solve_continuous_lyapunov(A.T, -C.T @ C)
    Lc, Lo = _sqrt_psd(Wc), _sqrt_psd(Wo)
    U, s, Vt = np.linalg.svd(Lo.T @ Lc)
    keep = s > MINIMAL_HSV * s[0] * 1e-3
    U, s, Vt = U[:, keep], s[keep], Vt[keep]
    T = Lc @ Vt.T / np.sqrt(s)
    Ti = (U / np.sqrt(s)).T @ Lo.T
    return Ti @ A @ T, Ti @ B, C @ T, s


def _sqrt_psd(W: np.ndarray) -> np.ndarray:
    """L with L L^T = W for a symmetric positive semi-definite W (negative rounding set to 0)."""
    lam, Q = np.linalg.eigh((W + W.T) / 2)
    return Q * np.sqrt(np.clip(lam, 0.0, None))


def residualise(A: np.ndarray, B: np.ndarray, C: np.ndarray, D: np.ndarray, keep: np.ndarray):
    """Singular perturbation: the states not in ``keep`` at their steady state (exact at DC)."""
    k = np.asarray(keep, dtype=bool)
    A11, A12, A21, A22 = A[np.ix_(k, k)], A[np.ix_(k, ~k)], A[np.ix_(~k, k)], A[np.ix_(~k, ~k)]
    X = np.linalg.solve(A22, np.hstack([A21, B[~k]]))
    n = int(k.sum())
    return (A11 - A12 @ X[:, :n], B[k] - A12 @ X[:, n:], C[:, k] - C[:, ~k] @ X[:, :n],
            D - C[:, ~k] @ X[:, n:])


def without_fast_modes(c: Compensator, fastest: float) -> Compensator:
    """The compensator with every mode faster than ``fastest`` rad/s at its steady state.

    A mode faster than the machine can patch (its rate is a coefficient no input reaches) is
    residualised: its contribution becomes a direct term, exact at DC, off by about w/|pole| at
    frequency w. The rest is balanced again.
    """
    lam = np.linalg.eigvals(c.A)
    if (np.abs(lam) <= fastest).all():
        return c
    A, B, C, ns = _split(c.A, c.B, c.C, lambda re, im: abs(complex(re, im)) <= fastest)
    keep = np.arange(A.shape[0]) < ns
    A2, B2, C2, D2 = residualise(A, B, C, c.D, keep)
    A2, B2, C2, nu, hsv = _unstable_then_balanced(A2, B2, C2, lambda re, im: re >= 0)
    return Compensator(c.inputs, c.R, A2, B2, C2, D2, hsv, f"{c.method}, modes above {fastest:g} rad/s "
                       "residualised", unstable=nu)


def reduced(c: Compensator, order: int, method: str = "truncate") -> Compensator:
    """The compensator at ``order`` states in all (the integral part's one among them).

    Parameters
    ----------
    c : Compensator
        In balanced coordinates (as :func:`compensator` and :func:`without_fast_modes` give).
    order : int
        States wanted, the integral state included.
    method : {"truncate", "residualise"}
        Balanced truncation (exact at infinite frequency) or balanced singular perturbation
        (exact at DC).

    Returns
    -------
    Compensator
        The reduced law; ``c`` itself when ``order`` is not below its own.
    """
    r = order - (0 if c.R is None else 1) - c.unstable
    if r < 0:
        raise ValueError(f"order {order} drops the integral part or an unstable mode")
    n = c.A.shape[0] - c.unstable
    if r >= n:
        return c
    keep = np.arange(c.A.shape[0]) < c.unstable + r
    if method == "truncate":
        A, B, C, D = c.A[np.ix_(keep, keep)], c.B[keep], c.C[:, keep], c.D
    elif method == "residualise":
        A, B, C, D = residualise(c.A, c.B, c.C, c.D, keep)
    else:
        raise ValueError(f"method must be 'truncate' or 'residualise' (got {method!r})")
    word = "balanced truncation" if method == "truncate" else "balanced singular perturbation"
    return Compensator(c.inputs, c.R, A, B, C, D, c.hsv[:r], f"{c.method}; {word} to {order} states",
                       unstable=c.unstable)


def margins(design: Design, c: Compensator) -> Margins:
    """The loop margins at the plant input with ``c`` as the law, on the design model."""
    A, B, C = loop_with_controller(design.model, c.controller())
    return loop_margins(A, B, C)
