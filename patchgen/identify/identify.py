"""From a set of recordings to the bench's and the plant's parameters: every file read and fitted,
each parameter taken from the test made for it (several recordings of one test combined by their
inverse variances, with a check that they agree), what no recording gives taken from a base bench
profile and said so.

Where each parameter comes from, first choice first:

| parameter | tests |
|---|---|
| actuator model, K_U, tau | actuator_step, else actuator_ramp |
| dead zone | actuator_ramp, else actuator_step |
| sensor constants s, theta | calibration, else the base profile |
| s_dot constant | coast_down (K_s / rho), else the base profile |
| noise levels, bandwidth | quiet, else the base profile |
| b_VF | coast_down (with masses), else incline |
| l, c | free_swing (c with masses) |
| drift rate | integrator_drift (reported; the machine profile holds drift) |

A column in encoder counts is read with the base profile's counts (patchgen.identify.encoders); the
base is the one given, else the one the recordings name (``# bench = <id>``), else DEFAULT_BASE. On
a bench whose cart a DC motor drives, the actuator and the cart's damping are the motor's
(patchgen.identify.motor).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path

from patchgen.identify import actuator, encoders, friction, motor, pendulum, sensors
from patchgen.identify.estimate import (
    Check,
    Estimate,
    Parameter,
    TestFit,
    abs_estimate,
    combine_into,
    normal,
    welch,
)
from patchgen.identify.figures import G_TABLE_B1, Incline, Links, Masses, read_figures
from patchgen.identify.kalman import FitError
from patchgen.identify.plausible import check_fit
from patchgen.identify.recording import Recording, expand, read_recording
from patchgen.identify.rotary_identify import check_links, rotary_identify
from patchgen.inputs.drive_fields import motor_of
from patchgen.inputs.errors import InputError
from patchgen.plant.cart_pendulum import MEASURED
from patchgen.plant.plant_model import ROTARY
from patchgen.profiles.bench import BenchProfile, load_bench

FITTED_COLUMN = {"actuator_step": "force_N", "actuator_ramp": "force_N", "coast_down": "s_dot_V",
                 "free_swing": "theta_V", "integrator_drift": "out_V"}  # the channel each fit explains
MIN_LAG_S = 1e-3  # a bench lag shorter than this is written as a pure gain (the profile's own floor)
ROTARY_TESTS = ("motor_step", "arm_coast")  # recorded on a rotary pendulum's bench alone
DEFAULT_BASE = "uw-1991"  # the base profile when none is given and no recording names its bench


@dataclass
class Identification:
    """Everything identify found: the fits, the bench profile's and the plant's parameters (dotted
    names, e.g. ``actuator.K_U``), the checks across recordings, and warnings."""

    fits: list[TestFit]
    bench: dict[str, Parameter]
    plant: dict[str, Parameter]
    extra: dict[str, Estimate]
    checks: list[Check] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    base: str = ""
    profile: BenchProfile | None = None  # the base profile itself


def read_all(paths: list[str]) -> list[Recording | tuple[str, Masses | Incline | Links]]:
    """Every recording and figures file the paths name (folders expanded), read and checked, each
    once: a file named twice (by two paths) or two files of identical samples or figures would count
    one test's data as two, and narrow its interval as new data would."""
    out: list[Recording | tuple[str, Masses | Incline | Links]] = []
    seen: dict[object, str] = {}
    for f in expand(paths):
        suffix = Path(f).suffix
        real = os.path.realpath(f)
        if real in seen:
            raise InputError(f, "test", f"given twice (also as {seen[real]}): a recording counts once")
        seen[real] = f
        if suffix == ".csv":
            item: Recording | tuple[str, Masses | Incline | Links] = read_recording(f)
            content = (item.test, tuple((k, v.tobytes()) for k, v in sorted(item.columns.items())))
        elif suffix == ".toml":
            item = (f, read_figures(f))
            content = (item[1].test, tuple(sorted(item[1].model_dump().items())))
        else:
            raise InputError(f, "", "not a recording (.csv) or test figures (.toml)")
        if content in seen:
            raise InputError(f, "test", f"the same {content[0]} data as {seen[content]} (identical numbers): "
                                        "a recording counts once")
        seen[content] = f
        out.append(item)
    return out


def _pick(fits: list[TestFit], tests: tuple[str, ...], name: str) -> list[Estimate]:
    """Estimates of ``name`` from the first of ``tests`` that has any."""
    for test in tests:
        found = [f.estimates[name] for f in fits if f.test == test and name in f.estimates]
        if found:
            return found
    return []


def base_profile(recs: list[Recording], base: BenchProfile | None) -> tuple[BenchProfile, list[str]]:
    """The base profile: the one given, else the one the recordings name (``# bench = <id or path>``),
    else DEFAULT_BASE; and a warning when the recordings name another than the one given.

    Raises
    ------
    InputError
        Recordings that name two benches, or a bench that cannot be read (naming the file and ``bench``).
    """
    named = [(r.source, r.notes["bench"]) for r in recs if r.notes.get("bench")]
    other = next(((s, n) for s, n in named if n != named[0][1]), None)
    if other is not None and base is None:
        raise InputError(other[0], "bench", f"names bench {other[1]!r}, {named[0][0]} names {named[0][1]!r}: "
                                            "recordings of one bench, or give it with --base")
    if base is not None:
        wrong = [n for _, n in named if n != base.id]
        return base, [f"the recordings name bench {wrong[0]!r}; identify took the profile given, {base.id!r}"] \
            if wrong else []
    if named:
        return load_bench(named[0][1], named[0][0], "bench"), []
    return load_bench(DEFAULT_BASE), []


def identify(paths: list[str], base: BenchProfile | None = None) -> Identification:
    """Read and fit every recording, and gather the bench's and plant's parameters.

    Parameters
    ----------
    paths : list of str
        Recording files (CSV), test-figure files (TOML) and folders of them.
    base : BenchProfile, optional
        Where what the recordings do not give comes from (force limit, track, random forces, a
        motor's figures, encoders' counts, and any sensor constant or noise level not recorded);
        None: the bench the recordings name, else DEFAULT_BASE (base_profile).

    Returns
    -------
    Identification
        The fits and the parameters; InputError for a bad or unexciting recording.
    """
    items = read_all(paths)
    recs = [it for it in items if isinstance(it, Recording)]
    base, notes = base_profile(recs, base)
    if base.plant == ROTARY.name:  # its own tests (patchgen.identify.rotary_identify)
        figures = [it for it in items if isinstance(it, tuple)]
        result = Identification([], {}, {}, {}, warnings=notes, base=base.id, profile=base)
        rotary_identify(result, recs, check_links(figures, base), base)
        return result
    for r in recs:
        if r.test in ROTARY_TESTS:
            raise r.error("", f"{r.test} is a rotary pendulum's test: bench {base.id} is a cart's (give --base a "
                              "rotary bench)")
    for src, _ in (it for it in items if isinstance(it, tuple) and isinstance(it[1], Links)):
        raise InputError(src, "test", f"links figures are a rotary pendulum's: bench {base.id} is a cart's")
    masses = [(src, f) for it in items if isinstance(it, tuple) for src, f in [it] if isinstance(f, Masses)]
    if len(masses) > 1:
        raise InputError(masses[1][0], "test", f"masses given twice (also in {masses[0][0]})")
    mass_src, mass = masses[0] if masses else ("", None)
    fits: list[TestFit] = []
    for r in recs:
        if r.test == "calibration":
            for q in ("s", "theta"):
                if f"{q}_counts" in r.columns:
                    encoders.constant_of(r, q, base, 0.0)  # a count on a bench without that encoder: refused
            fits.append(sensors.fit_calibration(r))
            check_fit(fits[-1], base.sensors.s, None)
    result = Identification(fits, {}, {}, {}, warnings=notes, base=base.id, profile=base)
    encoders.check_counts(result, base)
    k_s = _constant(result, "K_s", "sensors.s", base.sensors.s, "V/m")
    k_theta = _constant(result, "K_theta", "sensors.theta", base.sensors.theta, "V/rad")
    g = mass.g_m_per_s2 if mass else G_TABLE_B1
    for r in recs:
        try:
            fit = _fit(r, base, k_theta, g, mass)
        except FitError as exc:
            raise r.error(FITTED_COLUMN.get(r.test, ""), f"the {r.test} fit fails: {exc}") from None
        if fit is not None:
            check_fit(fit, k_s, mass.M_kg + mass.m_kg if mass else None)
            fits.append(fit)
    for src, fig in (it for it in items if isinstance(it, tuple)):
        if isinstance(fig, Incline):
            fits.append(friction.fit_incline(fig, src))
            if motor_of(base.actuator) is not None:
                result.warnings.append(f"{src}: B.2 has no rotor and no back-EMF, which a motor-driven cart has: "
                                       "its b_VF is used only without a coast-down")
    _actuator(result, base)
    if motor_of(base.actuator) is not None:
        motor.actuator(result, base)
    _sensors(result, base, k_s)
    _plant(result, mass, mass_src, motor_of(base.actuator))
    drift = [abs_estimate(e) for e in _pick(fits, ("integrator_drift",), "drift")]
    if drift:
        result.extra["drift_V_per_s"] = combine_into(result, drift, "drift rate")
    return result


def _fit(r: Recording, base: BenchProfile, k_theta: float, g: float, mass: Masses | None) -> TestFit | None:
    """One recording's fit (calibrations are fitted first, by the caller)."""
    band = base.disturbance.bandwidth_Hz
    if r.test == "actuator_step":
        lagless = motor_of(base.actuator) is not None and base.actuator.motor_lag() == 0
        return motor.fit_step_gain(r) if lagless else actuator.fit_step(r)
    if r.test == "actuator_ramp":
        return actuator.fit_ramp(r)
    if r.test == "coast_down":
        column, per_m = encoders.constant_of(r, "s", base, 0.0)
        filt = base.sensors.filters().get("s_dot")
        if column.endswith("_counts") and filt is not None:
            return encoders.fit_coast_filtered(r, per_m, filt, band)
        return friction.fit_coast(r, band, column)
    if r.test == "free_swing":
        column, gain = encoders.constant_of(r, "theta", base, k_theta)
        return pendulum.fit_swing(r, gain, g, band, mass.m_kg if mass else None,
                                  mass.m_uncertainty_kg if mass else 0.0, column)
    if r.test == "quiet":
        return sensors.fit_quiet(r)
    if r.test == "integrator_drift":
        return sensors.fit_drift(r)
    return None


def _constant(result: Identification, name: str, key: str, fallback: float, unit: str) -> float:
    found = _pick(result.fits, ("calibration",), name)
    if found:
        est = combine_into(result, found, f"sensor constant {key}")
        result.bench[key] = Parameter(est.value, unit, est, est.source)
        return est.value
    result.bench[key] = Parameter(fallback, unit, None, f"base profile {result.base}")
    return fallback


def _actuator(result: Identification, base: BenchProfile) -> None:
    fits = result.fits
    step = [f for f in fits if f.test == "actuator_step"]
    models = sorted({n.removeprefix("model: ") for f in step for n in f.notes if n.startswith("model: ")})
    if len(models) > 1:
        result.warnings.append(f"the step recordings disagree on the actuator's model ({', '.join(models)}): "
                               "the profile takes lag")
    model = models[0] if len(models) == 1 else ("lag" if step or any(f.test == "actuator_ramp" for f in fits)
                                                 else base.actuator.model)
    gains = _pick(fits, ("actuator_step", "actuator_ramp"), "K_U") if len(models) <= 1 else [
        f.estimates["K_U"] for f in step if "model: lag" in f.notes]
    if gains:
        K = combine_into(result, gains, "K_U")
        taus = _pick(fits, ("actuator_step", "actuator_ramp"), "tau") if len(models) <= 1 else [
            f.estimates["tau"] for f in step if "model: lag" in f.notes]  # tau from the same fits as K_U
        tau = combine_into(result, taus, "tau") if model != "gain" else None  # a gain's step fits no lag
        if model == "lag" and tau.value < MIN_LAG_S:
            model = "gain"
        result.bench["actuator.model"] = Parameter(model, "", None, K.source)
        result.bench["actuator.K_U"] = Parameter(K.value, K.unit, K, K.source)
        result.bench["actuator.tau"] = (Parameter(0.0, "s", None, K.source) if tau is None else
                                        Parameter(0.0 if model == "gain" else tau.value, "s", tau, tau.source))
    else:
        origin = f"base profile {result.base}"
        result.bench["actuator.model"] = Parameter(base.actuator.model, "", None, origin)
        result.bench["actuator.K_U"] = Parameter(base.actuator.K_U, "N/V", None, origin)
        result.bench["actuator.tau"] = Parameter(base.actuator.tau, "s", None, origin)
    # the step first: its held levels pin the dead zone once the lag has settled, where in a ramp the
    # lag, the dead zone and any hysteresis all shift the same edges
    dz = _pick(fits, ("actuator_step", "actuator_ramp"), "dead_zone")
    if dz:
        est = combine_into(result, dz, "dead zone")
        result.bench["actuator.dead_zone_V"] = Parameter(max(est.value, 0.0), "V", est, est.source)
    else:
        result.bench["actuator.dead_zone_V"] = Parameter(base.actuator.dead_zone_V, "V", None,
                                                         f"base profile {result.base}")
    result.bench["actuator.force_limit_N"] = Parameter(base.actuator.force_limit_N, "N", None,
                                                       f"base profile {result.base} (not identified)")


def _sensors(result: Identification, base: BenchProfile, k_s: float) -> None:
    rho = _pick(result.fits, ("coast_down",), "rho")
    direct = _pick(result.fits, ("coast_down",), "K_s_dot")  # a filtered velocity's, against its position
    if direct:
        est = combine_into(result, direct, "K_s_dot")
        result.bench["sensors.s_dot"] = Parameter(est.value, est.unit, est, est.source)
    elif rho:
        r = combine_into(result, rho, "rho = K_s / K_s_dot")
        ks = result.bench["sensors.s"].estimate
        ks_se = ks.se if ks else 0.0
        value = k_s / r.value
        se = value * math.hypot(ks_se / k_s, r.se / r.value)
        dof = welch([(value * ks_se / k_s, ks.dof if ks else math.inf), (value * r.se / r.value, r.dof)])
        est = normal(value, se, "V/(m/s)", f"K_s / rho; {r.method}", r.source, dof)
        result.bench["sensors.s_dot"] = Parameter(value, est.unit, est, est.source)
    else:
        result.bench["sensors.s_dot"] = Parameter(base.sensors.s_dot, "V/(m/s)", None, f"base profile {result.base}")
    for s in MEASURED:
        found = _pick(result.fits, ("quiet",), f"noise_{s}")
        if found:
            est = combine_into(result, found, f"noise on {s}")
            result.bench[f"sensors.noise_V_rms.{s}"] = Parameter(est.value, "V", est, est.source)
        elif s in base.sensors.noise_V_rms:
            result.bench[f"sensors.noise_V_rms.{s}"] = Parameter(base.sensors.noise_V_rms[s], "V", None,
                                                                 f"base profile {result.base}")
    bands = [f.estimates[k] for f in result.fits if f.test == "quiet" for k in f.estimates
             if k.startswith("bandwidth_")]
    resolved = [b for b in bands if b.high > b.low]
    if resolved:
        est = combine_into(result, resolved, "noise bandwidth")
        result.bench["sensors.noise_bandwidth_Hz"] = Parameter(est.value, "Hz", est, est.source)
    elif bands:
        top = max(bands, key=lambda b: b.value)
        result.bench["sensors.noise_bandwidth_Hz"] = Parameter(top.value, "Hz", None,
                                                               f"{top.source}: at least half the sample rate")
        result.warnings.append("the quiet recordings do not resolve the noise's bandwidth (white at their rate): "
                               "the profile takes half the sample rate with the in-band level (the same density)")
    else:
        result.bench["sensors.noise_bandwidth_Hz"] = Parameter(base.sensors.noise_bandwidth_Hz, "Hz", None,
                                                               f"base profile {result.base}")


def _plant(result: Identification, mass: Masses | None, mass_src: str, drive=None) -> None:
    fits, plant = result.fits, result.plant
    if mass is not None:
        plant["M"] = Parameter(mass.M_kg, "kg", None, mass_src)
        plant["m"] = Parameter(mass.m_kg, "kg", None, mass_src)
        plant["g"] = Parameter(mass.g_m_per_s2, "m/s^2", None, mass_src)
    lengths = _pick(fits, ("free_swing",), "l")
    if lengths:
        est = combine_into(result, lengths, "l")
        plant["l"] = Parameter(est.value, "m", est, est.source)
    decay = _pick(fits, ("coast_down",), "decay")
    if decay and mass is not None:
        a = combine_into(result, decay, "b_VF / (M + m)")
        total = mass.M_kg + mass.m_kg + motor.moving_mass(drive)  # with a motor, the rotor moves with the cart
        total_se = math.hypot(mass.M_uncertainty_kg, mass.m_uncertainty_kg)
        est = normal(a.value * total, math.hypot(a.se * total, a.value * total_se), "kg/s", a.method, a.source,
                     welch([(a.se * total, a.dof), (a.value * total_se, math.inf)]))
        plant["b_VF"] = Parameter(est.value, "kg/s", est, est.source)
        if drive is not None:
            motor.damping(result, drive, est)
        for f in fits:
            if f.test == "coast_down" and "coulomb" in f.estimates and "sensors.s_dot" in result.bench:
                c = f.estimates["coulomb"]
                k = 1.0 if c.unit == "m/s^2" else float(result.bench["sensors.s_dot"].value)
                result.extra[f"coulomb_N ({f.source})"] = normal(c.value * total / k, c.se * total / k, "N",
                                                                 c.method, f.source, c.dof)
    elif decay:
        result.warnings.append("the coast-down gives b_VF / (M + m): a masses file (test = \"masses\") turns it "
                               "into b_VF")
    if "b_VF" not in plant:
        slides = _pick(fits, ("incline",), "b_VF")
        if slides:
            est = combine_into(result, slides, "b_VF (incline)")
            plant["b_VF"] = Parameter(est.value, "kg/s", est, est.source)
    damping = _pick(fits, ("free_swing",), "c")
    if damping:
        est = combine_into(result, damping, "c")
        plant["c"] = Parameter(est.value, "kg m^2/s", est, est.source)
    if lengths and mass is not None and mass.l_cm_m is not None:
        pendulum.rigid(result, mass.m_kg, mass.l_cm_m, mass_src)
    elif lengths:
        result.warnings.append("the free swing gives c / (m l^2): a masses file (test = \"masses\") turns it into c")
    if mass is not None and mass.d_m is not None:
        plant["d"] = Parameter(mass.d_m, "m", None, mass_src)

