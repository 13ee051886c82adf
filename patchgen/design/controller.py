"""The values the design stages hand each other: a controller as matrices, the estimator behind
it (a reduced observer's matrices among them), the integrator part every controller shares, and
the loop a controller closes around the design model.

patchgen.design.lqg builds them, patchgen.design.observer and patchgen.design.corner read and
build them too; keeping them here lets those modules import one another in one direction only.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from patchgen.design.margins import Margins
from patchgen.design.model import LinearModel


@dataclass(frozen=True)
class Controller:
    """A linear controller from measured y (s, theta, s_dot; SI) to force u: xc' = Ac xc + Bc y,
    u = Cc xc + Dc y. Its states are named."""

    states: tuple[str, ...]
    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray
    Dc: np.ndarray


@dataclass(frozen=True)
class RhoTry:
    """One loop-transfer-recovery factor tried, the loop margins it gave, and whether they pass."""

    rho: float
    margins: Margins
    accepted: bool


@dataclass(frozen=True)
class ReducedObserver:
    """z' = F z + G y + H u (SI), w_hat = z + Lr y; states named by the w they estimate."""

    unmeasured: tuple[str, ...]
    Lr: np.ndarray  # n_w x n_y
    F: np.ndarray
    G: np.ndarray
    H: np.ndarray  # n_w
    pole: float


@dataclass(frozen=True)
class Estimator:
    """How the controller gets the states it does not measure, and how that was chosen."""

    kind: str  # "kalman", "differentiator", "filtered_differentiator" or "reduced_observer"
    states: tuple[str, ...]
    L: np.ndarray | None  # n x m Kalman gain (kalman), Lr (reduced_observer)
    poles: np.ndarray
    rho: float | None = None
    rho_tries: list[RhoTry] = field(default_factory=list)
    margins_rho1: Margins | None = None  # LQG before recovery (rho = 1)
    rolloff_s: float | None = None
    observer: ReducedObserver | None = None
    chosen_from_noise: bool = False  # roll-off or pole chosen by patchgen.design.corner's rule
    force_error_rms_N: float | None = None  # that rule's predicted figure


@dataclass(frozen=True)
class IntegratorPart:
    """The design's integral states as a controller carries them: xi' = Ai xi + Ei y, gains Ki."""

    names: tuple[str, ...]
    Ai: np.ndarray
    Ei: np.ndarray
    Ki: np.ndarray


def integrator_part(model: LinearModel, K: np.ndarray) -> IntegratorPart:
    """The integral states of ``model``: their A block, their input matrix from y, their gains.

    Parameters
    ----------
    model : LinearModel
        The design model; integral states are those named ``int_*``.
    K : numpy.ndarray
        The 1 x n state-feedback gain (u = -K x).

    Returns
    -------
    IntegratorPart
        Every controller patchgen builds integrates the measured signals this way.
    """
    idx = [i for i, s in enumerate(model.states) if s.startswith("int_")]
    Ei = np.zeros((len(idx), len(model.measured)))
    for r, i in enumerate(idx):
        Ei[r] = model.A[i, :][[model.index(m) for m in model.measured]]
    return IntegratorPart(tuple(model.states[i] for i in idx), model.A[np.ix_(idx, idx)], Ei, K[:, idx])


def loop_with_controller(model: LinearModel, ctl: Controller):
    """The loop broken at the plant input: plant (without integral states) then controller."""
    keep = [i for i, s in enumerate(model.states) if not s.startswith("int_")]
    Ap, Bp, Cp = model.A[np.ix_(keep, keep)], model.B[keep], model.C[:, keep]
    n, nc = Ap.shape[0], ctl.Ac.shape[0]
    A = np.zeros((n + nc, n + nc))
    A[:n, :n] = Ap
    A[n:, :n] = ctl.Bc @ Cp
    A[n:, n:] = ctl.Ac
    B = np.vstack([Bp, np.zeros((nc, 1))])
    C = -np.hstack([ctl.Dc @ Cp, ctl.Cc])
    return A, B, C


def sort_poles(v) -> np.ndarray:
    """Eigenvalues in a fixed order: by real part, then imaginary part."""
    v = np.asarray(v, dtype=complex)
    return v[np.lexsort((v.imag, v.real))]
