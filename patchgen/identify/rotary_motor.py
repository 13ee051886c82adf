"""A rotary pendulum's arm (a QUBE-Servo 2's) from its encoder: the motor's step and the arm's coast-down.

With the pendulum fixed to it the arm is a rigid body turned by a DC motor,

    alpha'' = -a alpha' + k V(t) + d(t),

a = (D_r + k_t k_m / R_m) / J while the amplifier drives the motor (its back-EMF damps the arm),
a = D_r / J when it is disabled, k = k_t / (R_m J), V the motor's voltage held over each sample
and d the bench's random torque over J, an Ornstein-Uhlenbeck process relaxing at lam = 4 x its
bandwidth (patchgen.identify.filters). The encoder reads alpha in whole counts (variance about a
count squared over twelve).

The motor step is fitted by maximum likelihood through a Kalman filter that carries d
(patchgen.identify.encoder_coast.driven_nll, the coast's filter with the input added), by
patchgen.identify.kalman.ml_fit with its sandwich covariance and Satterthwaite's degrees of
freedom; the coast-down is encoder_coast.fit_position's, from the moment the hand lets go.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lsim

from patchgen.identify import encoder_coast, kalman
from patchgen.identify.encoders import END_FRACTION, MIN_COAST_SAMPLES
from patchgen.identify.estimate import ML_KALMAN, Panel, TestFit, normal
from patchgen.identify.recording import Recording

_JIT = {"cache": True, "error_model": "numpy"}
NOISE = (4, 5)  # log q, log r among the motor step's parameters
NOISE_FLOOR = 1e-6  # of the start's variance: the lowest a noise variance may reach (as encoder_coast's)
MIN_TRAVEL_COUNTS = 5  # the arm must turn through more counts than this: a few counts are the encoder's flicker
SMOOTH_S = 0.05  # s: the coast's speed is averaged over this to find where it has slowed (a count's
# flicker at 200 Hz is 0.1 rad/s in a two-sample rate, half the 5 % of a 4 rad/s spin)
HOLD_S = 0.3  # s: an arm that holds its count this long has stopped (stiction, which viscous friction is not;
# a viscous arm wandering under the random torque holds a count for 0.1 s now and then)
TAIL_TIMES = 8.0  # the coast is fitted for at most this many of its time constants 1 / a: the decay is
# over, and the cable's pull on a long wander is not in the model
START_FILTER_HZ = 5.0  # the start's filter passes the arm's response (its 1 / a is some 0.2 s, its steps a second)
START_SETTLE = 10.0  # the filter's 1 / w left out while it settles from rest (its transient to e^-10 x 10)
START_RATE_SAMPLES = 5  # the start's initial rate is the mean over this many steps: a count's flicker averaged
QUANTISATION_SHARE = 1e-2  # the velocity's variance the start's noise level keeps at least, of the rate's


def response(a: float, k: float, z0: float, v0: float, u: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """The noise-free angle and rate at each sample, u held from each sample to the next (exact steps)."""
    decay = math.exp(-a * dt)
    lag = -math.expm1(-a * dt) / a  # the angle one unit of rate adds over a step as it decays
    z, v = np.empty(u.size), np.empty(u.size)
    zi, vi = z0, v0
    for t in range(u.size):
        z[t], v[t] = zi, vi
        top = k * u[t] / a
        zi += top * dt + (vi - top) * lag
        vi = top + (vi - top) * decay
    return z, v


def _start(t: np.ndarray, z: np.ndarray, u: np.ndarray) -> tuple[float, float]:
    """a and k by least squares on the equation seen through the filter F = w^2 / (s + w)^2,
    s^2 F z = -a s F z + k F u (a state-variable filter, w = START_FILTER_HZ): the filter's
    derivatives of the angle average the counts' flicker where its differences would amplify it,
    and what the random torque adds to s^2 F z is small beside what the voltage does."""
    w = 2 * math.pi * START_FILTER_HZ
    A, B = np.array([[0.0, 1.0], [-w * w, -2 * w]]), np.array([[0.0], [w * w]])
    C, D = np.eye(2), np.zeros((2, 1))
    tt = t - t[0]
    _, fz, _ = lsim((A, B, C, D), z - z[0], tt)  # F z and s F z, the angle linear between samples
    _, fu, _ = lsim((A, B, C, D), u, tt, interp=False)  # F u, the voltage held over each sample
    accel = w * w * (z - z[0] - fz[:, 0]) - 2 * w * fz[:, 1]  # s^2 F z
    keep = tt >= START_SETTLE / w
    (a, k), *_ = np.linalg.lstsq(np.column_stack([-fz[keep, 1], fu[keep, 0]]), accel[keep], rcond=None)
    return float(a), float(k)


def fit_motor_step(rec: Recording, counts_per_rad: float, force_bandwidth_Hz: float) -> TestFit:
    """Fit the arm driven by the motor's voltage (a ``motor_step`` recording).

    Parameters
    ----------
    rec : Recording
        Columns t_s, V_m_V (the motor's voltage, held from each sample to the next) and alpha_counts.
    counts_per_rad : float
        The arm's encoder's counts per radian (2048 / 2 pi on a QUBE-Servo 2).
    force_bandwidth_Hz : float
        The random torque's bandwidth (the bench profile's), which the Kalman filter carries.

    Returns
    -------
    TestFit
        Estimates ``a`` (the arm's damping with the motor driven, 1/s) and ``k`` (the motor's
        acceleration per volt, rad/s^2/V).

    Raises
    ------
    InputError
        A constant voltage (nothing to identify k from), or an arm that never turns.
    """
    t, u = rec.columns["t_s"], np.ascontiguousarray(rec.columns["V_m_V"], dtype=float)
    counts = rec.columns["alpha_counts"]
    if np.ptp(u) == 0:
        raise rec.error("V_m_V", f"the voltage is {u[0]:.3g} V throughout: step it (a square wave of a volt or "
                                 "two) so that the arm's response shows the motor's gain")
    if np.ptp(counts) <= MIN_TRAVEL_COUNTS:
        raise rec.error("alpha_counts", f"the arm turns through {np.ptp(counts):.0f} counts at most: is the "
                                        "amplifier enabled and the arm free?")
    z = np.ascontiguousarray(counts / counts_per_rad, dtype=float)
    dt, lam, r0 = rec.dt, 4.0 * force_bandwidth_Hz, 1.0 / (12.0 * counts_per_rad ** 2)
    a0, k0 = _start(t, z, u)
    a0 = max(a0, 1.0 / (t[-1] - t[0]))  # a start that decays within the recording, whatever the data say
    z0, v0 = float(z[0]), float(np.mean(np.diff(z[:START_RATE_SAMPLES + 1]))) / dt
    _, v_model = response(a0, k0, z0, v0, u, dt)
    rate = np.diff(z) / dt
    model = 0.5 * (v_model[1:] + v_model[:-1])
    var_rate = float(np.var(rate - model))
    var_v = max(var_rate - 2 * r0 / dt ** 2, QUANTISATION_SHARE * var_rate, 1e-12)  # less the counts' flicker
    q0 = 2 * a0 * lam * (a0 + lam) * var_v
    pred, contrib = np.empty(z.size), np.empty(z.size)

    def nll(p: np.ndarray) -> float:
        return float(encoder_coast.driven_nll(z, u, dt, p[0], p[1], lam, math.exp(p[4]), math.exp(p[5]), p[2], p[3],
                                pred, contrib))

    def many(P: np.ndarray) -> np.ndarray:
        return np.array([nll(p) for p in P])

    def terms(p: np.ndarray) -> np.ndarray:
        nll(p)
        return contrib.copy()

    rate_step = math.sqrt(r0) / dt
    p0 = np.array([a0, k0, z0, v0, math.log(q0), math.log(r0)])
    s0 = np.array([0.01 * a0, 0.01 * abs(k0) or 1e-3, math.sqrt(r0), max(0.01 * abs(v0), rate_step), 0.3, 0.3])
    lower = np.array([1e-6, -np.inf, -np.inf, -np.inf, math.log(NOISE_FLOOR * q0), math.log(NOISE_FLOOR * r0)])
    fit = kalman.ml_fit(nll, p0, s0, lower, per_sample=terms, noise=NOISE, nll_many=many)
    nll(fit.p)
    est = {"a": normal(fit.p[0], fit.se(0), "1/s", ML_KALMAN, rec.source, fit.dof_of(0)),
           "k": normal(fit.p[1], fit.se(1), "rad/s^2/V", ML_KALMAN, rec.source, fit.dof_of(1))}
    free, _ = response(fit.p[0], fit.p[1], fit.p[2], fit.p[3], u, dt)
    sd = math.sqrt(math.exp(fit.p[4]) / (2 * lam))
    return TestFit(rec.source, rec.test, est, title="motor step (arm's encoder)",
                   notes=[f"the random acceleration {sd:.3g} rad/s^2 rms over {force_bandwidth_Hz:.3g} Hz, the "
                          f"encoder's read {math.sqrt(math.exp(fit.p[5])) * counts_per_rad:.3g} counts rms"],
                   panels=[Panel(t, z, free, "alpha (rad)"),
                           Panel(t, z - pred, None, "alpha less its one-step prediction (rad)")])


def _free_coast(p: np.ndarray, t: np.ndarray, sign: float) -> np.ndarray:
    """The coast's angle: p = a, z0, v0 and, when given, the Coulomb deceleration (rad/s^2)."""
    a, z0, v0 = p[:3]
    f = p[3] * sign if p.size > 3 else 0.0
    return z0 + (v0 + f / a) * (-np.expm1(-a * t) / a) - f / a * t


def fit_arm_coast(rec: Recording, counts_per_rad: float, force_bandwidth_Hz: float) -> TestFit:
    """Fit the arm's coast-down: spun by hand and let go, the amplifier disabled (a = D_r / J).

    Parameters
    ----------
    rec : Recording
        Columns t_s and alpha_counts.
    counts_per_rad : float
        The arm's encoder's counts per radian.
    force_bandwidth_Hz : float
        The random torque's bandwidth (the bench profile's).

    Returns
    -------
    TestFit
        Estimate ``a`` (the arm's own damping, 1/s) and, when the data show it, ``coulomb`` (rad/s^2).

    Raises
    ------
    InputError
        An arm that never turns, that does not slow down, or that slows in too few samples.
    """
    t_all, counts = rec.columns["t_s"], rec.columns["alpha_counts"]
    z_all = counts / counts_per_rad
    dt = rec.dt
    v = np.gradient(z_all, dt)
    k0 = int(np.argmax(np.abs(v)))
    top = abs(v[k0])
    if top * dt * counts_per_rad < 5.0:
        raise rec.error("alpha_counts", f"the arm never turns faster than {top:.3g} rad/s: spin it harder")
    width = max(1, round(SMOOTH_S / dt))
    smooth = np.convolve(v, np.ones(width) / width, mode="same")
    k0 = int(np.argmax(np.abs(smooth))) + width // 2 + 2  # the smoothed top is within half its window of the release
    below = np.flatnonzero(np.abs(smooth[k0:]) < END_FRACTION * top)
    if below.size == 0:
        raise rec.error("alpha_counts", f"the arm does not slow to {END_FRACTION:.0%} of its top speed in the "
                                        "recording: record until it has nearly stopped")
    k_slow = k0 + int(below[0])
    a0 = max(math.log(abs(smooth[k0]) / max(abs(smooth[k_slow]), 1e-9)) / max((k_slow - k0) * dt, dt), 1e-3)
    hold = max(1, round(HOLD_S / dt))
    still = np.flatnonzero(np.convolve(np.diff(counts[k0:]) != 0, np.ones(hold), mode="valid") == 0)
    k1 = min(k0 + int(still[0]) + 1 if still.size else counts.size, k0 + int(TAIL_TIMES / (a0 * dt)))
    if k1 - k0 < MIN_COAST_SAMPLES:
        raise rec.error("t_s", f"only {k1 - k0} samples while the arm coasts: record faster")
    t, z = t_all[k0:k1] - t_all[k0], z_all[k0:k1]
    sign = float(np.sign(smooth[k0]))
    fit, zc, _ = encoder_coast.fit_position(z, dt, sign, 4.0 * force_bandwidth_Hz, (a0, smooth[k0]),
                                            1.0 / (12.0 * counts_per_rad ** 2))
    est, checks, p = encoder_coast.coast_estimates(fit, zc, rec.source, "a", "rad/s^2", "torque")
    free = _free_coast(p, t, sign)
    return TestFit(rec.source, rec.test, est, checks, title="arm coast-down (encoder)",
                   notes=[f"decay from the arm's encoder, {t_all[k0]:.3g} s (the hand let go) to {t_all[k1 - 1]:.3g} s "
                          + ("(the arm stopped)" if k1 < counts.size else "(the recording's end)")],
                   panels=[Panel(t + t_all[k0], z, free, "alpha (rad)"),
                           Panel(t + t_all[k0], z - free, None, "alpha less the free coast (rad)")])
