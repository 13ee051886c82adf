"""The LQG design: LQR gain, steady-state Kalman estimator, loop transfer recovery, margins.

spec -> Design. Control law u = -K x (force in N). The estimator (when there is one) carries the
plant and actuator states; integral states come from integrators of the measured s and theta.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from patchgen.design.margins import Margins, loop_margins
from patchgen.design.model import LinearModel, build_model, open_loop_poles, plant_zeros
from patchgen.design.numerics import failing_as
from patchgen.inputs.spec import DesignSpec, q_matrix, r_matrix
from patchgen.plant.equations import PlantParams


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
    rho: float
    margins: Margins
    accepted: bool


@dataclass(frozen=True)
class Estimator:
    kind: str  # "kalman", "differentiator", "filtered_differentiator" or "reduced_observer"
    states: tuple[str, ...]
    L: np.ndarray | None  # n x m Kalman gain (kalman)
    poles: np.ndarray
    rho: float | None
    rho_tries: list[RhoTry] = field(default_factory=list)
    margins_rho1: Margins | None = None  # LQG before recovery (rho = 1)
    rolloff_s: float | None = None
    observer: object | None = None  # reduced_observer: patchgen.design.observer.ReducedObserver
    chosen_from_noise: bool = False  # roll-off or pole chosen by patchgen.design.corner's rule
    force_error_rms_N: float | None = None  # that rule's predicted figure


@dataclass(frozen=True)
class Design:
    spec: DesignSpec
    model: LinearModel
    Q: np.ndarray
    R: np.ndarray
    K: np.ndarray  # 1 x n, u = -K x
    S: np.ndarray
    closed_loop_poles: np.ndarray
    open_loop_poles: np.ndarray
    zeros: dict[str, np.ndarray]
    lqr_margins: Margins
    estimator: Estimator | None
    controller: Controller | None
    lqg_margins: Margins | None

    @property
    def states(self) -> tuple[str, ...]:
        return self.model.states

    def gain(self, state: str) -> float:
        return float(self.K[0, self.model.index(state)])


def _stabilisable(A, B) -> bool:
    n = A.shape[0]
    for lam in np.linalg.eigvals(A):
        if lam.real >= -1e-12 and np.linalg.matrix_rank(np.hstack([lam * np.eye(n) - A, B]), tol=1e-9) < n:
            return False
    return True


def _unstabilisable_part(spec: DesignSpec, model: LinearModel) -> tuple[str, str]:
    """Which part makes the model not stabilisable: an integral state (its leak), else the plant."""
    plant = tuple(s for s in model.states if not s.startswith("int_"))
    Ap, Bp, _ = model.submodel(plant)
    for name in (s for s in model.states if s.startswith("int_")):
        A, B, _ = model.submodel(plant + (name,))
        if _stabilisable(Ap, Bp) and not _stabilisable(A, B):
            leak = getattr(spec.integrators, f"{name}_leak")
            return (f"integrators.{name}_leak", f"with a leak of {leak:g} 1/s the integral state {name} makes the "
                    "model not stabilisable: a pole on the axis the force cannot move (the default leak avoids it)")
    return ("plant", "the model is not stabilisable: with these plant and actuator figures an unstable mode "
            "cannot be moved by the force")


def lqr(spec: DesignSpec, model: LinearModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Q, R, K, S of the regulator, with the checks a user needs named."""
    Q, R = q_matrix(spec), r_matrix(spec)
    A, B = model.A, model.B
    if not _stabilisable(A, B):
        if spec.actuator.model == "lag_zero" and spec.actuator.zero == 0:
            raise spec.error("actuator.zero", "a zero exactly at the origin cancels the cart's position pole, "
                             "so the model is not stabilisable; move it off the axis (e.g. 1e-5)")
        raise spec.error(*_unstabilisable_part(spec, model))
    ev, vec = np.linalg.eigh((Q + Q.T) / 2)
    H = (vec * np.sqrt(np.clip(ev, 0, None))) @ vec.T
    if not _stabilisable(A.T, H.T):
        field = "weights.bryson" if spec.weights.bryson is not None else "weights.Q"
        raise spec.error(field, "(A, Q^1/2) is not detectable: weight the unstable modes (e.g. theta)")
    try:
        S = sla.solve_continuous_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise spec.error("weights", f"the Riccati equation has no stabilising solution ({exc})") from None
    K = np.linalg.solve(R, B.T @ S)
    if not np.all(np.isfinite(K)) or np.max(np.linalg.eigvals(A - B @ K).real) >= 0:
        raise spec.error("weights", "the Riccati solution does not stabilise the model")
    return Q, R, K, S


def kalman_gain(spec: DesignSpec, model: LinearModel, rho: float) -> np.ndarray:
    """Steady-state Kalman gain for the estimated states from s, theta, s_dot, W scaled by rho."""
    e = spec.estimator
    Ae, Be, Ce = model.submodel(model.estimated)
    G = Be if isinstance(e.Gamma, str) else np.array(e.Gamma, dtype=float).reshape(len(model.estimated), -1)
    W = np.atleast_2d(np.array(e.W, dtype=float))
    V = np.array(e.V, dtype=float)
    V = np.diag(V) if V.ndim == 1 else V
    Qn = rho * G @ W @ G.T
    Qn = (Qn + Qn.T) / 2
    n = Ae.shape[0]
    if not _stabilisable(Ae.T, Ce.T):
        raise spec.error("estimator", "the estimated model is not detectable from s, theta, s_dot")
    try:
        P = sla.solve_continuous_are(Ae.T, Ce.T, Qn, V)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise spec.error("estimator",
                         f"the estimator Riccati equation has no solution at rho = {rho:g} ({exc})") from None
    L = P @ Ce.T @ np.linalg.inv(V)
    if not np.all(np.isfinite(L)) or np.max(np.linalg.eigvals(Ae - L @ Ce).real) >= 0 or L.shape[0] != n:
        raise spec.error("estimator", f"the Kalman filter is not stable at rho = {rho:g}")
    return L


def _integrator_part(model: LinearModel, K: np.ndarray):
    """Integral states: their A block, input matrix from y, and their gains."""
    idx = [i for i, s in enumerate(model.states) if s.startswith("int_")]
    names = tuple(model.states[i] for i in idx)
    Ai = model.A[np.ix_(idx, idx)]
    Ei = np.zeros((len(idx), len(model.measured)))
    for r, i in enumerate(idx):
        Ei[r] = model.A[i, :][[model.index(m) for m in model.measured]]
    return names, Ai, Ei, K[:, idx]


def kalman_controller(model: LinearModel, K: np.ndarray, L: np.ndarray) -> Controller:
    """LQG compensator (A - B K - L C for the estimated states) plus the integrators of y."""
    est = model.estimated
    Ae, Be, Ce = model.submodel(est)
    Ke = K[:, [model.index(s) for s in est]]
    inames, Ai, Ei, Ki = _integrator_part(model, K)
    ne, ni = len(est), len(inames)
    Ac = np.zeros((ne + ni, ne + ni))
    Ac[:ne, :ne] = Ae - Be @ Ke - L @ Ce
    Ac[:ne, ne:] = -Be @ Ki
    Ac[ne:, ne:] = Ai
    Bc = np.vstack([L, Ei])
    Cc = -np.hstack([Ke, Ki])
    Dc = np.zeros((1, len(model.measured)))
    return Controller(tuple(f"xhat_{s}" for s in est) + inames, Ac, Bc, Cc, Dc)


def differentiator_controller(model: LinearModel, K: np.ndarray, rolloff: float) -> Controller:
    """Static gains on s, theta, s_dot; theta_dot from a differentiator with a first-order roll-off
    (theta_dot ~ s/(rolloff s + 1) theta); integral states from integrators; an actuator state
    (if any) from a model of the actuator driven by the commanded force."""
    my = list(model.measured)
    names: list[str] = ["dfilt_theta"]
    inames, Ai, Ei, Ki = _integrator_part(model, K)
    names += list(inames)
    has_act = "actuator" in model.states
    if has_act:
        names.append("xhat_actuator")
    n = len(names)
    Ac, Bc = np.zeros((n, n)), np.zeros((n, len(my)))
    Cc, Dc = np.zeros((1, n)), np.zeros((1, len(my)))
    # filter state z' = (theta - z)/rolloff; theta_dot ~ (theta - z)/rolloff
    it = my.index("theta")
    Ac[0, 0] = -1.0 / rolloff
    Bc[0, it] = 1.0 / rolloff
    for st in ("s", "theta", "s_dot"):
        Dc[0, my.index(st)] -= K[0, model.index(st)]
    kd = K[0, model.index("theta_dot")]
    Dc[0, it] -= kd / rolloff
    Cc[0, 0] += kd / rolloff
    for r in range(len(inames)):
        j = 1 + r
        Ac[j, 1:1 + len(inames)] = Ai[r]
        Bc[j] = Ei[r]
        Cc[0, j] -= Ki[0, r]
    if has_act:
        ia = model.index("actuator")
        j = n - 1
        Cc[0, j] -= K[0, ia]
        # x_a' = A_aa x_a + B_a u, with u = Cc xc + Dc y itself
        Ac[j, j] += model.A[ia, ia]
        Ac[j] += model.B[ia, 0] * Cc[0]
        Bc[j] += model.B[ia, 0] * Dc[0]
    return Controller(tuple(names), Ac, Bc, Cc, Dc)


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


def _close_enough(lqg: Margins, lqr: Margins) -> bool:
    if not lqg.stable or lqg.pm_deg is None or lqr.pm_deg is None:
        return False
    gm_ok = (lqg.lower_gm_db is None) == (lqr.lower_gm_db is None) and (
        lqr.lower_gm_db is None or abs(lqg.lower_gm_db - lqr.lower_gm_db) <= 1.0)
    return gm_ok and abs(lqg.pm_deg - lqr.pm_deg) <= 5.0


def design(spec: DesignSpec, plant: PlantParams | None = None, default_rolloff_s: float | None = None) -> Design:
    """Run the whole design for a spec (optionally on a perturbed plant, for sweeps)."""
    model = build_model(spec, plant)
    with failing_as(spec.path, "weights", "the LQR design"):
        Q, R, K, S = lqr(spec, model)
        cl = np.linalg.eigvals(model.A - model.B @ K)
        lqr_m = loop_margins(model.A, model.B, K)
        zeros = {"s/F_U": plant_zeros(spec, "s"), "s_dot/F_U": plant_zeros(spec, "s_dot")}
    with failing_as(spec.path, "estimator", f"the {spec.estimator.kind} estimator"):
        est, ctl, lqg_m = _estimator(spec, model, K, lqr_m, default_rolloff_s)
    return Design(spec, model, Q, R, K, S, _sort(cl), open_loop_poles(model), zeros, lqr_m, est, ctl, lqg_m)


def _estimator(spec: DesignSpec, model: LinearModel, K: np.ndarray, lqr_m: Margins,
               default_rolloff_s: float | None) -> tuple[Estimator | None, Controller | None, Margins | None]:
    """The spec's estimator, its controller and the loop margins with it (none: all None)."""
    est = ctl = None
    lqg_m = None
    e = spec.estimator
    if e.kind == "kalman":
        tries: list[RhoTry] = []
        L1 = kalman_gain(spec, model, 1.0)
        m1 = loop_margins(*loop_with_controller(model, kalman_controller(model, K, L1)))
        if e.rho == "auto":
            rho, L, m = 1.0, L1, m1
            k = 0
            while True:
                ok = _close_enough(m, lqr_m)
                tries.append(RhoTry(rho, m, ok))
                if ok or rho * 10 > e.rho_max * (1 + 1e-9):
                    break
                k += 1
                rho = 10.0 ** k
                L = kalman_gain(spec, model, rho)
                m = loop_margins(*loop_with_controller(model, kalman_controller(model, K, L)))
        else:
            rho = float(e.rho)
            L = kalman_gain(spec, model, rho)
            m = loop_margins(*loop_with_controller(model, kalman_controller(model, K, L)))
            tries.append(RhoTry(rho, m, _close_enough(m, lqr_m)))
        Ae, _, Ce = model.submodel(model.estimated)
        ctl = kalman_controller(model, K, L)
        est = Estimator("kalman", model.estimated, L, _sort(np.linalg.eigvals(Ae - L @ Ce)), rho, tries, m1)
        lqg_m = m
    elif e.kind == "differentiator":
        roll = e.rolloff_s or default_rolloff_s
        if roll is None:
            raise spec.error("estimator.rolloff_s", "missing field (no machine default either)")
        ctl = differentiator_controller(model, K, roll)
        lqg_m = loop_margins(*loop_with_controller(model, ctl))
        est = Estimator("differentiator", ("theta_dot",), None, np.array([-1.0 / roll + 0j]), None, [], None, roll)
    elif e.kind in ("filtered_differentiator", "reduced_observer"):
        est, ctl = _noise_shaped_estimator(spec, model, K)
        lqg_m = loop_margins(*loop_with_controller(model, ctl))
    return est, ctl, lqg_m


def _noise_shaped_estimator(spec: DesignSpec, model: LinearModel, K: np.ndarray):
    """A filtered differentiator or a reduced observer, its speed from the spec or, when the spec
    leaves it out, from the bench's noise levels (patchgen.design.corner)."""
    from patchgen.design import corner
    from patchgen.design.observer import ObserverError, reduced_observer, reduced_observer_controller
    from patchgen.profiles.bench import load_bench

    e = spec.estimator
    fixed = e.rolloff_s if e.kind == "filtered_differentiator" else e.observer_pole
    choice = None
    if e.kind == "filtered_differentiator":
        build = lambda r: differentiator_controller(model, K, r)
        grid = corner.ROLLOFF_GRID_S
    else:
        build = lambda p: reduced_observer_controller(model, K, reduced_observer(model, p))
        grid = corner.POLE_GRID
    noise = corner.noise_model(spec, load_bench(spec.bench, spec.path), model)
    if fixed is None:
        try:
            def robust(c):
                mg = loop_margins(*loop_with_controller(model, c), gain_limits=False)
                return mg.stable and mg.pm_deg is not None and mg.pm_deg >= corner.MIN_PM_DEG

            choice = corner.choose(model, K, build, noise, grid, robust)
        except ValueError as exc:
            raise spec.error("estimator", str(exc)) from None
        value = choice.value
    else:
        value = float(fixed)
    try:
        ctl = build(value)
    except ObserverError as exc:
        raise spec.error("estimator.observer_pole", str(exc)) from None
    err = corner.force_error_rms(model, K, ctl, noise)
    if e.kind == "filtered_differentiator":
        est = Estimator(e.kind, ("theta_dot",), None, np.array([-1.0 / value + 0j]), None, [], None, value,
                        None, fixed is None, err)
    else:
        obs = reduced_observer(model, value)
        est = Estimator(e.kind, obs.unmeasured, obs.Lr, _sort(np.linalg.eigvals(obs.F)), None, [], None, None,
                        obs, fixed is None, err)
    return est, ctl


def _sort(v):
    v = np.asarray(v, dtype=complex)
    return v[np.lexsort((v.imag, v.real))]

