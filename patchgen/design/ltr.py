"""The Kalman estimator and loop transfer recovery: the steady-state filter at a given rho, its
compensator, and the search over rho = 1, 10, 100, ... for the first loop close enough to the
LQR loop (docs/spec.md, estimator.rho). A rho the search cannot compute is refused with the
rho_max that stops it at the last one it could, once the design made with it passes."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.linalg as sla

from patchgen.design.controller import Controller, Estimator, RhoTry, integrator_part, loop_with_controller, sort_poles
from patchgen.design.margins import Margins, loop_margins
from patchgen.design.model import LinearModel
from patchgen.design.riccati import STABLE_TOL, filter_gain, filter_inputs, stabilisable
from patchgen.inputs.errors import Cure, InputError
from patchgen.inputs.spec import DesignSpec

# rho = "auto" stops at the first rho whose loop margins are this close to the LQR loop's
# (docs/spec.md, estimator.rho): "recovered" to within what the margin figures are quoted to.
LTR_GM_TOLERANCE_DB = 1.0  # each gain limit within 1 dB
LTR_PM_TOLERANCE_DEG = 5.0  # phase margin within 5 deg
RHO_STEP = 10.0  # rho = 1, 10, 100, ...: powers of ten (docs/spec.md; the thesis's case 1 lands on 1e7)
RHO_MAX_SLACK = 1e-9  # relative: rho_max = 1e7 still admits 10^7 computed as a float power


def kalman_gain(spec: DesignSpec, model: LinearModel, rho: float, field: str = "estimator.rho") -> np.ndarray:
    """Steady-state Kalman gain for the estimated states from s, theta, s_dot, W scaled by rho; a
    filter that cannot be had at this rho is refused naming ``field``."""
    Ae, Ce, Qn, V = filter_inputs(spec, model, rho)
    n = Ae.shape[0]
    if not stabilisable(Ae.T, Ce.T):
        raise spec.error("estimator", "the estimated model is not detectable from s, theta, s_dot")
    ratio = np.abs(Qn).max() / np.abs(V).max()  # process noise against measurement noise
    little = ("rho x W puts so much process noise on the model against V that the filter is beyond computing "
              "(a smaller rho or W)" if ratio > 1 else "rho x W puts too little process noise on the model to move "
              "the plant's poles off the axis (a larger rho or W)")
    try:
        P = sla.solve_continuous_are(Ae.T, Ce.T, Qn, V)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise spec.error(field, f"the estimator Riccati equation has no solution at rho = {rho:g} ({exc}): "
                         f"{little}") from None
    L = filter_gain(Ae, Ce, Qn, V, P)
    if (not np.all(np.isfinite(L)) or np.max(np.linalg.eigvals(Ae - L @ Ce).real) >= -STABLE_TOL
            or L.shape[0] != n):
        raise spec.error(field, f"the Kalman filter is not stable at rho = {rho:g}: {little}")
    return L


def kalman_controller(model: LinearModel, K: np.ndarray, L: np.ndarray) -> Controller:
    """LQG compensator (A - B K - L C for the estimated states) plus the integrators of y."""
    est = model.estimated
    Ae, Be, Ce = model.submodel(est)
    Ke = K[:, [model.index(s) for s in est]]
    ip = integrator_part(model, K)
    inames, Ai, Ei, Ki = ip.names, ip.Ai, ip.Ei, ip.Ki
    ne, ni = len(est), len(inames)
    Ac = np.zeros((ne + ni, ne + ni))
    Ac[:ne, :ne] = Ae - Be @ Ke - L @ Ce
    Ac[:ne, ne:] = -Be @ Ki
    Ac[ne:, ne:] = Ai
    Bc = np.vstack([L, Ei])
    Cc = -np.hstack([Ke, Ki])
    Dc = np.zeros((1, len(model.measured)))
    return Controller(tuple(f"xhat_{s}" for s in est) + inames, Ac, Bc, Cc, Dc)



def close_enough(lqg: Margins, lqr: Margins) -> bool:
    """Loop transfer recovery has recovered the LQR loop: gain limits and phase margin within the
    LTR tolerances (the same gain limits present)."""
    if not lqg.stable or lqg.pm_deg is None or lqr.pm_deg is None:
        return False
    gm_ok = (lqg.lower_gm_db is None) == (lqr.lower_gm_db is None) and (
        lqr.lower_gm_db is None or abs(lqg.lower_gm_db - lqr.lower_gm_db) <= LTR_GM_TOLERANCE_DB)
    return gm_ok and abs(lqg.pm_deg - lqr.pm_deg) <= LTR_PM_TOLERANCE_DEG



def _kalman_margins(spec: DesignSpec, model: LinearModel, K: np.ndarray, rho: float, field: str = "estimator.rho"):
    """The Kalman gain at ``rho`` and the loop margins of its compensator."""
    L = kalman_gain(spec, model, rho, field)
    return L, loop_margins(*loop_with_controller(model, kalman_controller(model, K, L)))


def kalman_estimator(spec: DesignSpec, model: LinearModel, K: np.ndarray, lqr_m: Margins,
                     redesign: Callable[[DesignSpec], object]):
    """The Kalman estimator after loop transfer recovery: rho from the spec, or the first power
    of RHO_STEP whose loop is close enough to the LQR loop (up to the spec's rho_max). The
    filter at rho = 1 gives the report's loop before recovery (left out when there is none).
    A search that meets a rho it cannot compute is refused with the rho_max that stops it at the
    last it could, checked by ``redesign`` (the changed spec designed as this one is).

    Returns
    -------
    (Estimator, Controller, Margins)
        The estimator, its compensator and the loop margins with it.
    """
    e = spec.estimator
    tries: list[RhoTry] = []
    if e.rho == "auto":
        field = "estimator.W"  # the search starts at rho = 1: W (through Gamma) is the noise it starts from
        rho, k = 1.0, 0
        L, m = _kalman_margins(spec, model, K, rho, field)
        m1 = m
        while True:
            ok = close_enough(m, lqr_m)
            tries.append(RhoTry(rho=rho, margins=m, accepted=ok))
            if ok or rho * RHO_STEP > e.rho_max * (1 + RHO_MAX_SLACK):
                break
            k += 1
            try:
                L, m = _kalman_margins(spec, model, K, RHO_STEP ** k, field)
            except InputError as exc:
                raise spec.error(exc.field, exc.message, _stop_at(spec, rho, redesign)) from None
            rho = RHO_STEP ** k
    else:
        field, rho = "estimator.rho", float(e.rho)
        L, m = _kalman_margins(spec, model, K, rho, field)
        tries.append(RhoTry(rho=rho, margins=m, accepted=close_enough(m, lqr_m)))
        m1 = m if rho == 1.0 else _margins_at_rho1(spec, model, K)
    Ae, _, Ce = model.submodel(model.estimated)
    est = Estimator(kind="kalman", states=model.estimated, L=L, poles=sort_poles(np.linalg.eigvals(Ae - L @ Ce)),
                    rho=rho, rho_tries=tries, margins_rho1=m1)
    return est, kalman_controller(model, K, L), m


def _margins_at_rho1(spec: DesignSpec, model: LinearModel, K: np.ndarray) -> Margins | None:
    try:  # no filter at rho = 1: the report leaves the loop before recovery out
        return _kalman_margins(spec, model, K, 1.0)[1]
    except InputError:
        return None


def _stop_at(spec: DesignSpec, rho: float, redesign: Callable[[DesignSpec], object]) -> Cure | None:
    """rho_max = ``rho`` (the last rho the search computed), when the design made with it passes."""
    try:
        m = redesign(spec.changed("estimator.rho_max", rho)).lqg_margins
    except InputError:
        return None
    pm = "" if m.pm_deg is None else f", PM {m.pm_deg:.1f} deg"
    return Cure("estimator.rho_max", rho, f"stops the search at rho = {rho:g}, the last it computes{pm}")
