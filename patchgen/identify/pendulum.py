"""The pendulum's free swing, hanging, with the cart clamped (thesis B.2.2).

B.5 with I = m l^2: phi'' + beta phi' + (g / l) sin(phi) = 0 about hanging (phi = theta - pi),
beta = c / (m l^2). The period gives l = g / w0^2 (the "effective length"), the decay c =
beta m l^2. The swing is fitted through the angle pot's voltage gain phi + offset, its gain the
theta sensor constant (which matters only through sin(phi), the swing's amplitude-dependent period),
by maximum likelihood through an extended Kalman filter (patchgen.identify.kalman): the bench's
random force at the tip keeps the swing from being the noise-free decay. A Coulomb term
-gam sgn(phi') (a linear decay of the amplitude, which the thesis looked for and did not see) is
kept when the data show it.
"""

from __future__ import annotations

import math

import numpy as np

from patchgen.identify import filters, kalman, lsq
from patchgen.identify.estimate import ML_KALMAN, Z_REJECT, Check, Panel, Parameter, TestFit, delta, normal
from patchgen.identify.recording import Recording

MIN_PERIODS = 5  # swings a recording must hold for its period and decay
START_SNR = 20.0  # the swing's amplitude in noise levels
NOISE_FLOOR = 1e-9  # relative: the lowest noise variance the likelihood may reach
NOISE = (5, 6)  # log q, log r among the fit's parameters


def _crossings(y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Times at which y rises through zero (linear interpolation)."""
    k = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


def fit_swing(rec: Recording, gain: float, g: float, force_bandwidth_Hz: float, m: float | None = None,
              m_se: float = 0.0, column: str = "theta_V") -> TestFit:
    """Fit a free swing: l (m) from the period and, with the pendulum's mass, c (kg m^2/s).

    Parameters
    ----------
    rec : Recording
        A ``free_swing`` recording (t_s, theta_V).
    gain : float
        The theta sensor's constant (V/rad).
    g : float
        Gravity (m/s^2).
    force_bandwidth_Hz : float
        The random force's bandwidth (the bench profile's; the filter carries the torque at the tip
        as a first-order process of that band, patchgen.identify.filters).
    m, m_se : float, optional
        The pendulum's mass (kg) and its standard uncertainty; without it c is not estimated.
    column : str
        The angle's column: the pot's ``theta_V`` (gain in V/rad), or an encoder's ``theta_counts``
        (gain in counts per rad).

    Returns
    -------
    TestFit
        Estimates ``l``, ``beta`` (c / (m l^2), 1/s), ``c`` (with m) and, when the data show it,
        ``coulomb`` (rad/s^2).
    """
    t_all, y_all = rec.columns["t_s"], rec.columns[column]
    dt = rec.dt
    unit = column.rpartition("_")[2]
    d = np.diff(y_all)
    noise = float(1.4826 * np.median(np.abs(d - np.median(d))) / math.sqrt(2)) or 1e-9
    off0 = float(np.median(y_all))
    moving = np.flatnonzero(np.abs(y_all - y_all[0]) > START_SNR * noise)
    if moving.size == 0 or np.ptp(y_all) < 2 * START_SNR * noise:
        raise rec.error(column, f"the pendulum does not swing above the sensor's noise ({np.ptp(y_all):.3g} V peak "
                                   f"to peak against {noise:.3g} V): start it from a larger angle")
    k0 = int(moving[0])
    ups = _crossings(y_all[k0:] - off0, t_all[k0:])
    if ups.size < MIN_PERIODS + 1:
        raise rec.error("t_s", f"{max(ups.size - 1, 0)} whole swings recorded; the period and the decay need at "
                               f"least {MIN_PERIODS}: record for longer")
    k0 = int(np.searchsorted(t_all, ups[0]))
    dt, (t, y) = filters.blocks(dt, t_all[k0:] - t_all[k0], y_all[k0:])
    period = float(np.mean(np.diff(ups)))
    wd = 2 * math.pi / period
    # the decay from the amplitude of each whole swing
    edges = np.searchsorted(t, ups - ups[0])
    amp = np.array([0.5 * np.ptp(y[a:b]) for a, b in zip(edges[:-1], edges[1:]) if b > a + 2])
    tm = 0.5 * (ups[:-1] + ups[1:])[:amp.size] - ups[0]
    sig = max(-np.polyfit(tm, np.log(amp), 1)[0], 1e-4) if amp.size > 1 else 1e-3
    w2_0 = wd * wd + sig * sig
    phi_amp = amp[0] / gain
    # a start: the noise-free swing by least squares
    out = np.empty(t.size)

    def free(p: np.ndarray) -> np.ndarray:
        filters.swing_free(t.size, dt, p[0], p[1], p[3], p[4], out)
        return gain * out + p[2]

    slope = (y[min(3, y.size - 1)] - y[0]) / (min(3, y.size - 1) * dt)
    p0 = np.array([2 * sig, w2_0, off0, (y[0] - off0) / gain, math.copysign(phi_amp * wd, slope)])
    scale = np.array([1e-3 * max(2 * sig, 1e-3), 1e-4 * w2_0, noise, noise / gain, noise / gain * wd])
    first = lsq.fit(lambda p: free(p) - y, p0, scale, covariance=False)  # a start: its covariance ignores the torque
    r = float(np.var(free(first.p) - y))
    pred, terms = np.empty(t.size), np.empty(t.size)

    def nll_many(P: np.ndarray) -> np.ndarray:
        out = np.empty(P.shape[0])
        filters.swing_nll_many(y, dt, lam, gain, np.ascontiguousarray(P, dtype=float), pred, terms, out)
        return out

    def nll(p: np.ndarray) -> float:
        return float(nll_many(p[None, :])[0])

    def per_sample(p: np.ndarray) -> np.ndarray:
        nll(p)
        return terms.copy()

    lam = 4.0 * force_bandwidth_Hz
    q0 = max(r / gain ** 2 * wd ** 3 * 1e-2, 1e-12) * lam * lam
    floor = math.log(NOISE_FLOOR * max(r, 1e-12))
    start = np.concatenate([first.p, [math.log(q0), math.log(max(noise ** 2, r * 1e-3))]])
    # the likelihood's own scales: the least-squares covariance ignores the random torque
    sd_y = math.sqrt(r / y.size)
    se0 = np.array([0.1 * max(first.p[0], 1e-3), 1e-4 * first.p[1], sd_y, sd_y / gain, sd_y / gain * wd, 0.3, 0.05])
    lower = np.array([-np.inf, 0.0, -np.inf, -np.inf, -np.inf, floor - 20, floor])
    fit = kalman.ml_fit(nll, start, se0, lower, per_sample=per_sample, noise=NOISE, nll_many=nll_many)
    # Coulomb friction at the hinge: about beta x the swing's speed at the same decay
    gam_scale = max(fit.p[0], 1e-3) * phi_amp * wd
    both, zc = kalman.added_term(nll, fit, se0, gam_scale, lower, nll_many)
    coulomb = zc > Z_REJECT  # friction opposes the motion: a negative torque is no friction
    if coulomb:
        se = np.sqrt(np.diag(fit.cov))
        fit = kalman.ml_fit(nll, both, np.append(np.where(se > 0, se, se0), gam_scale), np.append(lower, -np.inf),
                            per_sample=per_sample, noise=NOISE, nll_many=nll_many)
    checks = [Check("Coulomb friction", zc, Z_REJECT, coulomb,
                    f"likelihood-ratio z = {zc:.3g} for a constant friction torque: " +
                    ("the data show a linear decay part (Coulomb friction at the hinge, not in patchgen's plant)"
                     if coulomb else "the decay is exponential: viscous friction alone, as the thesis found"))]
    nll(fit.p)
    est = {}
    cov2 = fit.cov[:2, :2]
    lv, lse = delta(lambda v: g / v[1], fit.p[:2], cov2)
    est["l"] = normal(lv, lse, "m", ML_KALMAN, rec.source, fit.dof_of(1))
    est["beta"] = normal(fit.p[0], fit.se(0), "1/s", ML_KALMAN, rec.source, fit.dof_of(0))
    if m is not None:
        cov3 = np.zeros((3, 3))
        cov3[:2, :2], cov3[2, 2] = cov2, m_se ** 2
        c_of = lambda v: v[0] * v[2] * (g / v[1]) ** 2
        cv, cse = delta(c_of, np.append(fit.p[:2], m), cov3)
        grad = np.zeros(fit.p.size)
        grad[:2] = [m * (g / fit.p[1]) ** 2, -2 * fit.p[0] * m * g * g / fit.p[1] ** 3]
        est["c"] = normal(cv, cse, "kg m^2/s", ML_KALMAN, rec.source, fit.dof(grad))
    if coulomb:
        est["coulomb"] = normal(fit.p[7], fit.se(7), "rad/s^2", ML_KALMAN, rec.source, fit.dof_of(7))
    beta = fit.p[0]
    env = amp[0] * np.exp(-0.5 * beta * (tm - tm[0]))
    t_plot = t + t_all[k0]
    return TestFit(rec.source, rec.test, est, checks, title="free swing, hanging",
                   notes=[f"period {period:.5g} s over {ups.size - 1} swings, fitted from {t_all[k0]:.3g} s; "
                          f"random torque q = {math.exp(fit.p[5]):.3g} rad^2/s^3"],
                   panels=[Panel(t_plot, y, pred.copy(), f"theta ({unit})"),
                           Panel(tm + t_all[k0], amp, env, f"amplitude ({unit})", points=True),
                           Panel(t_plot, y - pred, None, f"innovation ({unit})")])


def rigid(result, m: float, l_cm: float, source: str) -> None:
    """A rigid pendulum's plant entries from its swing and its centre of mass: the swing gives the
    length L = I / (m l) of the point mass that swings as it does and, as a point mass, c = beta m L^2;
    with the pivot-to-centre distance l measured (``l_cm_m``), I = m l L, so J = m l (L - l) and
    c = beta I = beta m l L (``result.plant``'s l, J and c replaced; L kept in ``result.extra``)."""
    plant = result.plant
    L = plant["l"].estimate
    result.extra["swing length L"] = L
    plant["l"] = Parameter(l_cm, "m", None, f"{source} (l_cm_m: pivot to the centre of mass)")
    J = m * l_cm * (L.value - l_cm)
    if J < 0:
        result.warnings.append(f"the swing's length {L.value:.4g} m is shorter than the centre of mass's {l_cm:.4g} m: "
                               "no rigid body swings so; the plant takes J = 0")
    est = normal(J, m * l_cm * L.se, "kg m^2", f"m l (L - l), L from the swing; {L.method}", L.source, L.dof)
    plant["J"] = Parameter(max(J, 0.0), "kg m^2", est, f"{L.source}: m l (L - l), L = {L.value:.5g} m")
    if "c" in plant:
        c = plant["c"].estimate
        k = l_cm / L.value
        est = normal(c.value * k, c.se * k, c.unit, f"beta m l L; {c.method}", c.source, c.dof)
        plant["c"] = Parameter(est.value, c.unit, est, est.source)
