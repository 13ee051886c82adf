"""identify on a rotary pendulum's bench (a QUBE-Servo 2): the motor, the arm's and the pendulum's
damping and the pendulum's inertia from the recordings patchgen.identify.rotary_benchtest
describes, the sensors' constants and noise from its calibration and quiet recordings.

- J_0 (the arm and the pendulum's mass at its tip, about the motor's axis): the links figures
  (uniform rods), through the plant's own equations.
- k_t = k_m: the motor step's drive k, J_0 and the links' R_m: k_t = k J_0 R_m (an ideal motor's
  torque and back-EMF constants are equal in SI units).
- D_r: the arm's own decay D_r / J_0, from the coast-downs (a_c) and the step (a_s - k_t k_m /
  (R_m J_0)), combined with a check that they agree, times J_0.
- D_p, J_p: the free swing (patchgen.identify.pendulum's fit), its effective length L and decay
  beta, with the pendulum's mass and centre (L_p / 2) from the links.
- sensors.alpha, sensors.theta and their noise: calibration and quiet.

Everything else (the amplifier, the encoders' counts, the random forces) is the base profile's.
"""

from __future__ import annotations

import math

import numpy as np

from patchgen.identify import pendulum, rotary_motor, sensors
from patchgen.identify.estimate import DELTA, Estimate, Parameter, TestFit, abs_estimate, combine_into, delta, normal
from patchgen.identify.figures import G_WORKBOOK, Links
from patchgen.identify.kalman import FitError
from patchgen.identify.recording import Recording
from patchgen.inputs.errors import InputError
from patchgen.plant.rotary_equations import RotaryParams, inertias
from patchgen.plant.rotary_pendulum import MEASURED
from patchgen.profiles.bench import BenchProfile

ROD_CENTRE = 0.5  # a uniform rod's centre of mass, as a fraction of its length from the pivot


def _j0(x: np.ndarray, g: float) -> float:
    """J_0 of arm mass, arm length, pendulum mass and length x, as the plant's equations make it."""
    p = RotaryParams(m_r=x[0], L_r=x[1], m_p=x[2], L_p=x[3], D_r=0.0, D_p=0.0, R_m=1.0, k_t=1.0, k_m=1.0, g=g)
    return inertias(p).J_0


def _per_rad(base: BenchProfile, q: str, rec: Recording) -> float:
    counts = base.sensors.counts_per_rev.get(q)
    if counts is None:
        raise rec.error(f"{q}_counts", f"the base bench {base.id} has no encoder on {q}: give --base a bench that does")
    return counts / (2 * math.pi)


def _fit(rec: Recording, base: BenchProfile, links: Links | None) -> TestFit | None:
    band = base.disturbance.bandwidth_Hz
    if rec.test == "calibration":
        return sensors.fit_calibration(rec)
    if rec.test == "quiet":
        return sensors.fit_quiet(rec)
    if rec.test == "integrator_drift":  # the machine's, on any bench
        return sensors.fit_drift(rec)
    if rec.test == "motor_step":
        return rotary_motor.fit_motor_step(rec, _per_rad(base, "alpha", rec), band)
    if rec.test == "arm_coast":
        return rotary_motor.fit_arm_coast(rec, _per_rad(base, "alpha", rec), band)
    if rec.test == "free_swing":
        return pendulum.fit_swing(rec, _per_rad(base, "theta", rec), links.g_m_per_s2 if links else G_WORKBOOK, band,
                                  links.m_p_kg if links else None, links.mass_uncertainty_kg if links else 0.0,
                                  "theta_counts")
    raise rec.error("test", f"{rec.test} is a cart's test: a rotary bench takes calibration, quiet, motor_step, "
                            "arm_coast, free_swing and integrator_drift")


def rotary_identify(result, recs: list[Recording], links: tuple[str, Links] | None, base: BenchProfile) -> None:
    """Fit every recording of a rotary bench and fill ``result`` (an Identification): its fits, the
    bench's sensor figures and the plant's figures, each with its interval."""
    src, fig = links if links else ("", None)
    for r in recs:
        try:
            fit = _fit(r, base, fig)
        except FitError as exc:
            raise r.error("", f"the {r.test} fit fails: {exc}") from None
        result.fits.append(fit)
    _sensors(result, base)
    drift = _pick(result, "integrator_drift", "drift")
    if drift:
        result.extra["drift_V_per_s"] = combine_into(result, [abs_estimate(e) for e in drift], "drift rate")
    if fig is None:
        result.warnings.append("no links figures (test = \"links\"): the arm's inertia, hence the motor and the "
                               "dampings, cannot be had from the decays alone")
        return
    plant = result.plant
    u_m, u_l = fig.mass_uncertainty_kg, fig.length_uncertainty_m
    for k, v, u, unit in (("m_r", fig.m_r_kg, u_m, "kg"), ("L_r", fig.L_r_m, u_l, "m"), ("m_p", fig.m_p_kg, u_m, "kg"),
                          ("L_p", fig.L_p_m, u_l, "m"), ("R_m", fig.R_m_ohm, fig.R_m_uncertainty_ohm, "ohm")):
        plant[k] = Parameter(v, unit, normal(v, u, unit, "measured (stated uncertainty)", src) if u > 0 else None, src)
    plant["g"] = Parameter(fig.g_m_per_s2, "m/s^2", None, src)
    x = np.array([fig.m_r_kg, fig.L_r_m, fig.m_p_kg, fig.L_p_m])
    cov = np.diag([u_m ** 2, u_l ** 2, u_m ** 2, u_l ** 2])
    j0, j0_se = delta(lambda v: _j0(v, fig.g_m_per_s2), x, cov)
    result.extra["J_0"] = normal(j0, j0_se, "kg m^2", DELTA, src)
    _motor(result, j0, j0_se, fig, src)
    _swing(result, fig, src)


def _pick(result, test: str, name: str) -> list[Estimate]:
    return [f.estimates[name] for f in result.fits if f.test == test and name in f.estimates]


def _motor(result, j0: float, j0_se: float, fig: Links, src: str) -> None:
    """k_t = k_m and D_r from the step's drive and decay and the coasts' decay. The arm's own decay
    D_r / J_0 is had twice (the coasts' a_c, the step's a_s - k_t k_m / (R_m J_0)), combined, and
    only then multiplied by J_0: J_0's error, common to both, is counted once."""
    steps, coasts = _pick(result, "motor_step", "k"), _pick(result, "arm_coast", "a")
    decays: list[Estimate] = []
    if coasts:
        decays.append(combine_into(result, coasts, "the arm's coast-down decay"))
    if steps:
        k = combine_into(result, steps, "the motor step's drive")
        a_s = combine_into(result, _pick(result, "motor_step", "a"), "the motor step's decay")
        x = np.array([k.value, a_s.value, j0, fig.R_m_ohm])
        cov = np.diag([k.se ** 2, a_s.se ** 2, j0_se ** 2, fig.R_m_uncertainty_ohm ** 2])
        kt, kt_se = delta(lambda v: v[0] * v[2] * v[3], x, cov)
        sources = ", ".join(dict.fromkeys(s for s in (k.source, src) if s))
        est = normal(kt, kt_se, "N m/A", f"k J_0 R_m; {DELTA}", sources, k.dof)
        result.plant["k_t"] = Parameter(kt, "N m/A", est, sources)
        result.plant["k_m"] = Parameter(kt, "V s/rad", Estimate(kt, est.low, est.high, "V s/rad", est.method, sources,
                                                                 est.dof), f"{sources} (k_m = k_t in SI units)")
        d, d_se = delta(lambda v: v[1] - v[0] * v[0] * v[2] * v[3], x, cov)  # a_s - k_t k_m / (R_m J_0)
        decays.insert(0, normal(d, d_se, "1/s", f"a_s - k^2 J_0 R_m; {DELTA}", a_s.source, a_s.dof))
    if not decays:
        return
    own = combine_into(result, decays, "D_r from the step and the coasts")
    value, se = delta(lambda v: v[0] * v[1], np.array([own.value, j0]), np.diag([own.se ** 2, j0_se ** 2]))
    est = normal(value, se, "N m s/rad", f"(D_r / J_0) J_0; {own.method}", own.source, own.dof)
    result.plant["D_r"] = Parameter(value, "N m s/rad", est, est.source)


def _swing(result, fig: Links, src: str) -> None:
    """D_p and J_p from the swing's effective length L and decay beta: J_2 = m_p l_p L (the pivot's
    inertia), D_p = beta J_2, J_p = J_2 - m_p l_p^2, l_p = L_p / 2."""
    lengths, decays = _pick(result, "free_swing", "l"), _pick(result, "free_swing", "beta")
    if not lengths:
        return
    L = combine_into(result, lengths, "the swing's effective length")
    beta = combine_into(result, decays, "the swing's decay")
    u_m, u_l = fig.mass_uncertainty_kg, fig.length_uncertainty_m
    x = np.array([L.value, beta.value, fig.m_p_kg, fig.L_p_m])
    cov = np.diag([L.se ** 2, beta.se ** 2, u_m ** 2, u_l ** 2])
    j2 = lambda v: v[2] * ROD_CENTRE * v[3] * v[0]
    d, d_se = delta(lambda v: v[1] * j2(v), x, cov)
    sources = ", ".join(dict.fromkeys((L.source, src)))
    est = normal(d, d_se, "N m s/rad", f"beta m_p l_p L; {DELTA}", sources, beta.dof)
    result.plant["D_p"] = Parameter(d, "N m s/rad", est, sources)
    jp, jp_se = delta(lambda v: j2(v) - v[2] * (ROD_CENTRE * v[3]) ** 2, x, cov)
    est = normal(jp, jp_se, "kg m^2", f"m_p l_p (L - l_p); {DELTA}", sources, L.dof)
    result.plant["J_p"] = Parameter(jp, "kg m^2", est, sources)


def _sensors(result, base: BenchProfile) -> None:
    """The card's volts per radian (calibration) and each output's noise and bandwidth (quiet), else the base's."""
    origin = f"base profile {base.id}"
    for q in MEASURED:
        found = _pick(result, "calibration", f"K_{q}")
        if found:
            est = combine_into(result, found, f"sensor constant {q}")
            result.bench[f"sensors.{q}"] = Parameter(est.value, "V/rad", est, est.source)
        else:
            result.bench[f"sensors.{q}"] = Parameter(getattr(base.sensors, q), "V/rad", None, origin)
        noise = _pick(result, "quiet", f"noise_{q}")
        if noise:
            est = combine_into(result, noise, f"noise on {q}")
            result.bench[f"sensors.noise_V_rms.{q}"] = Parameter(est.value, "V", est, est.source)
        elif q in base.sensors.noise_V_rms:
            result.bench[f"sensors.noise_V_rms.{q}"] = Parameter(base.sensors.noise_V_rms[q], "V", None, origin)
    bands = [b for q in MEASURED for b in _pick(result, "quiet", f"bandwidth_{q}") if b.high > b.low]
    if bands:
        est = combine_into(result, bands, "noise bandwidth")
        result.bench["sensors.noise_bandwidth_Hz"] = Parameter(est.value, "Hz", est, est.source)
    else:
        result.bench["sensors.noise_bandwidth_Hz"] = Parameter(base.sensors.noise_bandwidth_Hz, "Hz", None, origin)


def check_links(items, base: BenchProfile) -> tuple[str, Links] | None:
    """The one links file among the figures (a cart's figures on a rotary bench are refused)."""
    found = [(s, f) for s, f in items if isinstance(f, Links)]
    other = next(((s, f) for s, f in items if not isinstance(f, Links)), None)
    if other is not None:
        raise InputError(other[0], "test", f"{other[1].test} figures are a cart's: bench {base.id} is a rotary "
                                           "pendulum's (test = \"links\")")
    if len(found) > 1:
        raise InputError(found[1][0], "test", f"links given twice (also in {found[0][0]})")
    return found[0] if found else None
