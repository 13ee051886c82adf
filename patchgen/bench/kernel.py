"""The compiled Monte-Carlo loop, runs side by side: blocks of up to LANES runs, every state an
array (quantity, lane), every inner loop over lanes (patchgen.bench.lanes, patchgen.bench.noise), so that LLVM
vectorises each operation across runs.

One step of one block: draw the lanes' noise, four RK4 stages of plant + actuator + circuit,
clip integrating amplifiers at the rails, check limit switches, fall and overloads. A lane whose
run has ended (the limit switches cut the motor) keeps being computed with the others but is no
longer recorded; the block stops when every lane has ended or at the scenario's end.

The arithmetic is plain IEEE, without fast-math, not even fused multiply-add (it is 7 % faster,
but LLVM fuses differently in a loop's vectorised body and its scalar remainder), so each lane's
result is bit for bit the same whatever the number of lanes in its block, its place in the
block, the number of threads or the order of the blocks: a run depends only on its own inputs
(tests/test_kernel.py checks it).

numba's disk cache is stamped with the content of the file of the function it compiled, and does
not see a change in a callee elsewhere: COMPILED_IN holds a digest of patchgen/bench/lanes.py and
patchgen/bench/noise.py, whose code is compiled into this file's, so that changing them changes this
file (tests/test_kernel.py says when it is out of date).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from patchgen.bench.circuit import DIFFERENTIATOR
from patchgen.bench.lanes import N_COEF, circuit, drive, plant_coefficients
from patchgen.bench.noise import WORDS, fill_normals

COMPILED_IN = "48847ad0e13ee270"  # sha256 of lanes.py then noise.py, first 16 hex digits
LANES = 64  # runs per block
DIST_CART_FORCE, DIST_TIP_FORCE, DIST_STEP = 0, 1, 2
# scalar settings, packed: floats and integers
F_DT, F_SAT, F_K_U, F_TAU, F_DEAD, F_FLIM, F_FALL = range(7)
I_STEPS, I_STRIDE, I_LIMIT, I_CLIP, I_OUT, I_ACT = range(6)
# per-run results: event times (NaN: never), maxima, RMS theta, final plant state
R_TRIP, R_FALL, R_MAX_TH, R_MAX_S, R_RMS_TH, R_MAX_UC, R_MAX_F, R_FINAL = range(8)
N_RESULTS = R_FINAL + 4
# cached on disk; IEEE arithmetic (see above); no Python exceptions for x / 0
_JIT = {"cache": True, "error_model": "numpy"}


@nb.njit(**_JIT)
def run_block(lo, nl, keys, signs, plants, fpar, ipar, x0, sensor_state, sensor_gain, noise_a, noise_std,
              amp_kind, in_ptr, in_src, in_gain, param1, param2, ic, drift_mag,
              dist_kind, dist_t0, dist_t1, dist_value, res, ovl_first, ovl_time, hist, hist_len):
    """Runs lo .. lo + nl - 1 side by side, into res, ovl_first, ovl_time (rows = runs; event
    times NaN beforehand) and, for runs below hist.shape[0], hist and hist_len."""
    h, sat = fpar[F_DT], fpar[F_SAT]
    n_steps, stride, limit_on, clip = ipar[I_STEPS], ipar[I_STRIDE], ipar[I_LIMIT] != 0, ipar[I_CLIP] != 0
    out_index = ipar[I_OUT]
    actuator = (ipar[I_ACT], fpar[F_K_U], fpar[F_TAU], fpar[F_DEAD], fpar[F_FLIM])
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
        circuit(xp, za, 0.0, quiet, sensor_state, sensor_gain, amp_kind, in_ptr, in_src, in_gain,
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
            circuit(xt, zt, s_ref, nz, sensor_state, sensor_gain, amp_kind, in_ptr, in_src, in_gain,
                    param1, param2, drift, sat, clip, sig, raw, ka, st, acc)
            drive(xt, xat, sig, out_index, tripped, pc, actuator, f_cart, f_tip, kp, kx, forces, st)
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
