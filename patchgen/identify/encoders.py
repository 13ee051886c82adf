"""Recordings read on encoders, and the velocity a bench without a tachometer has (a Quanser IP02's).

An encoder is a sensor whose constant is its count per SI unit: ``counts_per_m`` for the cart's
position, ``counts_per_rev`` / 2 pi for the pendulum's angle (patchgen.profiles.bench). The fits
take a column in counts exactly as they take a pot's voltage, with that constant in place of the
pot's; the bench profile identify is given (or the one the recordings name) states it, and a
recording in counts on a bench profile without that encoder is refused by its column.

A filtered velocity is the rate of the encoder's position through wn^2 / (s^2 + 2 zeta wn s + wn^2)
(``velocity_filter``): its coast-down is not the tachometer's first-order decay, so it is fitted
in two parts. The decay comes from the encoder's position alone, by maximum likelihood through a
Kalman filter that carries the random force (patchgen.identify.encoder_coast; Coulomb friction
when the data show it);
the velocity's constant (V per m/s) is the regression of the recorded voltage on the same filter
of the recorded position (exact for a position linear between samples).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import expm
from scipy.signal import dlsim

from patchgen.identify import encoder_coast, lsq
from patchgen.identify.estimate import LSQ_HAC, Z_REJECT, Check, Panel, TestFit, normal
from patchgen.identify.recording import COUNTS, Recording
from patchgen.profiles.bench import BenchProfile, VelocityFilter

END_FRACTION = 0.05  # the position's coast is fitted until the cart has slowed to this of its top speed
MIN_COAST_SAMPLES = 20  # samples of the free coast the decay needs
SETTLE_TIMES = 5.0  # the filter's time constants 1 / (zeta wn) left out at the start of the regression


def counts_per_unit(base: BenchProfile, quantity: str) -> float | None:
    """An encoder's counts per SI unit of ``quantity`` (per m, per rad) on ``base``; None without one."""
    quantum = base.sensors.quanta().get(quantity)
    return None if quantum is None else 1.0 / quantum


def constant_of(rec: Recording, quantity: str, base: BenchProfile, pot: float) -> tuple[str, float]:
    """The column a recording reads ``quantity`` in and its constant: the pot's (V per unit) or the
    encoder's (counts per unit, from the bench profile).

    Raises
    ------
    InputError
        A column in counts on a bench profile that states no encoder for it.
    """
    column = f"{quantity}_{COUNTS}"
    if column not in rec.columns:
        return f"{quantity}_V", pot
    per_unit = counts_per_unit(base, quantity)
    if per_unit is None:
        field = "counts_per_m" if quantity == "s" else "counts_per_rev"
        raise rec.error(column, f"recorded in counts, but the bench profile {base.id} states no encoder for "
                                f"{quantity} (sensors.{field}): name the bench the recordings were made on with "
                                "--base, or a '# bench =' line")
    return column, per_unit


def check_counts(result, base: BenchProfile) -> None:
    """Each calibration's count per unit (``K_s_counts``, ``K_theta_counts``) against the bench
    profile's, with which every recording in counts is read: a check, and a warning when the
    calibration rejects the profile's count (the profile keeps its own: an encoder's count is its
    make's, a calibration's slip more likely than the encoder's)."""
    for fit in result.fits:
        for q, name in (("s", "K_s_counts"), ("theta", "K_theta_counts")):
            e = fit.estimates.get(name)
            own = counts_per_unit(base, q)
            if e is None or own is None:
                continue
            z = abs(e.value - own) / e.se if e.se > 0 else 0.0
            bad = not e.covers(own)
            text = (f"{fit.source}: the encoder reads {e.value:.6g} {e.unit} (95 %: {e.low:.6g} to {e.high:.6g}); "
                    f"the bench profile {base.id} counts {own:.6g}, with which the recordings in counts are read")
            result.checks.append(Check(f"encoder count {q}", z, Z_REJECT, bad, text))
            if bad:
                result.warnings.append(text + ": they differ (a mark set off, or the profile's count)")


def filtered_rate(x: np.ndarray, dt: float, filt: VelocityFilter) -> np.ndarray:
    """The rate of x through wn^2 / (s^2 + 2 zeta wn s + wn^2), x linear between samples, from rest at x[0].

    Parameters
    ----------
    x : ndarray
        The position at step dt (any unit).
    dt : float
        The step (s).
    filt : VelocityFilter
        The filter (wn, zeta).

    Returns
    -------
    ndarray
        The filter's output rate at each sample (x's unit per second).
    """
    wn, ze = filt.wn_rad_s, filt.zeta
    M = np.zeros((4, 4))
    M[0, 1], M[1, 0], M[1, 1], M[1, 2], M[2, 3] = 1.0, -wn * wn, -2.0 * ze * wn, wn * wn, 1.0
    E = expm(M * dt)
    Phi, G0, G1 = E[:2, :2], E[:2, 2], E[:2, 3] / dt  # x' = Phi x + G0 u_k + G1 (u_{k+1} - u_k)
    B = np.column_stack([G0 - G1, G1])
    x = np.asarray(x, float)
    u = np.column_stack([x, np.append(x[1:], x[-1])])
    _, y, _ = dlsim((Phi, B, np.array([[0.0, 1.0]]), np.zeros((1, 2)), dt), u, x0=np.array([x[0], 0.0]))
    return y[:, 0]


def _free_coast(p: np.ndarray, t: np.ndarray, sign: float) -> np.ndarray:
    """The coast's position: p = a, z0, v0 and, when given, the Coulomb deceleration f (m/s^2)."""
    a, z0, v0 = p[:3]
    f = p[3] * sign if p.size > 3 else 0.0
    decay = -np.expm1(-a * t) / a
    return z0 + (v0 + f / a) * decay - f / a * t


def fit_coast_filtered(rec: Recording, per_m: float, filt: VelocityFilter, force_bandwidth_Hz: float
                       ) -> TestFit:
    """Fit a coast-down read on the cart's encoder (``s_counts``) with a filtered velocity (``s_dot_V``).

    Parameters
    ----------
    rec : Recording
        A ``coast_down`` recording (t_s, s_counts, s_dot_V).
    per_m : float
        The encoder's counts per metre (the bench profile's).
    filt : VelocityFilter
        The velocity's filter (the bench profile's).
    force_bandwidth_Hz : float
        The random force's bandwidth (the bench profile's), which the Kalman filter carries.

    Returns
    -------
    TestFit
        Estimates ``decay`` (the total damping over the moving mass, 1/s), ``K_s_dot`` (V/(m/s)),
        ``tach_offset`` (V) and, when the data show it, ``coulomb`` (m/s^2).
    """
    t_all, w_all = rec.columns["t_s"], rec.columns["s_dot_V"]
    z_all = rec.columns[f"s_{COUNTS}"] / per_m
    dt = rec.dt
    v = np.gradient(z_all, dt)
    k0 = int(np.argmax(np.abs(v)))
    top = abs(v[k0])
    if top * dt * per_m < 5.0:
        raise rec.error(f"s_{COUNTS}", f"the cart never moves faster than {top:.3g} m/s: push the cart harder")
    below = np.flatnonzero(np.abs(v[k0:]) < END_FRACTION * top)
    if below.size == 0:
        raise rec.error("s_dot_V", f"the cart does not slow to {END_FRACTION:.0%} of its top speed in the "
                                   "recording: record until it has nearly stopped")
    k0, k1 = k0 + 1, k0 + int(below[0])
    if k1 - k0 < MIN_COAST_SAMPLES:
        raise rec.error("t_s", f"only {k1 - k0} samples while the cart coasts: record faster "
                               f"(the cart slows in {(k1 - k0) * dt:.3g} s)")
    t, z = t_all[k0:k1] - t_all[k0], z_all[k0:k1]
    sign = float(np.sign(v[k0]))
    a0 = max(math.log(abs(v[k0]) / max(abs(v[k1]), 1e-9)) / max(t[-1], dt), 1e-3)
    fit, zc, _ = encoder_coast.fit_position(z, dt, sign, 4.0 * force_bandwidth_Hz, (a0, v[k0]),
                                            max(1.0 / (12.0 * per_m * per_m), 1e-18))
    est, checks, p = encoder_coast.coast_estimates(fit, zc, rec.source, "decay", "m/s^2", "force")
    rate = filtered_rate(z_all, dt, filt)
    keep = t_all - t_all[0] >= SETTLE_TIMES / (filt.zeta * filt.wn_rad_s)
    y, w = rate[keep], w_all[keep]
    k_start = float(np.polyfit(y, w, 1)[0])
    gain = lsq.fit(lambda p: p[0] * y + p[1] - w, np.array([k_start, 0.0]),
                   np.array([1e-2 * abs(k_start) or 1e-3, 1e-3 * max(np.ptp(w), 1e-9)]))
    est["K_s_dot"] = normal(gain.p[0], gain.se(0), "V/(m/s)", LSQ_HAC, rec.source)
    est["tach_offset"] = normal(gain.p[1], gain.se(1), "V", LSQ_HAC, rec.source)
    return TestFit(rec.source, rec.test, est, checks, title="coast-down (encoder, filtered velocity)",
                   notes=[f"decay from the encoder's position, {t_all[k0]:.3g} s (top speed) to {t_all[k1 - 1]:.3g} s "
                          f"({END_FRACTION:.0%} of it); the velocity's constant from s_dot_V against the "
                          f"{filt.wn_rad_s / (2 * math.pi):.3g} Hz filter of the position"],
                   panels=[Panel(t + t_all[k0], z, _free_coast(p, t, sign), "s (m)"),
                           Panel(t_all[keep], w, gain.p[0] * y + gain.p[1], "s_dot (V)"),
                           Panel(t + t_all[k0], z - _free_coast(p, t, sign), None, "s less the free coast (m)")])
