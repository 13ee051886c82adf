"""The LQG design: LQR gain, the estimator (a differentiator, a reduced observer or the Kalman
filter with loop transfer recovery, patchgen.design.ltr), margins.

spec -> Design. Control law u = -K x (force in N). The estimator (when there is one) carries the
plant and actuator states; integral states come from integrators of the measured s and theta.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from patchgen.design import corner
from patchgen.design.controller import Controller, Estimator, integrator_part, loop_with_controller, sort_poles
from patchgen.design.ltr import kalman_estimator
from patchgen.design.margins import Margins, loop_margins
from patchgen.design.model import LinearModel, build_model, open_loop_poles, plant_params, plant_zeros
from patchgen.design.numerics import failing_as
from patchgen.design.observer import ObserverError, reduced_observer, reduced_observer_controller
from patchgen.design.precision import GainSpread
from patchgen.design.riccati import STABLE_TOL, design_spread, lqr_gain, stabilisable
from patchgen.design.weights import q_matrix, r_matrix
from patchgen.inputs.spec import DesignSpec
from patchgen.plant.equations import PlantParams
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

ZERO_OFF_AXIS = 1e-8  # rad/s: a lag_zero's zero nearer the origin cancels the cart's pole to riccati.RANK_TOL


@dataclass(frozen=True)
class Design:
    """A spec's design: the model, the LQR weights, gain and Riccati solution, poles, zeros,
    the estimator and the controller it gives, and the loop margins with and without it."""

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
    spread: GainSpread  # how many digits of K (and L) the inputs fix: precision.py

    @property
    def states(self) -> tuple[str, ...]:
        """The design model's states, in K's order."""
        return self.model.states

    @property
    def plant(self) -> PlantParams | RotaryParams:
        """The spec's plant as the plant equations take them (the mechanism; the drive is the
        spec's actuator): what every stage after the design simulates, linearises or patches for."""
        return plant_params(self.spec)

    def gain(self, state: str) -> float:
        """The LQR gain on one named state (u = -K x)."""
        return float(self.K[0, self.model.index(state)])


def _unstabilisable_part(spec: DesignSpec, model: LinearModel) -> tuple[str, str]:
    """Which part makes the model not stabilisable: an integral state (its leak), else the plant."""
    plant = tuple(s for s in model.states if not s.startswith("int_"))
    Ap, Bp, _ = model.submodel(plant)
    for name in (s for s in model.states if s.startswith("int_")):
        A, B, _ = model.submodel(plant + (name,))
        if stabilisable(Ap, Bp) and not stabilisable(A, B):
            leak = getattr(spec.integrators, f"{name}_leak")
            return (f"integrators.{name}_leak", f"with a leak of {leak:g} 1/s the integral state {name} makes the "
                    "model not stabilisable: a pole on the axis the force cannot move (the default leak avoids it)")
    return ("plant", "the model is not stabilisable: with these plant and actuator figures an unstable mode "
            "cannot be moved by the force")


def lqr(spec: DesignSpec, model: LinearModel) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Q, R, K, S of the regulator, with the checks a user needs named."""
    Q, R = q_matrix(spec), r_matrix(spec)
    A, B = model.A, model.B
    if not stabilisable(A, B):
        z = spec.actuator.zero
        if spec.actuator.model == "lag_zero" and z < ZERO_OFF_AXIS:
            where = "exactly at the origin" if z == 0 else f"at {z:g} rad/s, this close to the origin,"
            raise spec.error("actuator.zero", f"a zero {where} cancels the cart's position pole, so the model is "
                             f"not stabilisable; move it off the axis (at least {ZERO_OFF_AXIS:g}; the default 1e-5)")
        raise spec.error(*_unstabilisable_part(spec, model))
    ev, vec = np.linalg.eigh((Q + Q.T) / 2)
    H = (vec * np.sqrt(np.clip(ev, 0, None))) @ vec.T
    if not stabilisable(A.T, H.T):
        field = "weights.bryson" if spec.weights.bryson is not None else "weights.Q"
        raise spec.error(field, "(A, Q^1/2) is not detectable: weight the unstable modes (e.g. theta)")
    try:
        S = sla.solve_continuous_are(A, B, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise spec.error("weights", f"the Riccati equation has no stabilising solution ({exc})") from None
    K = lqr_gain(A, B, Q, R, S)
    if not np.all(np.isfinite(K)) or np.max(np.linalg.eigvals(A - B @ K).real) >= -STABLE_TOL:
        raise spec.error("weights", "the Riccati solution does not stabilise the model")
    return Q, R, K, S


def differentiator_controller(model: LinearModel, K: np.ndarray, rolloff: float) -> Controller:
    """Static gains on the measured signals; each rate not measured (theta_dot, and s_dot on a
    bench without a velocity sensor) from a differentiator of its position with a first-order
    roll-off (theta_dot ~ s/(rolloff s + 1) theta); integral states from integrators; an actuator
    state (if any) from a model of the actuator driven by the commanded force."""
    my = list(model.measured)
    derived = [(p, r) for p, r in model.plant.rate_of.items() if r not in my]  # theta_dot's first, as the thesis's
    derived.sort(key=lambda pr: pr[1] != model.plant.angle_rate)
    nd = len(derived)
    names: list[str] = [f"dfilt_{p}" for p, _ in derived]
    ip = integrator_part(model, K)
    inames, Ai, Ei, Ki = ip.names, ip.Ai, ip.Ei, ip.Ki
    names += list(inames)
    has_act = "actuator" in model.states
    if has_act:
        names.append("xhat_actuator")
    n = len(names)
    Ac, Bc = np.zeros((n, n)), np.zeros((n, len(my)))
    Cc, Dc = np.zeros((1, n)), np.zeros((1, len(my)))
    for st in my:
        Dc[0, my.index(st)] -= K[0, model.index(st)]
    for f, (p, rate) in enumerate(derived):  # filter state z' = (p - z)/rolloff; its rate ~ (p - z)/rolloff
        ip_ = my.index(p)
        Ac[f, f] = -1.0 / rolloff
        Bc[f, ip_] = 1.0 / rolloff
        kd = K[0, model.index(rate)]
        Dc[0, ip_] -= kd / rolloff
        Cc[0, f] += kd / rolloff
    for r in range(len(inames)):
        j = nd + r
        Ac[j, nd:nd + len(inames)] = Ai[r]
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


def design(spec: DesignSpec, bench: BenchProfile | None = None, *, plant: PlantParams | RotaryParams | None = None,
           default_rolloff_s: float | None = None) -> Design:
    """Run the whole design of a spec: LQR gain, estimator, compensator and loop margins.

    Parameters
    ----------
    spec : DesignSpec
        The loaded spec.
    bench : BenchProfile, optional
        The bench the spec names, loaded by the caller. A filtered differentiator or a reduced
        observer needs it (its speed and force-error figure come from the bench's noise); other
        estimators do not read it.
    plant : PlantParams, optional
        A perturbed plant to design for (sweeps); by default the spec's.
    default_rolloff_s : float, optional
        The differentiator roll-off when the spec gives none (the machine profile's).

    Returns
    -------
    Design
        Gains, poles, zeros, margins, estimator and controller; u = -K x.

    Raises
    ------
    InputError
        A spec the design cannot meet, naming the field behind it.
    ValueError
        A filtered differentiator or reduced observer without a bench profile.
    """
    model = build_model(spec, plant)
    with failing_as(spec.path, "weights", "the LQR design"):
        Q, R, K, S = lqr(spec, model)
        cl = np.linalg.eigvals(model.A - model.B @ K)
        lqr_m = loop_margins(model.A, model.B, K)
        pm = spec.plant_model
        zeros = {f"{out}/{pm.input}": plant_zeros(spec, out) for out in (pm.position, pm.rate_of[pm.position])}
    redesign = lambda sp: design(sp, bench, plant=plant, default_rolloff_s=default_rolloff_s)
    with failing_as(spec.path, "estimator", f"the {spec.estimator.kind} estimator"):
        est, ctl, lqg_m = _estimator(spec, bench, model, K, lqr_m, default_rolloff_s, redesign)
    return Design(spec=spec, model=model, Q=Q, R=R, K=K, S=S, closed_loop_poles=sort_poles(cl),
                  open_loop_poles=open_loop_poles(model), zeros=zeros, lqr_margins=lqr_m, estimator=est,
                  controller=ctl, lqg_margins=lqg_m, spread=design_spread(spec, model, Q, R, est))



def design_on(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile | None, *,
              plant: PlantParams | RotaryParams | None = None) -> Design:
    """The design of a spec for the machine and bench it is patched on and tested against.

    Parameters
    ----------
    spec : DesignSpec
        The loaded spec.
    machine : MachineProfile
        Gives the differentiator roll-off when the spec has none.
    bench : BenchProfile or None
        Gives the noise a filtered differentiator or reduced observer is shaped for (None only
        for the estimators that do not read it, as in :func:`design`).
    plant : PlantParams, optional
        A perturbed plant to design for (sweeps).

    Returns
    -------
    Design
        As ``patchgen design SPEC`` computes it.
    """
    return design(spec, bench, plant=plant, default_rolloff_s=machine.imperfections.differentiator_rolloff_s)


def _estimator(spec: DesignSpec, bench: BenchProfile | None, model: LinearModel, K: np.ndarray, lqr_m: Margins,
               default_rolloff_s: float | None, redesign) -> tuple[Estimator | None, Controller | None, Margins | None]:
    """The spec's estimator, its controller and the loop margins with it (none: all None);
    ``redesign`` designs a changed spec as this one is (a refusal's suggestion is checked so)."""
    e = spec.estimator
    if e.kind == "kalman":
        return kalman_estimator(spec, model, K, lqr_m, redesign)
    if e.kind == "differentiator":
        roll = e.rolloff_s or default_rolloff_s
        if roll is None:
            raise spec.error("estimator.rolloff_s", "missing field (no machine default either)")
        ctl = differentiator_controller(model, K, roll)
        rates = spec.sensors.derived()
        est = Estimator(kind="differentiator", states=rates, L=None, poles=np.full(len(rates), -1.0 / roll + 0j),
                        rolloff_s=roll)
        return est, ctl, loop_margins(*loop_with_controller(model, ctl))
    if e.kind in ("filtered_differentiator", "reduced_observer"):
        if e.kind == "reduced_observer" and len(spec.sensors.derived()) > 1:
            rate = spec.plant_model.rate_of[spec.plant_model.position]
            raise spec.error("estimator.kind", f"the reduced observer is built for a measured {rate}: without one, "
                                               "a differentiator or a Kalman filter finds it")
        if bench is None:
            raise ValueError(f"{spec.name}: a {e.kind} estimator is shaped for the bench's noise; pass the bench "
                             f"profile the spec names ({spec.bench!r}, patchgen.profiles.bench.load_bench)")
        est, ctl = _noise_shaped_estimator(spec, bench, model, K, redesign)
        return est, ctl, loop_margins(*loop_with_controller(model, ctl))
    return None, None, None


def _noise_shaped_estimator(spec: DesignSpec, bench: BenchProfile, model: LinearModel, K: np.ndarray, redesign):
    """A filtered differentiator or a reduced observer, its speed from the spec or, when the spec
    leaves it out, from the bench's noise levels (patchgen.design.corner); a refusal names the
    speed to set when a design with it passes (corner.way_forward, through ``redesign``)."""
    e = spec.estimator
    fixed = e.rolloff_s if e.kind == "filtered_differentiator" else e.observer_pole
    if e.kind == "filtered_differentiator":
        build = lambda r: differentiator_controller(model, K, r)
        grid, field = corner.ROLLOFF_GRID_S, "estimator.rolloff_s"
    else:
        build = lambda p: reduced_observer_controller(model, K, reduced_observer(model, p))
        grid, field = corner.POLE_GRID, "estimator.observer_pole"
    noise = corner.noise_model(spec, bench, model)
    if fixed is None:
        def margin(c):
            mg = loop_margins(*loop_with_controller(model, c), gain_limits=False)
            return mg.pm_deg if mg.stable else None

        def margin_with(v):
            mg = redesign(spec.changed(field, v)).lqg_margins
            return mg.pm_deg if mg.stable else None

        try:
            value = corner.choose(model, K, build, noise, grid, margin).value
        except corner.NoRobustSpeed as exc:
            raise spec.error("estimator", str(exc), corner.way_forward(exc, field, margin_with)) from None
    else:
        value = float(fixed)
    try:
        ctl = build(value)
    except ObserverError as exc:
        raise spec.error("estimator.observer_pole", str(exc)) from None
    chosen = dict(chosen_from_noise=fixed is None, force_error_rms_N=corner.force_error_rms(model, K, ctl, noise))
    if e.kind == "filtered_differentiator":
        rates = spec.sensors.derived()
        est = Estimator(kind=e.kind, states=rates, L=None, poles=np.full(len(rates), -1.0 / value + 0j),
                        rolloff_s=value, **chosen)
    else:
        obs = reduced_observer(model, value)
        est = Estimator(kind=e.kind, states=obs.unmeasured, L=obs.Lr, poles=sort_poles(np.linalg.eigvals(obs.F)),
                        observer=obs, **chosen)
    return est, ctl
