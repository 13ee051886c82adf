"""The actuator: command voltage u_c to force on the cart, read on a force gauge with the cart held.

The model is the bench profile's (patchgen.bench.lanes): a dead zone on the command, then
K_U / (tau s + 1) ("lag") or K_U s / (tau s + 1) ("lag_zero", appendix A's reading), plus the
gauge's zero. The step test fits the first-order family (K_U + K_Z s) / (tau s + 1) that holds
both: a steady gain K_U whose interval excludes 0 rejects a zero at the origin (test 5's steady
force); a K_Z that differs from 0 in a lag rejects first order (K_Z = -K_U tau2 is a second lag
tau2 to first order in tau2: the score test of a second-order term). The ramp test fits the dead
zone, with a shift of h/2 against the command's direction of travel: h is the hysteresis.

The command is held over each sample interval and the force read just before it changes, so the
lag is exact sample to sample (a zero-order hold). Intervals: least squares with the Newey-West
covariance (patchgen.identify.lsq).
"""

from __future__ import annotations

import numba as nb
import numpy as np

from patchgen.identify import lsq
from patchgen.identify.estimate import LSQ_HAC, Z_REJECT, Check, Panel, TestFit, normal
from patchgen.identify.lag_grid import MIN_TAU_S, dead_value, dead_zone, grid_start, lag_state
from patchgen.identify.recording import Recording

RESPONSE_SNR = 20.0  # the force must move this many noise levels for a test to excite the actuator
LEVEL_TOLERANCE_V = 0.02  # V: command levels closer than this are one level
TRAVEL_WINDOW = 0.002  # of a ramp's samples: the command is smoothed over this before its direction is read


def force_model(p: np.ndarray, u: np.ndarray, dt: float) -> np.ndarray:
    """(K_U + K_Z s) / (tau s + 1) after the dead zone, plus the gauge's zero; p = K_U, K_Z, tau, dz, F0."""
    K, KZ, tau, dz, F0 = p
    out = np.empty(u.size)
    _force(np.ascontiguousarray(u, dtype=float), dz, np.exp(-dt / tau), K, KZ / tau, F0, out)
    return out


@nb.njit(cache=True)
def _force(u, dz, a, K, KZ_tau, F0, out):
    """force_model sample by sample: K y + K_Z / tau (v delayed one sample - y) + F0, v the command
    after the dead zone and y its lag (patchgen.identify.lag_grid.lag_filter), each by the same
    operations as dead_zone, lag_state and previous."""
    b0, b1, a1 = 0.0, 1.0 - a, -a
    z = prev = dead_value(u[0], dz)
    for k in range(u.size):
        v = dead_value(u[k], dz)
        y = z + b0 * v
        z = v * b1 - y * a1
        out[k] = K * y + KZ_tau * (prev - y) + F0
        prev = v


@nb.njit(cache=True)
def _ramp_force(u, shift, dz, a, K, F0, out):
    """ramp_model sample by sample: K y + F0, y the lag of u - shift after the dead zone."""
    b0, b1, a1 = 0.0, 1.0 - a, -a
    z = dead_value(u[0] - shift[0], dz)
    for k in range(u.size):
        v = dead_value(u[k] - shift[k], dz)
        y = z + b0 * v
        z = v * b1 - y * a1
        out[k] = K * y + F0


def _noise(f: np.ndarray) -> float:
    """A robust level of the force's sample-to-sample noise (N)."""
    d = np.diff(f)
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2)) or 1e-12


def _excited(rec: Recording, u: np.ndarray, f: np.ndarray) -> None:
    noise = _noise(f)
    rest = np.abs(u) <= np.percentile(np.abs(u), 10) + 1e-12
    f_rest = float(np.median(f[rest]))
    for side, pick in (("positive", u > 0), ("negative", u < 0)):
        if np.any(pick) and np.max(np.abs(f[pick] - f_rest)) < RESPONSE_SNR * noise:
            raise rec.error("force_N", f"no response above the noise to the {side} commands (up to "
                                           f"{np.max(np.abs(u)):.3g} V): the command does not leave the dead zone")


def _levels(u: np.ndarray) -> list[float]:
    lv: list[float] = []
    for x in np.unique(np.round(np.abs(u[u != 0]) / LEVEL_TOLERANCE_V)) * LEVEL_TOLERANCE_V:
        if not lv or x - lv[-1] > LEVEL_TOLERANCE_V:
            lv.append(float(x))
    return lv


def _scales(p: np.ndarray) -> np.ndarray:
    K = max(abs(p[0]), abs(p[1]), 1e-3)
    return np.array([1e-2 * K, 1e-2 * K, 1e-2 * max(p[2], 1e-3), 1e-2, 1e-2 * K])


def fit_step(rec: Recording) -> TestFit:
    """Fit the actuator step test: K_U, tau, the dead zone and the gauge zero, with the checks of a
    zero at the origin, of first order, and of the same gain both ways.

    Parameters
    ----------
    rec : Recording
        An ``actuator_step`` recording (t_s, u_c_V, force_N).

    Returns
    -------
    TestFit
        Estimates K_U (N/V; N s/V with a zero at the origin), tau (s), dead_zone (V), gauge_zero
        (N) and the model chosen, "lag" or "lag_zero" (in notes and ``model`` checks).
    """
    t, u, f = rec.columns["t_s"], rec.columns["u_c_V"], rec.columns["force_N"]
    dt = rec.dt
    if np.sum(np.abs(np.diff(u)) > LEVEL_TOLERANCE_V) < 2:
        raise rec.error("u_c_V", "the command never steps: a step test steps the command between levels")
    if len(_levels(u)) < 2:
        raise rec.error("u_c_V", f"the command steps to one level only ({_levels(u)[0]:.3g} V): K_U and the dead "
                                 "zone need steps to at least two levels")
    _excited(rec, u, f)
    start = grid_start(u, f, dt, True)
    scale = _scales(start)
    general = lsq.fit(lambda p: force_model(p, u, dt) - f, start, scale,
                      bounds=([-np.inf, -np.inf, MIN_TAU_S, 0, -np.inf], np.inf))
    zK = general.p[0] / general.se(0)
    zZ = general.p[1] / general.se(1)
    steady = abs(zK) > Z_REJECT
    checks = [Check("zero at the origin", abs(zK), Z_REJECT, steady,
                    f"steady force per volt {general.p[0]:.4g} N/V, z = {zK:.3g}: " +
                    ("the data reject a zero at the origin (a constant command holds a steady force)"
                     if steady else "no steady force: the data support a zero at the origin (lag_zero)"))]
    model = "lag" if steady or abs(zZ) <= Z_REJECT else "lag_zero"
    gain = 0 if model == "lag" else 1  # which of K_U, K_Z the model keeps

    def full(q: np.ndarray) -> np.ndarray:
        p = np.zeros(5)
        p[gain], p[2:] = q[0], q[1:]
        return p

    if model == "lag":
        second = abs(zZ) > Z_REJECT
        tau2 = -general.p[1] / general.p[0]
        checks.append(Check("first order", abs(zZ), Z_REJECT, second,
                            f"added term K_Z s: {general.p[1]:.3g} N s/V, z = {zZ:.3g}: " + (
                                (f"the data reject a first-order lag: a second lag of about {tau2:.3g} s "
                                 "(a second-order actuator; the profile keeps the first-order fit)")
                                if second and tau2 > 0 else "the data reject a first-order lag: the force leads it"
                                if second else "first order suffices (no second-order term)")))
    keep = [gain, 2, 3, 4]
    final = lsq.fit(lambda q: force_model(full(q), u, dt) - f, general.p[keep], scale[keep],
                    bounds=([-np.inf, MIN_TAU_S, 0, -np.inf], np.inf))
    p = full(final.p)
    both_ways = bool(np.any(u > 0) and np.any(u < 0))
    notes = [f"model: {model}"]
    if model == "lag" and not both_ways:
        notes.append("steps of one sign only: whether one K_U serves both directions is not tested (step both ways)")
    if model == "lag" and both_ways:
        z = final.score_test(lag_state(np.maximum(dead_zone(u, p[3]), 0.0), dt, p[2]))
        skew = abs(z) > Z_REJECT
        checks.append(Check("same gain both ways", abs(z), Z_REJECT, skew,
                            f"score z = {z:.3g}: " + ("the data reject one K_U for both signs (the force per volt "
                                                      "differs with direction)" if skew else
                                                      "one K_U serves both directions")))
    unit_K = "N/V" if model == "lag" else "N s/V"
    est = {name: normal(final.p[i], final.se(i), unit, LSQ_HAC, rec.source)
           for i, (name, unit) in enumerate((("K_U", unit_K), ("tau", "s"), ("dead_zone", "V"), ("gauge_zero", "N")))}
    fit = force_model(p, u, dt)
    return TestFit(rec.source, rec.test, est, checks, notes=notes, title=f"actuator step: {model}",
                   panels=[Panel(t, f, fit, "force (N)"), Panel(t, u, None, "u_c (V)"),
                           Panel(t, f - fit, None, "residual (N)")])


def ramp_model(p: np.ndarray, u: np.ndarray, direction: np.ndarray, dt: float) -> np.ndarray:
    """K_U / (tau s + 1) after a dead zone shifted by h/2 along the command's travel; p = K_U, tau, dz, F0, h."""
    K, tau, dz, F0, h = p
    out = np.empty(u.size)
    _ramp_force(np.ascontiguousarray(u, dtype=float), np.ascontiguousarray(0.5 * h * direction, dtype=float), dz,
                np.exp(-dt / tau), K, F0, out)
    return out


def travel(u: np.ndarray) -> np.ndarray:
    """+1 where the command rises, -1 where it falls, the last direction carried over a pause; the
    command smoothed over TRAVEL_WINDOW of the recording first, so that its noise does not flip it."""
    w = max(1, int(TRAVEL_WINDOW * u.size))
    smooth = np.convolve(np.pad(u, w, mode="edge"), np.ones(2 * w + 1) / (2 * w + 1), mode="valid")
    d = np.sign(np.round(np.diff(smooth, prepend=smooth[0]), 12))
    idx = np.where(d != 0, np.arange(d.size), 0)
    np.maximum.accumulate(idx, out=idx)
    out = d[idx]
    first = np.flatnonzero(d)
    out[:first[0] if first.size else d.size] = d[first[0]] if first.size else 0.0
    return out


def fit_ramp(rec: Recording) -> TestFit:
    """Fit the slow ramp through zero: the dead zone and any hysteresis (with K_U, tau, gauge zero).

    Parameters
    ----------
    rec : Recording
        An ``actuator_ramp`` recording (t_s, u_c_V, force_N).

    Returns
    -------
    TestFit
        Estimates dead_zone (V), hysteresis (V, when the data show it), K_U, tau, gauge_zero.
    """
    t, u, f = rec.columns["t_s"], rec.columns["u_c_V"], rec.columns["force_N"]
    dt = rec.dt
    if not (np.min(u) < 0 < np.max(u)):
        raise rec.error("u_c_V", f"the command does not pass through zero (it stays within {np.min(u):.3g} to "
                                 f"{np.max(u):.3g} V): a ramp through zero sees both edges of the dead zone")
    _excited(rec, u, f)
    direction = travel(u)
    s = grid_start(u, f, dt, False)
    start = np.array([s[0], s[2], s[3], s[4], 0.0])
    scale = np.array([1e-2 * max(abs(s[0]), 1e-3), 1e-2 * max(s[2], 1e-3), 1e-2, 1e-2 * abs(s[0]), 1e-2])
    lo = [-np.inf, MIN_TAU_S, 0, -np.inf, -np.inf]
    checks, notes, full = [], [], None
    if np.any(direction > 0) and np.any(direction < 0):
        full = lsq.fit(lambda p: ramp_model(p, u, direction, dt) - f, start, scale, bounds=(lo, np.inf))
        zh = full.p[4] / full.se(4)
        hyst = abs(zh) > Z_REJECT
        checks.append(Check("hysteresis", abs(zh), Z_REJECT, hyst,
                            f"edges shifted against the travel by h = {full.p[4]:.3g} V, z = {zh:.3g}: " +
                            ("the data show hysteresis (not in the bench profile: it keeps the mean edge)" if hyst
                             else "no hysteresis")))
    else:  # one way only: a shift against the travel is a shift of the dead zone's centre as well
        hyst = False
        notes.append("the ramp runs one way only: hysteresis cannot be told from an offset dead zone, not tested "
                     "(ramp up and back down)")
    if hyst:
        final, p = full, full.p
    else:
        first = start[:4] if full is None else full.p[:4]
        final = lsq.fit(lambda q: ramp_model(np.append(q, 0.0), u, direction, dt) - f, first, scale[:4],
                        bounds=(lo[:4], np.inf))
        p = np.append(final.p, 0.0)
    est = {name: normal(final.p[i], final.se(i), unit, LSQ_HAC, rec.source)
           for name, i, unit in (("dead_zone", 2, "V"), ("K_U", 0, "N/V"), ("tau", 1, "s"), ("gauge_zero", 3, "N"))}
    if hyst:
        est["hysteresis"] = normal(full.p[4], full.se(4), "V", LSQ_HAC, rec.source)
    fit = ramp_model(p, u, direction, dt)
    return TestFit(rec.source, rec.test, est, checks, notes=notes, title="actuator ramp through zero",
                   panels=[Panel(u, f, fit, "force (N)", xlabel="u_c (V)", points=True),
                           Panel(t, f - fit, None, "residual (N)")])
