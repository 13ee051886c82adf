"""The compiled inner loop, runs side by side: blocks of up to LANES runs, every state an array
(quantity, lane), every inner loop over lanes, so that LLVM vectorises each operation across runs.

One step of one block: draw the lanes' noise, four RK4 stages of plant + actuator + circuit,
clip integrating amplifiers at the rails, check limit switches, fall and overloads. A lane whose
run has ended (the limit switches cut the motor) keeps being computed with the others but is no
longer recorded; the block stops when every lane has ended or at the scenario's end.

The arithmetic is plain IEEE, without fast-math, not even fused multiply-add (it is 7 % faster,
but LLVM fuses differently in a loop's vectorised body and its scalar remainder), so each lane's
result is bit for bit the same whatever the number of lanes in its block, its place in the
block, the number of threads or the order of the blocks: a run depends only on its own inputs
(tests/test_kernel.py checks it). Every compiled function lives in this one file
because numba's disk cache is stamped with the content of the file of the function it compiled:
a change in a callee elsewhere would not invalidate it.

Noise: counter-based, so drawn inside the loop for all lanes at once. Philox4x32-10 (Salmon et
al., "Parallel random numbers: as easy as 1, 2, 3", SC 2011) with the run's key and counter
(step, channel group, attempt, domain) gives the bits; the Marsaglia-Tsang ziggurat makes each
32-bit word normal: 10 bits pick one of 1024 layers, 1 the sign, 21 the abscissa (a resolution of
5e-7 of the layer's width). A word outside its layer's inner rectangle (0.43 % of them; 1.5 %
with 256 layers, where the refused words cost more than the rest) takes the wedge or tail test
with further counters of its step and channel.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from .circuit import DIFFERENTIATOR, INTEGRATOR, LAG, SUMMER
from .plant import PLANT_STATES

LANES = 64  # runs per block
ACT_GAIN, ACT_LAG, ACT_LAG_ZERO = 0, 1, 2
DIST_CART_FORCE, DIST_TIP_FORCE, DIST_STEP = 0, 1, 2
S_INDEX = PLANT_STATES.index("s")  # the sensor whose reference a step command moves
# scalar settings, packed: floats and integers
F_DT, F_SAT, F_K_U, F_TAU, F_DEAD, F_FLIM, F_FALL = range(7)
I_STEPS, I_STRIDE, I_LIMIT, I_CLIP, I_OUT, I_ACT = range(6)
# per-run results: event times (NaN: never), maxima, RMS theta, final plant state
R_TRIP, R_FALL, R_MAX_TH, R_MAX_S, R_RMS_TH, R_MAX_UC, R_MAX_F, R_FINAL = range(8)
N_RESULTS = R_FINAL + 4
# cached on disk; IEEE arithmetic (see above); no Python exceptions for x / 0
_JIT = {"cache": True, "error_model": "numpy"}

# ---- noise -----------------------------------------------------------------------------------

_M0, _M1 = np.uint64(0xD2511F53), np.uint64(0xCD9E8D57)
_W0, _W1 = np.uint64(0x9E3779B9), np.uint64(0xBB67AE85)
_LO, _S32 = np.uint64(0xFFFFFFFF), np.uint64(32)
_ZERO, _ONE = np.uint64(0), np.uint64(1)
_LAYER_BITS = 10
_J_BITS = 32 - _LAYER_BITS - 1
_LAYER, _SIGN_SHIFT, _J_SHIFT = np.uint64(2**_LAYER_BITS - 1), np.uint64(_LAYER_BITS), np.uint64(_LAYER_BITS + 1)
WORDS = 4  # normals per Philox call: channels are drawn in groups of four


def _ziggurat(layers: int = 2**_LAYER_BITS, r: float = 4.038849846109505):
    """Layer edges x_0 > x_1 = r > ... > x_layers = 0 of equal area v under f = exp(-x^2/2)
    (layer 0: the rectangle below f(r), x_0 = v / f(r), plus the tail), r being the edge at which
    that many layers close at the top (found by bisection; tests/test_kernel.py checks it); and
    per layer: w (x = j w for a _J_BITS-bit j), k (j < k is under the curve at every height of the
    layer), f at its outer and inner edge."""
    f = lambda x: math.exp(-0.5 * x * x)
    v = r * f(r) + math.sqrt(math.pi / 2) * math.erfc(r / math.sqrt(2))
    x = [v / f(r), r]
    for _ in range(layers - 2):
        x.append(math.sqrt(-2.0 * math.log(f(x[-1]) + v / x[-1])))
    x = np.array(x + [0.0])
    fx = np.exp(-0.5 * x * x)
    k = np.floor(x[1:] / x[:-1] * 2.0**_J_BITS).astype(np.uint64)
    return x, x[:-1] / 2.0**_J_BITS, k, fx[:-1], fx[1:]


ZIGGURAT_EDGES, _ZW, _ZK, _ZF_OUT, _ZF_IN = _ziggurat()
_ZR = float(ZIGGURAT_EDGES[1])


@nb.njit(inline="always", **_JIT)
def philox(c0, c1, c2, c3, k0, k1):
    """Philox4x32-10 of counter (c0..c3) and key (k0, k1): uint64 values holding 32-bit words."""
    for i in range(10):
        if i > 0:
            k0 = (k0 + _W0) & _LO
            k1 = (k1 + _W1) & _LO
        p0 = _M0 * c0
        p1 = _M1 * c2
        c0, c1, c2, c3 = (p1 >> _S32) ^ c1 ^ k0, p1 & _LO, (p0 >> _S32) ^ c3 ^ k1, p0 & _LO
    return c0, c1, c2, c3


@nb.njit(inline="always", **_JIT)
def _zig_fast(word):
    """A normal from the inner rectangle of the layer a 32-bit word picks: (z, accepted)."""
    idx = word & _LAYER
    j = word >> _J_SHIFT
    z = np.float64(j) * _ZW[idx]
    return (-z if (word >> _SIGN_SHIFT) & _ONE else z), j < _ZK[idx]


@nb.njit(**_JIT)
def _zig_slow(word, n, ch, k0, k1):
    """A word the inner rectangles refused: wedge or tail test, then fresh words from counters
    (n, ch, attempt, 1) until one is accepted."""
    attempt = _ZERO
    while True:
        idx = word & _LAYER
        j = word >> _J_SHIFT
        neg = (word >> _SIGN_SHIFT) & _ONE
        x = np.float64(j) * _ZW[idx]
        if j < _ZK[idx]:
            return -x if neg else x
        attempt += _ONE
        o0, o1, o2, _ = philox(n, ch, attempt, _ONE, k0, k1)
        u1 = (np.float64(o1) + 0.5) * 2.0**-32
        u2 = (np.float64(o2) + 0.5) * 2.0**-32
        if idx == 0:  # the tail beyond r (Marsaglia 1964)
            a = -math.log(u1) / _ZR
            if -2.0 * math.log(u2) > a * a:
                return -(_ZR + a) if neg else _ZR + a
        elif _ZF_OUT[idx] + u1 * (_ZF_IN[idx] - _ZF_OUT[idx]) < math.exp(-0.5 * x * x):
            return -x if neg else x
        word = o0


@nb.njit(**_JIT)
def fill_normals(n, k0, k1, z, words):
    """Standard normals of step n for every channel (row) and lane (column) of z, whose rows are
    a whole number of groups of WORDS. k0, k1: the lanes' keys (uint64); words: scratch (WORDS,
    lanes) uint64. Loops kept apart (bits; inner rectangles; the rare rest) so that each vectorises."""
    c0 = np.uint64(n)
    for g in range(z.shape[0] // WORDS):
        c1 = np.uint64(g)
        for l in range(k0.shape[0]):
            words[0, l], words[1, l], words[2, l], words[3, l] = philox(c0, c1, _ZERO, _ZERO, k0[l], k1[l])
        for w in range(WORDS):
            ch = g * WORDS + w
            refused = 0
            for l in range(k0.shape[0]):
                z[ch, l], accepted = _zig_fast(words[w, l])
                refused += not accepted
            if refused:
                for l in range(k0.shape[0]):
                    if not _zig_fast(words[w, l])[1]:
                        z[ch, l] = _zig_slow(words[w, l], c0, np.uint64(ch), k0[l], k1[l])


@nb.njit(**_JIT)
def run_normals(key0, key1, n_steps, nch):
    """One run's normals, (n_steps + 1, nch): exactly those the engine draws for that key."""
    k0 = np.full(1, np.uint64(key0))
    k1 = np.full(1, np.uint64(key1))
    rows = (nch + WORDS - 1) // WORDS * WORDS
    z = np.empty((rows, 1))
    words = np.empty((WORDS, 1), dtype=np.uint64)
    out = np.empty((n_steps + 1, nch))
    for n in range(n_steps + 1):
        fill_normals(n, k0, k1, z, words)
        out[n] = z[:nch, 0]
    return out


# ---- plant -----------------------------------------------------------------------------------

_TWO_OVER_PI = 2.0 / math.pi
_PIO2_A = math.ldexp(math.floor(math.ldexp(math.pi / 2, 30)), -30)  # 31 bits: k * _PIO2_A exact
_PIO2_B = math.pi / 2 - _PIO2_A  # the rest of the double nearest pi/2 (an exact difference)
_PIO2_C = 6.123233995736766e-17  # pi/2 minus that double
# Taylor coefficients, highest order first: sin r = r + r z (S1 + z S2 + ...), cos r = 1 + z (C1 + ...)
_SIN = tuple((-1) ** k / math.factorial(2 * k + 1) for k in range(8, 0, -1))
_COS = tuple((-1) ** k / math.factorial(2 * k) for k in range(9, 0, -1))


@nb.njit(inline="always", **_JIT)
def sincos(x):
    """(sin x, cos x) by arithmetic alone, so that a loop over lanes vectorises (libm's are
    scalar calls): reduction by pi/2 in three parts, then Taylor series on |r| <= pi/4, where the
    first omitted terms are below 1e-19. Within a few ulp of libm for |x| < 1e5."""
    k = math.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - k * _PIO2_A) - k * _PIO2_B) - k * _PIO2_C
    z = r * r
    ps = 0.0
    for a in _SIN:
        ps = ps * z + a
    pc = 0.0
    for a in _COS:
        pc = pc * z + a
    s = r + r * z * ps
    c = 1.0 + z * pc
    q = np.int64(k)  # the quadrant, by selects (a return per quadrant stops vectorisation)
    swap = (q & 1) != 0
    sn = c if swap else s
    cs = s if swap else c
    return (-sn if q & 2 else sn), (-cs if (q + 1) & 2 else cs)


N_COEF = 10


@nb.njit(inline="always", **_JIT)
def plant_coefficients(p, out):
    """The per-run constants of eq. 2.16-2.19 from p = (M, m, l, g, b_VF, c, ...), into out."""
    M, m, l, g, b, c = p[0], p[1], p[2], p[3], p[4], p[5]
    out[0], out[1], out[2], out[3], out[4] = M + m, m, m * l, c / l, m * g
    out[5], out[6], out[7], out[8], out[9] = b, -c / (m * l * l), g / l, 1.0 / (m * l), 1.0 / l


@nb.njit(inline="always", **_JIT)
def plant_accel(q, i, sn, cs, sd, thd, force, tip):
    """(s_ddot, theta_ddot) of eq. 2.16-2.19 with coefficients q[:, i], plus a horizontal force at
    the pendulum tip (distance l): generalised forces tip on s and tip * l * cos(theta) on theta."""
    den = q[0, i] - q[1, i] * cs * cs
    bracket = -q[5, i] * sd + q[2, i] * thd * thd * sn + q[3, i] * thd * cs - q[4, i] * sn * cs + force
    sdd = (bracket + tip * sn * sn) / den
    return sdd, q[6, i] * thd + q[7, i] * sn + tip * cs * q[8, i] - cs * sdd * q[9, i]


@nb.njit(**_JIT)
def plant_rhs(p, th, sd, thd, force, tip_force):
    """(ds, dtheta, ds_dot, dtheta_dot) as the kernel computes them (p = M, m, l, g, b_VF, c)."""
    q = np.empty((N_COEF, 1))
    plant_coefficients(p, q[:, 0])
    sn, cs = sincos(th)
    sdd, thdd = plant_accel(q, 0, sn, cs, sd, thd, force, tip_force)
    return sd, thd, sdd, thdd


# ---- circuit ---------------------------------------------------------------------------------


@nb.njit(inline="always", **_JIT)
def _sum_but_last(j, in_ptr, in_src, in_gain, sig, acc):
    """acc[0, lane] = 0 + amplifier j's inputs times their gains but the last. Returns the row
    of acc holding that sum (row 1 is zeros: at most one input) and the last input's signal and
    gain, for the caller to add in its own loop over lanes (a pass fewer). Without inputs: the
    zero row at the end of sig, gain 0."""
    lo, hi = in_ptr[j], in_ptr[j + 1] - 1
    if hi < lo:
        return 1, sig.shape[0] - 1, 0.0
    for k in range(lo, hi):
        g, src = in_gain[k], in_src[k]
        if k == lo:
            for l in range(acc.shape[1]):
                acc[0, l] = 0.0 + g * sig[src, l]
        else:
            for l in range(acc.shape[1]):
                acc[0, l] += g * sig[src, l]
    return (0 if hi > lo else 1), in_src[hi], in_gain[hi]


@nb.njit(**_JIT)
def _circuit(X, Z, s_ref, nz, sensor_state, sensor_gain, amp_kind, in_ptr, in_src, in_gain,
             param1, param2, drift, sat, clip, sig, raw, dz, st, acc):
    """Sensors and amplifiers in evaluation order: sig (clipped if clip; its last row stays 0),
    raw (before clipping), and the amplifier state derivatives into dz[st] (a summer's stay 0);
    every array (quantity, lane). Indexing, not views: a view per row and step would cost more
    than the row's arithmetic."""
    ns = sensor_state.shape[0]
    nl = acc.shape[1]
    hi = sat if clip else np.inf
    for i in range(ns):
        q, g = sensor_state[i], sensor_gain[i]
        ref = s_ref if q == S_INDEX else 0.0
        for l in range(nl):
            sig[i, l] = g * (X[q, l] - ref) + nz[i, l]
    # outputs in evaluation order (integrators and lags, whose outputs are their states, first)
    for j in range(amp_kind.shape[0]):
        kd, a = amp_kind[j], ns + j
        if kd == INTEGRATOR or kd == LAG:
            for l in range(nl):
                v = Z[j, l] + nz[a, l]
                raw[j, l] = v
                sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
            continue
        b, src, g = _sum_but_last(j, in_ptr, in_src, in_gain, sig, acc)
        if kd == SUMMER:
            for l in range(nl):
                v = -(acc[b, l] + g * sig[src, l]) + nz[a, l]
                raw[j, l] = v
                sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
        else:  # DIFFERENTIATOR with roll-off
            p1, p2 = param1[j], param2[j]
            for l in range(nl):
                e = acc[b, l] + g * sig[src, l] - Z[j, l]
                v = -p1 * e + nz[a, l]
                raw[j, l] = v
                sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
                dz[st, j, l] = p2 * e
    # last, the integrating amplifiers' inputs, now that every signal of this instant is known
    for j in range(amp_kind.shape[0]):
        kd = amp_kind[j]
        if kd == INTEGRATOR or kd == LAG:
            b, src, g = _sum_but_last(j, in_ptr, in_src, in_gain, sig, acc)
            p1 = param1[j]
            if kd == INTEGRATOR:
                for l in range(nl):
                    dz[st, j, l] = -p1 * (acc[b, l] + g * sig[src, l]) + drift[j, l]
            else:
                for l in range(nl):
                    dz[st, j, l] = p1 * (-(acc[b, l] + g * sig[src, l]) - Z[j, l]) + drift[j, l]


@nb.njit(**_JIT)
def _drive(X, XA, sig, out_index, tripped, pc, fpar, act, f_cart, f_tip, kp, kx, forces, st):
    """Actuator (dead zone, model, force limit; off once tripped) and plant slopes per lane,
    into kp[st], kx[st], forces[st]."""
    dz, flim, K_U = fpar[F_DEAD], fpar[F_FLIM], fpar[F_K_U]
    inv_tau = 1.0 / fpar[F_TAU]
    ku_tau = K_U / fpar[F_TAU]
    for l in range(XA.shape[0]):
        u = sig[out_index, l]
        v = u - dz if u > dz else (u + dz if u < -dz else 0.0)
        xa = XA[l]
        if act == ACT_GAIN:
            force, dx = K_U * v, 0.0
        elif act == ACT_LAG:
            force, dx = xa, (K_U * v - xa) * inv_tau
        else:
            force, dx = ku_tau * (v - xa), (v - xa) * inv_tau
        force = flim if force > flim else (-flim if force < -flim else force)
        if tripped[l]:
            force = 0.0
        sd, thd = X[2, l], X[3, l]
        sn, cs = sincos(X[1, l])
        sdd, thdd = plant_accel(pc, l, sn, cs, sd, thd, force + f_cart, f_tip)
        kp[st, 0, l], kp[st, 1, l], kp[st, 2, l], kp[st, 3, l] = sd, thd, sdd, thdd
        kx[st, l] = dx
        forces[st, l] = force


# ---- runs ------------------------------------------------------------------------------------


@nb.njit(**_JIT)
def run_block(lo, nl, keys, signs, plants, fpar, ipar, x0, sensor_state, sensor_gain, noise_a, noise_std,
              amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag,
              dist_kind, dist_t0, dist_t1, dist_value, res, ovl_first, ovl_time, hist, hist_len):
    """Runs lo .. lo + nl - 1 side by side, into res, ovl_first, ovl_time (rows = runs; event
    times NaN beforehand) and, for runs below hist.shape[0], hist and hist_len."""
    h, sat = fpar[F_DT], fpar[F_SAT]
    n_steps, stride, limit_on, clip = ipar[I_STEPS], ipar[I_STRIDE], ipar[I_LIMIT] != 0, ipar[I_CLIP] != 0
    out_index, act = ipar[I_OUT], ipar[I_ACT]
    ns, na = sensor_state.shape[0], amp_kind.shape[0]
    nch = ns + na
    pc = np.empty((N_COEF, nl))
    half = np.empty(nl)
    k0 = np.empty(nl, dtype=np.uint64)
    k1 = np.empty(nl, dtype=np.uint64)
    drift = np.empty((na, nl))  # each integrating amplifier drifts one way, drawn per run
    xp = np.empty((4, nl))
    za = np.empty((na, nl))
    for l in range(nl):
        plant_coefficients(plants[lo + l], pc[:, l])
        half[l] = plants[lo + l, 6]
        k0[l], k1[l] = keys[lo + l, 0], keys[lo + l, 1]
        for j in range(na):
            drift[j, l] = drift_mag[j] * signs[lo + l, j]
            za[j, l] = ic[j]
        for i in range(4):
            xp[i, l] = x0[i]
    nz = np.zeros((nch, nl))
    rows = (nch + WORDS - 1) // WORDS * WORDS
    z = np.empty((rows, nl))
    words = np.empty((WORDS, nl), dtype=np.uint64)
    noisy = np.any(noise_std > 0.0)
    if noisy:  # start the noise in its stationary distribution
        fill_normals(0, k0, k1, z, words)
        for c in range(nch):
            for l in range(nl):
                nz[c, l] = z[c, l] * noise_std[c] / math.sqrt(1.0 - noise_a[c] * noise_a[c])
    sig = np.zeros((nch + 1, nl))  # signals, and a row of zeros (the input of an unwired amplifier)
    raw = np.zeros((na, nl))
    kp = np.zeros((4, 4, nl))  # RK4 slopes of the plant, amplifier and actuator states
    ka = np.zeros((4, na, nl))
    kx = np.zeros((4, nl))
    acc = np.zeros((2, nl))  # a partial sum of inputs, and zeros
    xt = np.empty((4, nl))
    zt = np.empty((na, nl))
    xa = np.zeros(nl)
    xat = np.empty(nl)
    # a differentiator starts settled on its input (the angle was held before the run): set its
    # filter state to its input, in evaluation order (one pass per amplifier reaches every chain)
    quiet = np.zeros((nch, nl))
    for _ in range(na):
        _circuit(xp, za, 0.0, quiet, sensor_state, sensor_gain, amp_kind, in_ptr, in_src, in_gain,
                 param1, param2, drift, sat, False, sig, raw, ka, 0, acc)
        for j in range(na):
            if amp_kind[j] == DIFFERENTIATOR:
                for l in range(nl):
                    za[j, l] -= raw[j, l] / param1[j]
    forces = np.zeros((4, nl))
    tripped = np.zeros(nl, dtype=np.bool_)
    fallen = np.zeros(nl, dtype=np.bool_)
    alive = np.ones(nl, dtype=np.bool_)
    pinned = np.zeros((na, nl), dtype=np.bool_)  # clipped at a rail by the last update
    sum_th2, mth, ms, muc, mf = np.zeros(nl), np.zeros(nl), np.zeros(nl), np.zeros(nl), np.zeros(nl)
    n_alive = nl
    n_hist = max(0, min(nl, hist.shape[0] - lo))
    for n in range(n_steps + 1):
        t = n * h
        if noisy and n > 0:  # new noise for this step
            fill_normals(n, k0, k1, z, words)
            for c in range(nch):
                a, s = noise_a[c], noise_std[c]
                for l in range(nl):
                    nz[c, l] = a * nz[c, l] + s * z[c, l]
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
        for st in range(4):
            _stage_state(st, h, xp, za, xa, kp, ka, kx, xt, zt, xat)
            _circuit(xt, zt, s_ref, nz, sensor_state, sensor_gain, amp_kind, in_ptr, in_src, in_gain,
                     param1, param2, drift, sat, clip, sig, raw, ka, st, acc)
            _drive(xt, xat, sig, out_index, tripped, pc, fpar, act, f_cart, f_tip, kp, kx, forces, st)
            if st == 0:  # record and summarise time t; a run ends at the scenario's end or at a trip
                for l in range(n_hist):
                    if alive[l] and (n % stride == 0 or n == n_steps or tripped[l]):
                        _record(hist, hist_len, lo + l, l, t, xp, s_ref, sig, out_index, forces, ns)
                n_alive -= _summaries(n, t, n == n_steps, lo, alive, tripped, fallen, xp, raw, pinned,
                                      sig, out_index, forces, fpar, sum_th2, mth, ms, muc, mf, res,
                                      ovl_first, ovl_time)
        if n_alive == 0:
            break
        for i in range(4):
            for l in range(nl):
                xp[i, l] += h / 6.0 * (kp[0, i, l] + 2.0 * kp[1, i, l] + 2.0 * kp[2, i, l] + kp[3, i, l])
        for j in range(na):
            rail = clip and amp_kind[j] != DIFFERENTIATOR  # a capacitor cannot charge past the rails
            for l in range(nl):
                v = za[j, l] + h / 6.0 * (ka[0, j, l] + 2.0 * ka[1, j, l] + 2.0 * ka[2, j, l] + ka[3, j, l])
                pinned[j, l] = rail and (v > sat or v < -sat)
                za[j, l] = (sat if v > sat else (-sat if v < -sat else v)) if rail else v
        for l in range(nl):
            xa[l] += h / 6.0 * (kx[0, l] + 2.0 * kx[1, l] + 2.0 * kx[2, l] + kx[3, l])
        trips = 0
        for l in range(nl):
            trips += alive[l] and not tripped[l] and abs(xp[0, l]) >= half[l]
        if limit_on and trips:
            for l in range(nl):
                if alive[l] and not tripped[l] and abs(xp[0, l]) >= half[l]:
                    tripped[l] = True
                    res[lo + l, R_TRIP] = t + h


@nb.njit(**_JIT)
def _stage_state(st, h, xp, za, xa, kp, ka, kx, xt, zt, xat):
    """The states at RK4 stage st: the step's start, then start + c * the last stage's slopes."""
    nl = xa.shape[0]
    if st == 0:
        xt[:] = xp
        zt[:] = za
        xat[:] = xa
        return
    c = h if st == 3 else 0.5 * h
    for i in range(4):
        for l in range(nl):
            xt[i, l] = xp[i, l] + c * kp[st - 1, i, l]
    for j in range(za.shape[0]):
        for l in range(nl):
            zt[j, l] = za[j, l] + c * ka[st - 1, j, l]
    for l in range(nl):
        xat[l] = xa[l] + c * kx[st - 1, l]


@nb.njit(**_JIT)
def _summaries(n, t, end, lo, alive, tripped, fallen, xp, raw, pinned, sig, out_index, forces, fpar,
               sum_th2, mth, ms, muc, mf, res, ovl_first, ovl_time):
    """Figures at time t of the lanes still running; the results of those whose run ends here.
    Returns how many ended. The running figures are updated in every lane (an ended lane's are
    no longer read), so that loop vectorises; events (a fall, an overload, the end) are rare and
    are looked at lane by lane only when there is one."""
    sat, h, fall = fpar[F_SAT], fpar[F_DT], fpar[F_FALL]
    nl = alive.shape[0]
    events = 0
    for l in range(nl):
        th, s, u, f = abs(xp[1, l]), abs(xp[0, l]), abs(sig[out_index, l]), abs(forces[0, l])
        sum_th2[l] += xp[1, l] * xp[1, l]
        mth[l] = th if th > mth[l] else mth[l]
        ms[l] = s if s > ms[l] else ms[l]
        muc[l] = u if u > muc[l] else muc[l]
        mf[l] = f if f > mf[l] else mf[l]
        events += alive[l] and (tripped[l] or (th > fall and not fallen[l]))
    for j in range(raw.shape[0]):
        for l in range(nl):
            events += alive[l] and (abs(raw[j, l]) > sat or pinned[j, l])
    if events == 0 and not end:
        return 0
    ended = 0
    for l in range(nl):
        if not alive[l]:
            continue
        r = lo + l
        last = end or tripped[l]
        if not fallen[l] and abs(xp[1, l]) > fall:
            fallen[l] = True
            res[r, R_FALL] = t
        for j in range(raw.shape[0]):
            if abs(raw[j, l]) > sat or pinned[j, l]:
                if math.isnan(ovl_first[r, j]):
                    ovl_first[r, j] = t
                if not last:
                    ovl_time[r, j] += h
        if last:
            res[r, R_MAX_TH], res[r, R_MAX_S], res[r, R_RMS_TH] = mth[l], ms[l], math.sqrt(sum_th2[l] / (n + 1))
            res[r, R_MAX_UC], res[r, R_MAX_F] = muc[l], mf[l]
            for i in range(4):
                res[r, R_FINAL + i] = xp[i, l]
            alive[l] = False
            ended += 1
    return ended


@nb.njit(**_JIT)
def _record(hist, hist_len, r, l, t, xp, s_ref, sig, out_index, forces, ns):
    """One history sample of run r (lane l): t, plant state, s_ref, u_c, force, amplifier outputs."""
    k = hist_len[r]
    hist[r, k, 0] = t
    for i in range(4):
        hist[r, k, 1 + i] = xp[i, l]
    hist[r, k, 5], hist[r, k, 6], hist[r, k, 7] = s_ref, sig[out_index, l], forces[0, l]
    for j in range(hist.shape[2] - 8):
        hist[r, k, 8 + j] = sig[ns + j, l]
    hist_len[r] = k + 1


@nb.njit(parallel=True, nogil=True, **_JIT)
def run_blocks(keys, signs, plants, fpar, ipar, x0, sensor_state, sensor_gain, noise_a, noise_std,
               amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag,
               dist_kind, dist_t0, dist_t1, dist_value, res, ovl_first, ovl_time, hist, hist_len):
    """Every run of the batch, LANES at a time, the blocks spread over numba's threads."""
    runs = keys.shape[0]
    for b in nb.prange((runs + LANES - 1) // LANES):
        lo = b * LANES
        run_block(lo, min(LANES, runs - lo), keys, signs, plants, fpar, ipar, x0, sensor_state,
                  sensor_gain, noise_a, noise_std, amp_kind, in_ptr, in_src, in_gain, param1, param2,
                  ic, drift_mag, dist_kind, dist_t0, dist_t1, dist_value, res, ovl_first, ovl_time,
                  hist, hist_len)
