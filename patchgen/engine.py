"""The compiled inner loop: fixed-step RK4 of the nonlinear plant, the actuator and the patched
circuit, one run per thread (numba ``prange``), per-run summaries and optional histories.

Everything the loop needs arrives as flat float/int arrays (see ``EngineConfig``), so a run is
``n_steps`` iterations of: draw the noise held over the step, four RK4 stages of
plant + actuator + circuit, clip integrating amplifiers at the rails, check limit switches,
fall and overloads. A run ends at the scenario's end or when the limit switches cut the
motor: the bench experiment is then over, and what the cart does next depends on end stops no
profile describes. Noise is held over each step (zero-order hold) with the low-frequency
density of the given rms over its bandwidth (``noise_process``). Disturbances are averaged over
each step, so a push keeps its impulse whatever the step.

Default step (``default_step``), chosen by measurement (tests/test_engine.py; noise off, since a
noise realisation depends on the step): on the bench (dead zone, lag, clipping, switches: events
that make RK4 first order) 2 ms, where halving moves theta by at most 2e-5 rad RMS on the standard
scenarios (at 5 ms, up to 1e-3 rad); ideal (smooth) 10 ms, where halving moves theta by 1e-7
rad RMS. Either way no more than the fastest time constant in the loop (a differentiator's
roll-off, a lag, the actuator's tau): RK4 is stable to 2.8 time constants and damps such a
mode within 2 % per step there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba as nb
import numpy as np

from .circuit import DIFFERENTIATOR, INTEGRATOR, LAG, SUMMER
from .plant import PLANT_STATES

BENCH_DT_S = 0.002
IDEAL_DT_S = 0.01
STEPS_PER_TIME_CONSTANT = 1.0

ACT_GAIN, ACT_LAG, ACT_LAG_ZERO = 0, 1, 2
DIST_CART_FORCE, DIST_TIP_FORCE, DIST_STEP = 0, 1, 2
# fast-math without the no-NaN/no-infinity assumptions (NaN marks "never", inf "no limit")
_FAST = {"nsz", "arcp", "contract", "afn", "reassoc"}
S_INDEX = PLANT_STATES.index("s")  # the sensor whose reference a step command moves

# history channels before the amplifier outputs
HISTORY_CHANNELS = ("t", "s", "theta", "s_dot", "theta_dot", "s_ref", "u_c", "force")


@dataclass(frozen=True)
class EngineConfig:
    """Everything one batch of runs needs, as arrays the compiled loop accepts."""

    dt: float
    n_steps: int
    stride: int  # record every stride-th step into the history
    x0: np.ndarray  # plant state at t = 0
    plant: np.ndarray  # M, m, l, g, b_VF, c, half track (d/2)
    plant_spread: np.ndarray  # per plant parameter: each run draws it uniformly within +/- this fraction
    limit_switches: bool
    sensor_state: np.ndarray
    sensor_gain: np.ndarray
    sensor_noise_a: np.ndarray  # per-step noise memory (0 = white)
    sensor_noise_std: np.ndarray  # per-step innovation std (V)
    amp_kind: np.ndarray
    in_ptr: np.ndarray
    in_src: np.ndarray
    in_gain: np.ndarray
    param1: np.ndarray
    param2: np.ndarray
    ic_V: np.ndarray
    drift: np.ndarray  # V/s magnitude per amplifier (sign drawn per run)
    amp_noise_a: np.ndarray
    amp_noise_std: np.ndarray
    saturation_V: float
    clip: bool  # clip outputs at +/- saturation_V (overloads are recorded either way)
    output_index: int
    actuator: int  # ACT_*
    K_U: float
    tau: float
    dead_zone_V: float
    force_limit_N: float
    dist_kind: np.ndarray
    dist_t0: np.ndarray
    dist_t1: np.ndarray
    dist_value: np.ndarray
    fall_angle: float  # rad


def default_step(time_constants: list[float], ideal: bool) -> float:
    """The fixed step (s) when a scenario gives none (see the module docstring)."""
    base = IDEAL_DT_S if ideal else BENCH_DT_S
    return min([base] + [tc / STEPS_PER_TIME_CONSTANT for tc in time_constants if tc > 0])


def noise_process(rms: float, bandwidth_Hz: float, dt: float) -> tuple[float, float]:
    """(memory a, innovation std) of held noise n_k+1 = a n_k + std w_k that has rms ``rms``
    over ``bandwidth_Hz``, i.e. one-sided density rms^2 / B at low frequency, at step dt.

    With q = 1 / (2 dt B): a coarse step (q <= 1, Nyquist below B) carries only the in-band
    part, white, std = rms sqrt(q); a fine step uses a = (q - 1) / (q + 1), which gives the same
    density with stationary rms ``rms`` (the two meet at q = 1).
    """
    if rms <= 0.0:
        return 0.0, 0.0
    q = 1.0 / (2.0 * dt * bandwidth_Hz)
    if q <= 1.0:
        return 0.0, rms * math.sqrt(q)
    a = (q - 1.0) / (q + 1.0)
    return a, rms * math.sqrt(1.0 - a * a)


@dataclass
class BatchOutput:
    """Per-run summaries (arrays over runs) and the histories of the first ``n_history`` runs."""

    trip_time: np.ndarray  # s, NaN if the limit switches never tripped
    fall_time: np.ndarray  # s, NaN if never past the fall angle
    max_abs_theta: np.ndarray
    max_abs_s: np.ndarray
    rms_theta: np.ndarray
    max_abs_u_c: np.ndarray
    max_abs_force: np.ndarray
    overload_first: np.ndarray  # (runs, amps) s, NaN if never
    overload_time: np.ndarray  # (runs, amps) total time overloaded, s
    final_state: np.ndarray  # (runs, 4)
    history: np.ndarray  # (n_history, samples, channels)
    history_length: np.ndarray  # samples recorded per history run (a run ends at a trip)


def draw_batch(cfg: EngineConfig, rngs: list[np.random.Generator]
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each run's random draws, from its own generator: the drift sign of each amplifier, then
    standard normals (steps + 1, sensors + amplifiers) when any noise is on (float32: noise
    needs no more, and it halves the memory traffic), then, with a parameter spread, the run's
    plant. Drawn by numpy outside the compiled loop: its bulk normals are fast, and a run's
    draws do not depend on threads or batches."""
    runs = len(rngs)
    n_amp = len(cfg.amp_kind)
    noisy = bool(cfg.sensor_noise_std.any() or cfg.amp_noise_std.any())
    signs = np.empty((runs, n_amp))
    shape = (runs, cfg.n_steps + 1, len(cfg.sensor_state) + n_amp) if noisy else (runs, 0, 0)
    gauss = np.empty(shape, dtype=np.float32)
    plants = np.repeat(cfg.plant[None, :], runs, axis=0)
    spread = cfg.plant_spread.any()
    for r, rng in enumerate(rngs):
        signs[r] = np.where(rng.random(n_amp) < 0.5, 1.0, -1.0)
        if noisy:
            rng.standard_normal(out=gauss[r], dtype=np.float32)
        if spread:
            plants[r] *= 1.0 + cfg.plant_spread * rng.uniform(-1.0, 1.0, cfg.plant.shape[0])
    return signs, gauss, plants


def run_batch(cfg: EngineConfig, draws: tuple[np.ndarray, np.ndarray, np.ndarray],
              n_history: int) -> BatchOutput:
    """One run per row of ``draws`` (see draw_batch), in parallel threads, without the GIL;
    histories for the first n_history runs."""
    signs, gauss, plants = draws
    runs, n_amp = signs.shape
    n_samples = cfg.n_steps // cfg.stride + 2  # stride samples, and the last one off-stride
    out = BatchOutput(
        trip_time=np.full(runs, np.nan), fall_time=np.full(runs, np.nan),
        max_abs_theta=np.zeros(runs), max_abs_s=np.zeros(runs), rms_theta=np.zeros(runs),
        max_abs_u_c=np.zeros(runs), max_abs_force=np.zeros(runs),
        overload_first=np.full((runs, n_amp), np.nan), overload_time=np.zeros((runs, n_amp)),
        final_state=np.zeros((runs, 4)),
        history=np.zeros((n_history, n_samples, len(HISTORY_CHANNELS) + n_amp)),
        history_length=np.zeros(n_history, dtype=np.int64),
    )
    args = (cfg.dt, cfg.n_steps, cfg.stride, cfg.x0, cfg.limit_switches,
            cfg.sensor_state, cfg.sensor_gain, cfg.sensor_noise_a, cfg.sensor_noise_std,
            cfg.amp_kind, cfg.in_ptr, cfg.in_src, cfg.in_gain, cfg.param1, cfg.param2, cfg.ic_V,
            cfg.drift, cfg.amp_noise_a, cfg.amp_noise_std, cfg.saturation_V, cfg.clip,
            cfg.output_index, cfg.actuator, cfg.K_U, cfg.tau, cfg.dead_zone_V, cfg.force_limit_N,
            cfg.dist_kind, cfg.dist_t0, cfg.dist_t1, cfg.dist_value, cfg.fall_angle,
            out.trip_time, out.fall_time, out.max_abs_theta, out.max_abs_s, out.rms_theta,
            out.max_abs_u_c, out.max_abs_force, out.overload_first, out.overload_time,
            out.final_state, out.history, out.history_length)
    if runs == 1:  # no thread launch: it costs more than a lone run on a busy machine
        _one_run(0, signs[0], gauss[0], args[0], args[1], args[2], args[3], plants[0], *args[4:])
    else:
        _batch(signs, gauss, plants, *args)
    return out


@nb.njit(cache=True, error_model="numpy", fastmath=_FAST)
def plant_rhs(p, th, sd, thd, force, tip_force):
    """Eq. 2.16-2.19 (as patchgen.plant.nonlinear_rhs) plus a horizontal force at the pendulum
    tip (distance l): generalised forces tip_force on s and tip_force * l * cos(theta) on theta.
    Returns (ds, dtheta, ds_dot, dtheta_dot); p = (M, m, l, g, b_VF, c, ...)."""
    M, m, l, g, b, c = p[0], p[1], p[2], p[3], p[4], p[5]
    sn, cs = math.sin(th), math.cos(th)
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
def _circuit(xt, zt, s_ref, nz_s, nz_a, sensor_state, sensor_gain, amp_kind, in_ptr, in_src,
             in_gain, param1, param2, drift, sat, clip, sig, raw, dz_out):
    """Evaluate sensors and amplifiers in order: sig (clipped if clip), raw (before clipping),
    and the amplifier state derivatives into dz_out."""
    ns = sensor_state.shape[0]
    for i in range(ns):
        q = xt[sensor_state[i]]
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
             sensor_state, sensor_gain, sna, sns,
             amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag, ana, ans, sat, clip,
             out_index, act, K_U, tau, dz, flim,
             dist_kind, dist_t0, dist_t1, dist_value, fall_angle,
             trip_t, fall_t, max_th, max_s, rms_th, max_uc, max_f, ovl_first, ovl_time, final,
             hist, hist_len):
    ns = sensor_state.shape[0]
    na = amp_kind.shape[0]
    half = p[6]
    noisy = gauss.shape[0] > 0
    drift = drift_mag * sign  # each integrating amplifier drifts one way, drawn per run
    nz_s = np.zeros(ns)
    nz_a = np.zeros(na)
    if noisy:  # start the noise in its stationary distribution
        for i in range(ns):
            nz_s[i] = gauss[0, i] * sns[i] / math.sqrt(1.0 - sna[i] * sna[i])
        for j in range(na):
            nz_a[j] = gauss[0, ns + j] * ans[j] / math.sqrt(1.0 - ana[j] * ana[j])
    xp = x0.copy()
    za = ic.copy()
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
        _circuit(xp, za, 0.0, quiet_s, quiet_a, sensor_state, sensor_gain, amp_kind, in_ptr,
                 in_src, in_gain, param1, param2, drift, sat, False, sig, raw, zt)
        for j in range(na):
            if amp_kind[j] == DIFFERENTIATOR:
                za[j] -= raw[j] / param1[j]
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
                xat = xa
            else:
                c = h if st == 3 else 0.5 * h
                for i in range(4):
                    xt[i] = xp[i] + c * kp[st - 1, i]
                for j in range(na):
                    zt[j] = za[j] + c * ka[st - 1, j]
                xat = xa + c * kx[st - 1]
            _circuit(xt, zt, s_ref, nz_s, nz_a, sensor_state, sensor_gain, amp_kind, in_ptr,
                     in_src, in_gain, param1, param2, drift, sat, clip, sig, raw, ka[st])
            uc = sig[out_index]
            v = 0.0
            if uc > dz:
                v = uc - dz
            elif uc < -dz:
                v = uc + dz
            if act == ACT_GAIN:
                force = K_U * v
                kx[st] = 0.0
            elif act == ACT_LAG:
                force = xat
                kx[st] = (K_U * v - xat) / tau
            else:
                force = K_U / tau * (v - xat)
                kx[st] = (v - xat) / tau
            if force > flim:
                force = flim
            elif force < -flim:
                force = -flim
            if tripped:
                force = 0.0
            d0, d1, d2, d3 = plant_rhs(p, xt[1], xt[2], xt[3], force + f_cart, f_tip)
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
            if not fallen and abs(th) > fall_angle:
                fallen = True
                fall_t[r] = t
            for j in range(na):
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


@nb.njit(cache=True, parallel=True, nogil=True, error_model="numpy", fastmath=_FAST)
def _batch(signs, gauss, plants, h, n_steps, stride, x0, limit_on,
           sensor_state, sensor_gain, sna, sns,
           amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag, ana, ans, sat, clip,
           out_index, act, K_U, tau, dz, flim,
           dist_kind, dist_t0, dist_t1, dist_value, fall_angle,
           trip_t, fall_t, max_th, max_s, rms_th, max_uc, max_f, ovl_first, ovl_time, final, hist,
           hist_len):
    for r in nb.prange(signs.shape[0]):
        _one_run(r, signs[r], gauss[r], h, n_steps, stride, x0, plants[r], limit_on,
                 sensor_state, sensor_gain, sna, sns,
                 amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag, ana, ans, sat,
                 clip, out_index, act, K_U, tau, dz, flim,
                 dist_kind, dist_t0, dist_t1, dist_value, fall_angle,
                 trip_t, fall_t, max_th, max_s, rms_th, max_uc, max_f, ovl_first, ovl_time, final,
                 hist, hist_len)
