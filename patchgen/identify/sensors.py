"""The sensors and the machine at rest: calibration (V per SI unit), quiet recordings (noise level
and bandwidth), a held integrator (drift).

A quiet sensor's noise is taken as the simulator draws it (patchgen.bench.engine.noise_process):
rms sigma over an equivalent bandwidth B, an AR(1) sequence at the recording's step dt with
memory a = (q - 1) / (q + 1), q = 1 / (2 dt B). The lag-1 autocorrelation estimates a, hence
B = (1 - a) / ((1 + a) 2 dt); the sample variance, sigma^2, with the AR(1) sequence's effective
degrees of freedom n (1 - a^2) / (1 + a^2) for its chi-square interval. A recording sampled at
or below 2 B sees white noise: its bandwidth is then only known to be at least half the sample
rate, and the level it gives is the in-band part, which keeps the low-frequency noise density
sigma^2 / B the loop sees.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import stats

from patchgen.identify import lsq
from patchgen.identify.estimate import CHI2_AR1, LSQ_HAC, OLS, Z95, Estimate, Panel, TestFit, normal
from patchgen.identify.recording import Recording

QUIET_LIMIT = 8.0  # a quiet sample beyond this many noise levels (median-based) means the rig moved
QUIET_BLOCKS = 10  # the recording in this many parts, for a noise scale that a disturbance in one part leaves alone
SENSORS = {"s_V": ("s", "V/m", "s_m", "m"), "theta_V": ("theta", "V/rad", "theta_rad", "rad"),
           "alpha_V": ("alpha", "V/rad", "alpha_rad", "rad"),
           "s_counts": ("s_counts", "counts/m", "s_m", "m"), "theta_counts": ("theta_counts", "counts/rad",
                                                                                "theta_rad", "rad")}


def fit_calibration(rec: Recording) -> TestFit:
    """Sensor constants from readings at positions and angles set by hand: V = K x + V0, ordinary
    least squares, t intervals.

    Parameters
    ----------
    rec : Recording
        A ``calibration`` recording (s_m with s_V and/or theta_rad with theta_V).

    Returns
    -------
    TestFit
        Estimates ``K_s`` (V/m) and/or ``K_theta`` (V/rad); read on an encoder, ``K_s_counts``
        (counts/m) and/or ``K_theta_counts`` (counts/rad).
    """
    est, panels = {}, []
    for col, (name, unit, ref, ref_unit) in SENSORS.items():
        if col not in rec.columns:
            continue
        x, v = rec.columns[ref], rec.columns[col]
        if np.unique(x).size < 3:
            raise rec.error(ref, f"{np.unique(x).size} distinct settings: a calibration needs at least three, "
                                 "spread over the range the sensor is used in")
        _unclipped(rec, col, ref, x, v)
        X = np.column_stack([x, np.ones_like(x)])
        coef, *_ = np.linalg.lstsq(X, v, rcond=None)
        resid = v - X @ coef
        dof = x.size - 2
        s2 = float(resid @ resid) / dof
        se = math.sqrt(s2 * np.linalg.inv(X.T @ X)[0, 0])
        tq = float(stats.t.ppf(0.975, dof))
        if abs(coef[0]) <= tq * se:
            raise rec.error(col, f"the voltage does not follow the {ref_unit} setting (slope {coef[0]:.3g} +/- "
                                 f"{tq * se:.2g} {unit}, not clear of zero): is the sensor connected?")
        est[f"K_{name}"] = Estimate(float(coef[0]), float(coef[0] - tq * se), float(coef[0] + tq * se), unit, OLS,
                                    rec.source, dof)
        order = np.argsort(x, kind="stable")
        panels.append(Panel(x[order], v[order], (X @ coef)[order], f"{name} ({unit.split('/')[0]})",
                            xlabel=f"{name} ({ref_unit})", points=True))
    return TestFit(rec.source, rec.test, est, panels=panels, title="sensor calibration")


def _unclipped(rec: Recording, col: str, ref: str, x: np.ndarray, v: np.ndarray) -> None:
    """Refuse a calibration whose largest or smallest reading is the same voltage at two or more
    settings: a pot or amplifier at its limit (a noisy reading never repeats to the last digit)."""
    for end in (v.max(), v.min()):
        settings = np.unique(x[v == end])
        if settings.size > 1 and np.unique(v).size > 2:
            raise rec.error(col, f"clipped: reads exactly {end:.6g} V at {settings.size} settings of {ref} "
                                 f"({settings.min():g} to {settings.max():g}): the sensor is at its limit there; "
                                 "calibrate within its range")


# no sensor and no amplifier output is free of noise: a channel that is exactly a constant (or a line)
# is disconnected, saturated or synthetic, and its "noise level" of 0 would be a verdict about nothing
ROUNDING = 1e-9  # residual rms, relative to the largest |voltage|, that is the line fit's own rounding
CONSTANT = "exactly constant about its trend (no noise at all): is the channel connected, or saturated?"

def noise_level(x: np.ndarray, dt: float, source: str) -> tuple[Estimate, Estimate, bool]:
    """(rms, bandwidth, resolved) of a quiet sensor's voltage, its mean and trend removed.

    Returns
    -------
    rms : Estimate
        V rms, chi-square interval with the AR(1) effective degrees of freedom.
    bandwidth : Estimate
        Hz; when not resolved (white at this rate), half the sample rate with the interval
        [fs / 2, inf) written as [fs / 2, fs / 2].
    resolved : bool
        Whether the samples resolve the bandwidth (lag-1 autocorrelation clear of zero).
    """
    n = x.size
    t = np.arange(n)
    r = x - np.polyval(np.polyfit(t, x, 1), t)
    var = float(r @ r) / (n - 2)
    if math.sqrt(var) <= ROUNDING * float(np.max(np.abs(x))):
        raise ValueError(CONSTANT)
    a = float(r[1:] @ r[:-1]) / float(r @ r)
    a = min(max(a, -0.999), 0.999)
    se_a = math.sqrt((1 - a * a) / n)
    resolved = a > Z95 * se_a
    a_use = a if resolved else 0.0
    nu = n * (1 - a_use ** 2) / (1 + a_use ** 2)
    lo, hi = nu * var / stats.chi2.ppf(0.975, nu), nu * var / stats.chi2.ppf(0.025, nu)
    rms = Estimate(math.sqrt(var), math.sqrt(lo), math.sqrt(hi), "V", CHI2_AR1, source, nu,
                   std_error=math.sqrt(var / (2 * nu)))
    if not resolved:
        return rms, Estimate(0.5 / dt, 0.5 / dt, 0.5 / dt, "Hz", "not resolved: at least half the sample rate",
                             source), False
    band = lambda aa: (1 - aa) / ((1 + aa) * 2 * dt)
    a_lo, a_hi = max(a - Z95 * se_a, 1e-9), min(a + Z95 * se_a, 0.999999)
    return rms, Estimate(band(a), band(a_hi), band(a_lo), "Hz", "lag-1 autocorrelation of the AR(1) noise",
                         source, std_error=se_a / (dt * (1 + a) ** 2)), True


def _local_scale(r: np.ndarray, blocks: int = QUIET_BLOCKS) -> float:
    """The noise's scale as the median over blocks of each block's own robust scale (1.4826 MAD
    about its median): a step, a slow swing or a burst in part of the recording leaves it alone,
    where one scale over the whole recording would grow with them and hide them."""
    parts = np.array_split(r, blocks)
    return float(np.median([1.4826 * np.median(np.abs(p - np.median(p))) for p in parts]))


def _noise_of(rec: Recording, col: str, x: np.ndarray) -> tuple[Estimate, Estimate, bool]:
    """:func:`noise_level` of one column, a channel without any noise refused by name."""
    try:
        return noise_level(x, rec.dt, rec.source)
    except ValueError:
        raise rec.error(col, CONSTANT) from None


def fit_quiet(rec: Recording) -> TestFit:
    """Each recorded sensor's noise level (V rms) and bandwidth (Hz) from a quiet recording.

    Parameters
    ----------
    rec : Recording
        A ``quiet`` recording (t_s and any of s_V, theta_V, s_dot_V), the rig clamped at rest.

    Returns
    -------
    TestFit
        Estimates ``noise_<sensor>`` and ``bandwidth_<sensor>`` per sensor recorded.
    """
    t, dt = rec.columns["t_s"], rec.dt
    est, panels, notes = {}, [], []
    for col in ("s_V", "theta_V", "s_dot_V", "alpha_V"):
        if col not in rec.columns:
            continue
        x = rec.columns[col]
        r = x - np.polyval(np.polyfit(t, x, 1), t)
        robust = _local_scale(r)
        if robust > 0 and np.max(np.abs(r)) > QUIET_LIMIT * robust:
            k = int(np.argmax(np.abs(r)))
            raise rec.error(col, f"not quiet: {r[k]:.3g} V off its level at {t[k]:.3g} s, {abs(r[k]) / robust:.0f} "
                                 "noise levels: clamp the cart and the pendulum and keep the bench still")
        name = col.removesuffix("_V")
        rms, band, resolved = _noise_of(rec, col, x)
        est[f"noise_{name}"] = rms
        est[f"bandwidth_{name}"] = band
        if not resolved:
            notes.append(f"{col}: white at {1 / dt:g} Hz; its bandwidth is at least {0.5 / dt:g} Hz (sample faster "
                         "to resolve it); the level is the in-band part")
        shown = min(x.size, int(round(0.2 / dt)) + 1)
        panels.append(Panel(t[:shown], r[:shown], None, f"{name} (V), first 0.2 s"))
    return TestFit(rec.source, rec.test, est, notes=notes, panels=panels, title="quiet sensors")


def fit_drift(rec: Recording) -> TestFit:
    """An integrator's drift rate (V/s) with its inputs grounded: a line through its output, least
    squares with the Newey-West covariance.

    Parameters
    ----------
    rec : Recording
        An ``integrator_drift`` recording (t_s, out_V).

    Returns
    -------
    TestFit
        Estimates ``drift`` (V/s, signed) and ``output_noise`` (V rms about the line).
    """
    t, v = rec.columns["t_s"], rec.columns["out_V"]
    tc = t - t.mean()
    first = np.polyfit(tc, v, 1)
    spread = max(float(np.std(v - np.polyval(first, tc))), 1e-12)
    fit = lsq.fit(lambda p: p[0] * tc + p[1] - v, first, np.array([spread / max(np.ptp(t), 1e-9), spread]))
    est = {"drift": normal(fit.p[0], fit.se(0), "V/s", LSQ_HAC, rec.source)}
    est["output_noise"], _, _ = _noise_of(rec, "out_V", v)
    line = fit.p[0] * tc + fit.p[1]
    return TestFit(rec.source, rec.test, est, title="held integrator",
                   notes=[f"drift {abs(fit.p[0]) * 1e3:.3g} mV/s: a scenario's drift = {abs(fit.p[0]):.3g} "
                          "(V/s; its sign is drawn per amplifier)"],
                   panels=[Panel(t, v, line, "out (V)"), Panel(t, v - line, None, "residual (V)")])
