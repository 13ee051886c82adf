"""Cart friction: the coast-down recording and the thesis's inclined slide (B.2.1).

Coast-down: the pendulum fixed to the cart, the cart pushed by hand and let go, the position pot
(s_V) and the tachometer (s_dot_V) recorded until it has nearly stopped. With w the tachometer's
voltage and z the pot's, (M + m) s'' = -b_VF s' - F_c sgn(s') + (random force) reads

    w' = -a w - f sgn(w) + noise,   z' = rho w,   a = b_VF / (M + m),  rho = K_s / K_s_dot,

fitted by maximum likelihood through a Kalman filter (patchgen.identify.kalman) from the moment the
cart runs free (the tachometer's peak) until it has slowed to END_FRACTION of that speed. f, the
Coulomb friction, is kept when the data show it (z beyond Z_REJECT), else the fit is viscous
alone, as the thesis assumed; rho gives the tachometer constant.

Inclined slide: B.1 with the track at phi, from rest to distance d in t_f,
s'' + b s' = g sin(phi) (B.2), s(0) = 0, s'(0) = 0, s(t_f) = d: a boundary-value problem with one
unknown parameter, solved as such (scipy.integrate.solve_bvp); its closed form
d = (a / b) t_f - (a / b^2)(1 - exp(-b t_f)), a = g sin(phi), gives the derivatives through which
the stated measurement uncertainties reach b (delta method).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_bvp
from scipy.optimize import brentq

from patchgen.identify import filters, kalman, lsq
from patchgen.identify.estimate import DELTA, ML_KALMAN, Z95, Z_REJECT, Check, Estimate, Panel, TestFit, normal
from patchgen.identify.figures import Incline
from patchgen.identify.recording import Recording
from patchgen.inputs.errors import InputError

END_FRACTION = 0.1  # the coast-down is fitted until the cart has slowed to a tenth of its top speed
START_SNR = 20.0  # the top speed must stand this many noise levels above the tachometer's noise
SMOOTH_S = 0.05  # s: the tachometer is smoothed over this to find the peak and the end
RESTRICTED = 3  # z0, w0 and the offset integrated out (REML, patchgen.identify.filters.linear_nll)
NOISE = (5, 6, 7)  # log q, log r1, log r2 among the fit's parameters
NOISE_FLOOR = 1e-9  # relative: the lowest noise variance the likelihood may reach (held there if it goes)


def _smooth(x: np.ndarray, n: int) -> np.ndarray:
    n = max(1, n)
    return np.convolve(np.pad(x, n, mode="edge"), np.ones(2 * n + 1) / (2 * n + 1), mode="valid")


def _mad_noise(x: np.ndarray) -> float:
    d = np.diff(x)
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(2)) or 1e-9


def coast_closed_form(p: np.ndarray, t: np.ndarray, sign: float) -> tuple[np.ndarray, np.ndarray]:
    """(z, w) of the noise-free coast: p = a, f, rho, z0, w0 (without the tachometer's offset)."""
    a, f, rho, z0, w0 = p
    fs = f * sign
    e = np.exp(-a * t)
    w = (w0 + fs / a) * e - fs / a
    z = z0 + rho * ((w0 + fs / a) * (1 - e) / a - fs / a * t)
    return z, w


def fit_coast(rec: Recording, force_bandwidth_Hz: float, column: str = "s_V") -> TestFit:
    """Fit a coast-down: a = b_VF / (M + m) (1/s), Coulomb friction f (V/s, when shown), rho = K_s / K_s_dot.

    Parameters
    ----------
    rec : Recording
        A ``coast_down`` recording (t_s, s_V, s_dot_V).
    force_bandwidth_Hz : float
        The random force's bandwidth (the bench profile's; the filter carries the force as a
        first-order process of that band, patchgen.identify.filters).
    column : str
        The position's column: the pot's ``s_V``, or an encoder's ``s_counts`` (rho is then in
        counts per volt of the tachometer).

    Returns
    -------
    TestFit
        Estimates ``decay`` (a, 1/s), ``coulomb`` (f in tachometer volts per second, present only
        when the data show it), ``rho`` (1/s) and ``tach_offset`` (V).
    """
    t_all, z_all, w_all = rec.columns["t_s"], rec.columns[column], rec.columns["s_dot_V"]
    dt = rec.dt
    ws = _smooth(w_all, round(SMOOTH_S / dt))
    noise = _mad_noise(w_all)
    k0 = int(np.argmax(np.abs(ws)))
    top = abs(ws[k0])
    if top < START_SNR * noise:
        raise rec.error("s_dot_V", f"the tachometer never rises above its noise ({top:.3g} V against "
                                   f"{noise:.3g} V): push the cart harder")
    below = np.flatnonzero(np.abs(ws[k0:]) < END_FRACTION * top)
    if below.size == 0:
        raise rec.error("s_dot_V", f"the cart does not slow to {END_FRACTION:.0%} of its top speed in the "
                                   "recording: record until it has nearly stopped")
    k1 = k0 + int(below[0])
    if k1 - k0 < 50:
        raise rec.error("t_s", f"only {k1 - k0} samples while the cart coasts: record faster "
                               f"(the cart slows in {(k1 - k0) * dt:.3g} s)")
    dt, (t, z, w) = filters.blocks(dt, t_all[k0:k1] - t_all[k0], z_all[k0:k1], w_all[k0:k1])
    sign = float(np.sign(ws[k0]))
    if np.ptp(z) < START_SNR * _mad_noise(z):
        raise rec.error(column, "the position does not move above its noise while the cart coasts")
    # a start: the noise-free coast by least squares, both channels weighted by their noise
    nz, nw = _mad_noise(z), _mad_noise(w)
    rho0 = float(np.polyfit(np.cumsum(w) * dt, z, 1)[0])
    a0 = max(math.log(abs(w[0]) / max(abs(w[-1]), 1e-9)) / max(t[-1], dt), 1e-3)

    def oe(p: np.ndarray) -> np.ndarray:
        zz, ww = coast_closed_form(p[:5], t, sign)
        return np.concatenate([(zz - z) / nz, (ww + p[5] - w) / nw])

    start = np.array([a0, 0.0, rho0, z[0], w[0], 0.0])
    scale = np.array([1e-2 * a0, 1e-2 * a0 * abs(w[0]), 1e-2 * abs(rho0), nz, nw, nw])
    first = lsq.fit(oe, start, scale)

    pred, terms = np.empty(t.size), np.empty(t.size)
    lam = 4.0 * force_bandwidth_Hz

    # the parameters in the order a, rho, z0, w0, offset, log q, log r1, log r2, then f when fitted
    def f_many(P: np.ndarray) -> np.ndarray:
        out = np.empty(P.shape[0])
        filters.coast_nll_many(z, w, dt, lam, sign, restricted[0], np.ascontiguousarray(P, dtype=float), pred, terms,
                               out)
        return out

    def f_nll(q: np.ndarray) -> float:
        return float(f_many(q[None, :])[0])

    def f_terms(q: np.ndarray) -> np.ndarray:
        f_nll(q)
        return terms.copy()

    resid = oe(first.p)
    r1, r2 = np.var(resid[:t.size]) * nz ** 2, np.var(resid[t.size:]) * nw ** 2
    q0 = max(r2 * 1e-2 / dt, 1e-12) * lam * lam
    restricted = [RESTRICTED]
    lo_noise = [math.log(NOISE_FLOOR * max(r1, r2, 1e-12))] * 3
    p0 = np.concatenate([first.p, [math.log(q0), math.log(r1), math.log(r2)]])
    # the likelihood's own scales (the least-squares covariance ignores the random force)
    s0 = np.concatenate([np.maximum(np.sqrt(np.clip(np.diag(first.cov), 0.0, None)), 1e-3 * np.abs(scale)),
                         [0.3, 0.05, 0.05]])
    lower = np.concatenate([[1e-6, -np.inf, -np.inf, -np.inf, -np.inf, -np.inf], lo_noise])
    # viscous alone first (f = 0), then the likelihood-ratio test of Coulomb friction
    keep = [0, 2, 3, 4, 5, 6, 7, 8]
    with_f = lambda q: np.insert(q[:8], 1, q[8] if q.size > 8 else 0.0)
    fit = kalman.ml_fit(f_nll, p0[keep], s0[keep], lower[keep], per_sample=f_terms, noise=NOISE, nll_many=f_many)
    f_scale = max(fit.p[0], 1e-3) * abs(w[0])
    both, zc = kalman.added_term(f_nll, fit, s0[keep], 0.1 * f_scale, lower[keep], f_many)
    coulomb = zc > Z_REJECT  # friction opposes the motion: a negative f is no friction
    checks = [Check("Coulomb friction", zc, Z_REJECT, coulomb,
                    f"likelihood-ratio z = {zc:.3g} for a constant friction force: " +
                    ("the data show Coulomb friction (not in patchgen's plant, which is viscous)" if coulomb
                     else "viscous friction alone, as the thesis assumed"))]
    if coulomb:
        se = np.sqrt(np.diag(fit.cov))
        restricted[0] = RESTRICTED + 1  # f enters linearly too
        fit = kalman.ml_fit(f_nll, both, np.append(np.where(se > 0, se, s0[keep]), 0.1 * f_scale),
                            np.append(lower[keep], -np.inf), per_sample=f_terms, noise=NOISE, nll_many=f_many)
    f_nll(fit.p)
    est = {name: normal(fit.p[i], fit.se(i), unit, ML_KALMAN, rec.source, fit.dof_of(i))
           for name, i, unit in (("decay", 0, "1/s"), ("rho", 1, "1/s"), ("tach_offset", 4, "V"))}
    if coulomb:
        est["coulomb"] = normal(fit.p[8], fit.se(8), "V/s", ML_KALMAN, rec.source, fit.dof_of(8))
    p_full = with_f(fit.p)
    z_free, w_free = coast_closed_form(p_full[:5], t, sign)
    return TestFit(rec.source, rec.test, est, checks, title="coast-down",
                   notes=[f"fitted from {t_all[k0]:.3g} s (top speed) to {t_all[k1 - 1]:.3g} s "
                          f"({END_FRACTION:.0%} of it); random force q = {math.exp(p_full[6]):.3g} V^2/s^3"],
                   panels=[Panel(t + t_all[k0], w, w_free + p_full[5], "s_dot (V)"),
                           Panel(t + t_all[k0], z, z_free, "s (V)"),
                           Panel(t + t_all[k0], w - pred, None, "innovation s_dot (V)")])


def slide_distance(b: float, a: float, t: float) -> float:
    """B.2's closed form: the distance from rest in time t, s'' + b s' = a."""
    if abs(b * t) < 1e-6:
        return 0.5 * a * t * t * (1 - b * t / 3)
    return a / b * t - a / (b * b) * (-math.expm1(-b * t))


def solve_b2(angle_deg: float, distance_m: float, time_s: float, g: float) -> float:
    """b (1/s) of B.2 from the slide's figures, as the boundary-value problem it is.

    Raises
    ------
    ValueError
        When no positive b gives that distance in that time.
    """
    a = g * math.sin(math.radians(angle_deg))
    if distance_m >= 0.5 * a * time_s ** 2:
        raise ValueError(f"{distance_m:g} m in {time_s:g} s is no less than a frictionless cart slides "
                         f"({0.5 * a * time_s ** 2:.4g} m)")
    guess = brentq(lambda b: slide_distance(b, a, time_s) - distance_m, 1e-9, 1e3)
    x = np.linspace(0.0, time_s, 41)
    y0 = np.vstack([[slide_distance(guess, a, tt) for tt in x], a / guess * -np.expm1(-guess * x)])
    sol = solve_bvp(lambda _t, y, p: np.vstack([y[1], a - p[0] * y[1]]),
                    lambda ya, yb, p: np.array([ya[0], ya[1], yb[0] - distance_m]), x, y0, p=[guess], tol=1e-10)
    if not sol.success:
        raise ValueError(f"the boundary-value problem did not converge ({sol.message})")
    return float(sol.p[0])


def fit_incline(fig: Incline, source: str) -> TestFit:
    """b = b_VF / (M + m) and b_VF from the inclined slide, with the B.3-style value reported beside.

    Parameters
    ----------
    fig : Incline
        The slide's figures.
    source : str
        Its file, named in errors.

    Returns
    -------
    TestFit
        Estimates ``decay`` (b, 1/s) and ``b_VF`` (kg/s), intervals by the delta method.
    """
    x = np.array([fig.angle_deg, fig.distance_m, fig.time_s, fig.mass_kg])
    sd = np.array([fig.angle_uncertainty_deg, fig.distance_uncertainty_m, fig.time_uncertainty_s,
                   fig.mass_uncertainty_kg])
    try:
        b = solve_b2(fig.angle_deg, fig.distance_m, fig.time_s, fig.g_m_per_s2)
    except ValueError as exc:
        raise InputError(source, "distance_m", f"{exc}: b would be negative") from None
    a = fig.g_m_per_s2 * math.sin(math.radians(fig.angle_deg))
    closed = lambda v: brentq(lambda bb: slide_distance(bb, fig.g_m_per_s2 * math.sin(math.radians(v[0])), v[2])
                              - v[1], 1e-9, 1e3)
    grad = np.empty(4)
    for i in range(3):
        h = 1e-6 * x[i]
        up, dn = x.copy(), x.copy()
        up[i] += h
        dn[i] -= h
        grad[i] = (closed(up) - closed(dn)) / (2 * h)
    grad[3] = 0.0
    se_b = float(math.sqrt(np.sum((grad * sd) ** 2)))
    bvf = b * fig.mass_kg
    se_bvf = math.sqrt((fig.mass_kg * se_b) ** 2 + (b * fig.mass_uncertainty_kg) ** 2)
    est = {"decay": Estimate(b, max(b - Z95 * se_b, 0.0), b + Z95 * se_b, "1/s", DELTA, source, std_error=se_b),
           "b_VF": Estimate(bvf, max(bvf - Z95 * se_bvf, 0.0), bvf + Z95 * se_bvf, "kg/s", DELTA, source,
                            std_error=se_bvf)}
    notes = [f"B.2 solved as a boundary-value problem: s'' + b s' = {fig.g_m_per_s2:g} sin({fig.angle_deg:g} deg), "
             f"s(0) = 0, s'(0) = 0, s({fig.time_s:g} s) = {fig.distance_m:g} m gives b = {b:.4g} 1/s"]
    checks = []
    if fig.reported_b_per_s is not None:
        inside = est["decay"].covers(fig.reported_b_per_s)
        where = f" ({fig.reported_source})" if fig.reported_source else ""
        notes.append(f"reported{where}: b = {fig.reported_b_per_s:g} 1/s, b_VF = "
                     f"{fig.reported_b_per_s * fig.mass_kg:.5g} kg/s; B.2 solved directly gives {b:.4g} 1/s")
        checks.append(Check("reported value", fig.reported_b_per_s, b, not inside,
                            f"the reported b = {fig.reported_b_per_s:g} 1/s{where} is "
                            + ("inside" if inside else "outside") + " the interval of B.2's direct solution "
                            f"({est['decay'].low:.4g} to {est['decay'].high:.4g} 1/s)"))
    tt = np.linspace(0, fig.time_s, 200)
    panels = [Panel(np.array([fig.time_s]), np.array([fig.distance_m]), np.array([slide_distance(b, a, v) for v in tt]),
                    "s (m)", points=True, fitted_x=tt)]
    return TestFit(source, "incline", est, checks, notes, panels, title="inclined slide (B.2)")
