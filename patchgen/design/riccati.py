"""The design's two Riccati gains from their inputs: the regulator's K and the Kalman filter's L,
whether they can be had (the PBH test), and how far each moves when those inputs move at rounding
level (patchgen.design.precision)."""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from patchgen.design.controller import Estimator
from patchgen.design.model import LinearModel
from patchgen.design.precision import GainSpread, gain_spread
from patchgen.inputs.spec import DesignSpec

STABLE_TOL = 1e-12  # a mode with real part above -1e-12 1/s counts as not decaying (rounding)
RANK_TOL = 1e-9  # the PBH rank test's singular-value cut-off for "the input cannot move this mode"


def stabilisable(A, B) -> bool:
    """The PBH test: every mode of A that does not decay can be moved by B (detectability: A', C')."""
    n = A.shape[0]
    for lam in np.linalg.eigvals(A):
        if lam.real >= -STABLE_TOL and np.linalg.matrix_rank(np.hstack([lam * np.eye(n) - A, B]), tol=RANK_TOL) < n:
            return False
    return True


def lqr_gain(A, B, Q, R, S=None) -> np.ndarray:
    """K = R^-1 B' S, S the stabilising solution of the regulator's Riccati equation."""
    S = sla.solve_continuous_are(A, B, Q, R) if S is None else S
    return np.linalg.solve(R, B.T @ S)


def filter_gain(Ae, Ce, Qn, V, P=None) -> np.ndarray:
    """L = P C' V^-1, P the stabilising solution of the filter's Riccati equation."""
    P = sla.solve_continuous_are(Ae.T, Ce.T, Qn, V) if P is None else P
    return P @ Ce.T @ np.linalg.inv(V)


def filter_inputs(spec: DesignSpec, model: LinearModel, rho: float) -> tuple[np.ndarray, ...]:
    """The Kalman filter's Ae, Ce, process noise rho G W G' and sensor noise V."""
    e = spec.estimator
    Ae, Be, Ce = model.submodel(model.estimated)
    G = Be if isinstance(e.Gamma, str) else np.array(e.Gamma, dtype=float).reshape(len(model.estimated), -1)
    W = np.atleast_2d(np.array(e.W, dtype=float))
    V = np.array(e.V, dtype=float)
    V = np.diag(V) if V.ndim == 1 else V
    Qn = rho * G @ W @ G.T
    return Ae, Ce, (Qn + Qn.T) / 2, V


def design_spread(spec: DesignSpec, model: LinearModel, Q, R, est: Estimator | None) -> GainSpread:
    """How far K (and a Kalman L) move when their Riccati inputs move at rounding level."""
    K = gain_spread(lqr_gain, (model.A, model.B, Q, R), symmetric=(2, 3))
    if est is None or est.kind != "kalman":
        return GainSpread(K=K)
    return GainSpread(K=K, L=gain_spread(filter_gain, filter_inputs(spec, model, est.rho), symmetric=(2, 3)))
