"""The engine as it was before runs went side by side: one run per call, a scalar loop, fast-math.
Kept verbatim (apart from taking its normals as float64, the bench's random forces on the plant,
each run's own actuator, sensor constants and noise levels, and this header) as the reference the
blocked kernel (patchgen.bench.kernel) is checked against, run for run, on the same noise streams."""

import math

import numba as nb
import numpy as np

from patchgen.bench.circuit import DIFFERENTIATOR, INTEGRATOR, LAG, SUMMER
from patchgen.bench.engine import EngineConfig
from patchgen.bench.kernel import DIST_CART_FORCE, DIST_TIP_FORCE, H_AMPS, Draws
from patchgen.bench.lanes import ACT_GAIN, ACT_LAG, ACT_MOTOR, S_INDEX
from patchgen.bench.noise import run_normals

_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}


def reference_runs(cfg: EngineConfig, draws: Draws, n_history: int = 1):
    """Every run of ``draws`` (patchgen.bench.engine.draw_batch) through the old loop, with the
    normals the kernel draws for its key. Returns arrays like patchgen.bench.engine.BatchOutput's."""
    keys, signs, plants = draws.keys, draws.signs, draws.plants
    st, sensors, noise, w, dist = cfg.records
    runs, n_amp = signs.shape
    ns = len(sensors.state)
    nch = ns + n_amp + 2  # the voltages, then the random forces on the cart and at the tip
    noisy = bool(draws.noise_std.any())
    n_samples = st.steps // st.stride + 2
    out = {"trip_time": np.full(runs, np.nan), "fall_time": np.full(runs, np.nan),
           "max_abs_theta": np.zeros(runs), "max_abs_s": np.zeros(runs), "rms_theta": np.zeros(runs),
           "max_abs_u_c": np.zeros(runs), "max_abs_force": np.zeros(runs), "limit_time": np.zeros(runs),
           "overload_first": np.full((runs, n_amp), np.nan), "overload_time": np.zeros((runs, n_amp)),
           "amp_peak": np.zeros((runs, n_amp)),
           "final_state": np.zeros((runs, 4)),
           "history": np.zeros((n_history, n_samples, H_AMPS + n_amp)),
           "history_length": np.zeros(n_history, dtype=np.int64)}
    std = draws.noise_std
    for r in range(runs):
        gauss = (run_normals(keys[r, 0], keys[r, 1], st.steps, nch) if noisy
                 else np.zeros((0, 0)))
        _one_run(r, signs[r], gauss, st.dt, st.steps, st.stride, st.x0, plants[r],
                 st.limit_switches, sensors.state, draws.sensor_gains[r], sensors.quantum, sensors.filt,
                 sensors.source, sensors.wn, sensors.zeta, noise.a[:ns], std[r, :ns],
                 w.kind, w.in_ptr, w.in_src, w.in_gain, w.param1, w.param2, w.ic, w.drift,
                 noise.a[ns:ns + n_amp], std[r, ns:ns + n_amp], noise.a[ns + n_amp:],
                 std[r, ns + n_amp:], st.saturation, st.clip, st.output, st.actuator,
                 *draws.actuators[r], dist.kind, dist.t0, dist.t1,
                 dist.value, st.fall_angle, out["trip_time"], out["fall_time"], out["max_abs_theta"],
                 out["max_abs_s"], out["rms_theta"], out["max_abs_u_c"], out["max_abs_force"], out["limit_time"],
                 out["overload_first"], out["overload_time"], out["amp_peak"], out["final_state"], out["history"],
                 out["history_length"])
    return out


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def plant_rhs(p, th, sd, thd, force, tip_force):
    """Eq. 2.16-2.19 (as patchgen.plant.equations.nonlinear_rhs) plus a horizontal force at the pendulum
    tip (distance l): generalised forces tip_force on s and tip_force * l * cos(theta) on theta.
    Returns (ds, dtheta, ds_dot, dtheta_dot); p = (M, m, l, g, b_VF, c, ...)."""
    M, m, l, g, b, c = p[0], p[1], p[2], p[3], p[4], p[5]
    sn, cs = math.sin(th), math.cos(th)
    J = p[7]
    if J != 0.0:  # a rigid pendulum: the Lagrangian's 2 x 2 mass matrix solved as it stands
        a11, a12, a22 = M + m, m * l * cs, J + m * l * l
        r1 = force - b * sd + m * l * sn * thd * thd + tip_force
        r2 = m * g * l * sn - c * thd + tip_force * l * cs
        det = a11 * a22 - a12 * a12
        return sd, thd, (a22 * r1 - a12 * r2) / det, (a11 * r2 - a12 * r1) / det
    den = (M + m) - m * cs * cs
    bracket = -b * sd + m * l * thd * thd * sn + (c / l) * thd * cs - m * g * sn * cs + force
    sdd = (bracket + tip_force * sn * sn) / den
    thdd = -c / (m * l * l) * thd + g / l * sn + tip_force * cs / (m * l) - cs * sdd / l
    return sd, thd, sdd, thdd


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST, inline="always")
def _rail(out, sat, clip):
    """An amplifier output held inside the rails (when clipping is on)."""
    if clip:
        if out > sat:
            return sat
        if out < -sat:
            return -sat
    return out


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _count(x, quantum):
    """An encoder's reading: x to the nearest whole count (quantum 0: x)."""
    if quantum == 0.0:
        return x
    return quantum * math.floor(x / quantum + 0.5)


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _circuit(xt, zt, xft, s_ref, nz_s, nz_a, sensor_state, sensor_gain, quantum, filt, amp_kind, in_ptr,
             in_src, in_gain, param1, param2, drift, sat, clip, sig, raw, dz_out):
    """Evaluate sensors and amplifiers in order: sig (clipped if clip), raw (before clipping),
    and the amplifier state derivatives into dz_out. A filtered sensor reads its filter's rate."""
    ns = sensor_state.shape[0]
    for i in range(ns):
        if filt[i] >= 0:
            sig[i] = sensor_gain[i] * xft[2 * filt[i] + 1] + nz_s[i]
            continue
        q = _count(xt[sensor_state[i]], quantum[i])
        if sensor_state[i] == S_INDEX:
            q -= s_ref
        sig[i] = sensor_gain[i] * q + nz_s[i]
    na = amp_kind.shape[0]
    # outputs in evaluation order (the compiler puts integrators and lags, whose outputs are their
    # states, before everything that reads them)
    for j in range(na):
        kd = amp_kind[j]
        if kd == INTEGRATOR or kd == LAG:
            out = zt[j]
        else:
            acc = 0.0
            for k in range(in_ptr[j], in_ptr[j + 1]):
                acc += in_gain[k] * sig[in_src[k]]
            if kd == SUMMER:
                out = -acc
                dz_out[j] = 0.0
            else:  # DIFFERENTIATOR with roll-off
                out = -param1[j] * (acc - zt[j])
                dz_out[j] = param2[j] * (acc - zt[j])
        out += nz_a[j]
        raw[j] = out
        sig[ns + j] = _rail(out, sat, clip)
    # last, the integrating amplifiers' inputs, now that every signal of this instant is known
    for j in range(na):
        kd = amp_kind[j]
        if kd == INTEGRATOR or kd == LAG:
            acc = 0.0
            for k in range(in_ptr[j], in_ptr[j + 1]):
                acc += in_gain[k] * sig[in_src[k]]
            if kd == INTEGRATOR:
                dz_out[j] = -param1[j] * acc + drift[j]
            else:
                dz_out[j] = param1[j] * (-acc - zt[j]) + drift[j]
    return 0


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def _one_run(r, sign, gauss, h, n_steps, stride, x0, p, limit_on,
             sensor_state, sensor_gain, quantum, filt, source, wn, zeta, sna, sns,
             amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag, ana, ans, fna, fns, sat, clip,
             out_index, act, K_U, tau, dz, flim, emf,
             dist_kind, dist_t0, dist_t1, dist_value, fall_angle,
             trip_t, fall_t, max_th, max_s, rms_th, max_uc, max_f, lim_t, ovl_first, ovl_time, amp_peak, final,
             hist, hist_len):
    ns = sensor_state.shape[0]
    na = amp_kind.shape[0]
    half = p[6]
    noisy = gauss.shape[0] > 0
    drift = drift_mag * sign  # each integrating amplifier drifts one way, drawn per run
    nz_s = np.zeros(ns)
    nz_a = np.zeros(na)
    nz_f = np.zeros(2)  # random force on the cart, at the tip
    if noisy:  # start the noise in its stationary distribution
        for i in range(ns):
            nz_s[i] = gauss[0, i] * sns[i] / math.sqrt(1.0 - sna[i] * sna[i])
        for j in range(na):
            nz_a[j] = gauss[0, ns + j] * ans[j] / math.sqrt(1.0 - ana[j] * ana[j])
        for k in range(2):
            nz_f[k] = gauss[0, ns + na + k] * fns[k] / math.sqrt(1.0 - fna[k] * fna[k])
    xp = x0.copy()
    za = np.where(np.isnan(ic), 0.0, ic)
    nf = 0
    for i in range(ns):
        nf = max(nf, filt[i] + 1)
    xf = np.zeros(2 * nf)  # each velocity filter's (y, y'), settled on the run's start
    for i in range(ns):
        if filt[i] >= 0:
            xf[2 * filt[i]] = _count(x0[source[i]], quantum[i])
            xf[2 * filt[i] + 1] = x0[sensor_state[i]]
    kf = np.zeros((4, 2 * nf))
    xft = np.zeros(2 * nf)
    sig = np.zeros(ns + na)
    raw = np.zeros(na)
    kp = np.zeros((4, 4))  # RK4 slopes of the plant, amplifier and actuator states
    ka = np.zeros((4, na))
    kx = np.zeros(4)
    xt = np.zeros(4)
    zt = np.zeros(na)
    # a differentiator starts settled on its input (the angle was held before the run): set its
    # filter state to its input, in evaluation order (one pass per amplifier reaches every chain)
    quiet_s = np.zeros(ns)
    quiet_a = np.zeros(na)
    for _ in range(na):
        _circuit(xp, za, xf, 0.0, quiet_s, quiet_a, sensor_state, sensor_gain, quantum, filt, amp_kind, in_ptr,
                 in_src, in_gain, param1, param2, drift, sat, False, sig, raw, zt)
        for j in range(na):
            if amp_kind[j] == DIFFERENTIATOR:
                za[j] -= raw[j] / param1[j]
    # an integrator with no IC (NaN) starts settled: the state where its slope is zero, by bisection
    # on the slope (it falls as the state rises: the integrator closes a lag)
    for j in range(na):
        if math.isnan(ic[j]):
            lo_z, hi_z = -1e3, 1e3
            for _ in range(200):
                za[j] = 0.5 * (lo_z + hi_z)
                _circuit(xp, za, xf, 0.0, quiet_s, quiet_a, sensor_state, sensor_gain, quantum, filt, amp_kind,
                         in_ptr, in_src, in_gain, param1, param2, drift, sat, False, sig, raw, zt)
                if zt[j] > 0.0:
                    lo_z = za[j]
                else:
                    hi_z = za[j]
    xa = 0.0
    tripped = False
    fallen = False
    pinned = np.zeros(na, dtype=np.bool_)  # clipped at a rail by the last update
    sum_th2 = 0.0
    mth = 0.0
    ms = 0.0
    muc = 0.0
    mf = 0.0
    sample = 0
    n = 0
    for n in range(n_steps + 1):
        t = n * h
        if noisy and n > 0:  # new noise for this step
            for i in range(ns):
                nz_s[i] = sna[i] * nz_s[i] + sns[i] * gauss[n, i]
            for j in range(na):
                nz_a[j] = ana[j] * nz_a[j] + ans[j] * gauss[n, ns + j]
            for k in range(2):
                nz_f[k] = fna[k] * nz_f[k] + fns[k] * gauss[n, ns + na + k]
        # disturbances averaged over the step (so an impulse keeps its area at any step)
        f_cart = 0.0
        f_tip = 0.0
        s_ref = 0.0
        for k in range(dist_kind.shape[0]):
            overlap = min(t + h, dist_t1[k]) - max(t, dist_t0[k])
            if overlap > 0.0:
                v = dist_value[k] * overlap / h
                if dist_kind[k] == DIST_CART_FORCE:
                    f_cart += v
                elif dist_kind[k] == DIST_TIP_FORCE:
                    f_tip += v
                else:
                    s_ref += v
        force0 = 0.0
        last = False
        for st in range(4):
            if st == 0:
                for i in range(4):
                    xt[i] = xp[i]
                for j in range(na):
                    zt[j] = za[j]
                for i in range(2 * nf):
                    xft[i] = xf[i]
                xat = xa
            else:
                c = h if st == 3 else 0.5 * h
                for i in range(4):
                    xt[i] = xp[i] + c * kp[st - 1, i]
                for j in range(na):
                    zt[j] = za[j] + c * ka[st - 1, j]
                for i in range(2 * nf):
                    xft[i] = xf[i] + c * kf[st - 1, i]
                xat = xa + c * kx[st - 1]
            for i in range(ns):  # y'' = wn^2 (counted position - y) - 2 zeta wn y'
                k = filt[i]
                if k >= 0:
                    kf[st, 2 * k] = xft[2 * k + 1]
                    kf[st, 2 * k + 1] = (wn[i] * wn[i] * (_count(xt[source[i]], quantum[i]) - xft[2 * k])
                                         - 2.0 * zeta[i] * wn[i] * xft[2 * k + 1])
            _circuit(xt, zt, xft, s_ref, nz_s, nz_a, sensor_state, sensor_gain, quantum, filt, amp_kind, in_ptr,
                     in_src, in_gain, param1, param2, drift, sat, clip, sig, raw, ka[st])
            uc = sig[out_index]
            v = 0.0
            if uc > dz:
                v = uc - dz
            elif uc < -dz:
                v = uc + dz
            if act == ACT_MOTOR:  # the amplifier limits the voltage; the back-EMF acts after it
                cmd = min(max(K_U * v, -flim), flim)
                limited = abs(K_U * v) >= flim
                if tau > 0.0:
                    force = xat
                    kx[st] = (cmd - emf * xt[2] - xat) / tau
                else:
                    force = cmd - emf * xt[2]
                    kx[st] = 0.0
            else:
                if act == ACT_GAIN:
                    force = K_U * v
                    kx[st] = 0.0
                elif act == ACT_LAG:
                    force = xat
                    kx[st] = (K_U * v - xat) / tau
                else:
                    force = K_U / tau * (v - xat)
                    kx[st] = (v - xat) / tau
                limited = abs(force) >= flim
                if force > flim:
                    force = flim
                elif force < -flim:
                    force = -flim
            if tripped:
                force = 0.0
            d0, d1, d2, d3 = plant_rhs(p, xt[1], xt[2], xt[3], force + (f_cart + nz_f[0]),
                                     f_tip + nz_f[1])
            kp[st, 0] = d0
            kp[st, 1] = d1
            kp[st, 2] = d2
            kp[st, 3] = d3
            if st > 0:
                continue
            # summaries at time t (state and signals of the step's first stage); the run ends
            # at the end of the scenario or when the limit switches have cut the motor
            force0 = force
            last = n == n_steps or tripped
            th = xp[1]
            sum_th2 += th * th
            mth = max(mth, abs(th))
            ms = max(ms, abs(xp[0]))
            muc = max(muc, abs(uc))
            mf = max(mf, abs(force))
            if limited and not last:
                lim_t[r] += h
            up = not fallen  # the peaks are the balancing's: up to the step the fall is seen at
            if not fallen and abs(th) > fall_angle:
                fallen = True
                fall_t[r] = t
            for j in range(na):
                if up:
                    amp_peak[r, j] = max(amp_peak[r, j], abs(raw[j]))
                if abs(raw[j]) > sat or pinned[j]:
                    if math.isnan(ovl_first[r, j]):
                        ovl_first[r, j] = t
                    if not last:
                        ovl_time[r, j] += h
            if r < hist.shape[0] and (n % stride == 0 or last):
                hist[r, sample, 0] = t
                for i in range(4):
                    hist[r, sample, 1 + i] = xp[i]
                hist[r, sample, 5] = s_ref
                hist[r, sample, 6] = uc
                hist[r, sample, 7] = force0
                for j in range(na):
                    hist[r, sample, 8 + j] = sig[ns + j]
                sample += 1
                hist_len[r] = sample
            if last:
                break
        if last:
            break
        for i in range(4):
            xp[i] += h / 6.0 * (kp[0, i] + 2.0 * kp[1, i] + 2.0 * kp[2, i] + kp[3, i])
        for j in range(na):
            za[j] += h / 6.0 * (ka[0, j] + 2.0 * ka[1, j] + 2.0 * ka[2, j] + ka[3, j])
            pinned[j] = False
            if clip and amp_kind[j] != DIFFERENTIATOR:  # a capacitor cannot charge past the rails
                if za[j] > sat:
                    za[j] = sat
                    pinned[j] = True
                elif za[j] < -sat:
                    za[j] = -sat
                    pinned[j] = True
        xa += h / 6.0 * (kx[0] + 2.0 * kx[1] + 2.0 * kx[2] + kx[3])
        for i in range(2 * nf):
            xf[i] += h / 6.0 * (kf[0, i] + 2.0 * kf[1, i] + 2.0 * kf[2, i] + kf[3, i])
        if limit_on and not tripped and abs(xp[0]) >= half:
            tripped = True
            trip_t[r] = t + h
    max_th[r] = mth
    max_s[r] = ms
    rms_th[r] = math.sqrt(sum_th2 / (n + 1))
    max_uc[r] = muc
    max_f[r] = mf
    for i in range(4):
        final[r, i] = xp[i]

