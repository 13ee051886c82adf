"""The plant and the patched circuit evaluated for every lane of a block (patchgen.bench.kernel): arrays
(quantity, lane), loops over lanes innermost so that LLVM vectorises them across runs.

Indexing, not views: numba reference-counts a view, and a view per row and stage would cost more
than the row's arithmetic. Branches that differ between lanes are selects; the plant's equations,
sine and cosine by arithmetic included, are patchgen.plant.compiled's.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from patchgen.bench.circuit import INTEGRATOR, LAG, SUMMER
from patchgen.plant.compiled import plant_accel, sincos
from patchgen.plant.equations import PLANT_STATES
from patchgen.plant.rotary_compiled import rotary_accel

ACT_GAIN, ACT_LAG, ACT_LAG_ZERO, ACT_MOTOR = 0, 1, 2, 3
PLANT_CART, PLANT_ROTARY = 0, 1  # the plant a batch runs: its equations and what its pushes are
# a run's actuator: N/V, s, V, N, N s/m (a motor's back-EMF damping; 0 for the others)
ACTUATOR_VECTOR = ("K_U", "tau", "dead_zone", "force_limit", "back_emf")
A_K_U, A_TAU, A_DEAD_ZONE, A_FORCE_LIMIT, A_BACK_EMF = range(len(ACTUATOR_VECTOR))
N_ACTUATOR = len(ACTUATOR_VECTOR)
A_INV_TAU, A_KU_TAU = N_ACTUATOR, N_ACTUATOR + 1  # rows actuator_rates adds: 1 / tau, K_U / tau
N_ACTUATOR_ROWS = N_ACTUATOR + 2
S_INDEX = PLANT_STATES.index("s")  # the sensor whose reference a step command moves
FILTER_ROWS = 2  # a sensor filter's states (y, y'): at most one filter, the velocity's
TERMS = 4  # an amplifier's inputs summed per pass over the lanes (input_groups)
# A block's integrated states are the rows of one array (plant, amplifiers, actuator, filter), so
# that a step's RK4 sums run as one loop; their slopes at each stage are rows of one array too,
# in the same order, with the actuator's force and whether it is at its limit after them.
P_ROWS = len(PLANT_STATES)
_JIT = {"cache": True, "error_model": "numpy"}  # as patchgen.bench.kernel's


def input_groups(in_ptr: np.ndarray, in_src: np.ndarray, in_gain: np.ndarray,
                 zero_row: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each amplifier's inputs as the circuit loop sums them: groups of TERMS (source signal,
    gain), padded with the zero signal at gain 0, at least one group per amplifier.

    Returns (group_ptr, group_src, group_gain): amplifier j's groups are rows group_ptr[j] to
    group_ptr[j + 1] - 1 of group_src and group_gain, (groups, TERMS). A sum of the padded
    terms is the sum of the inputs to the bit: it starts at +0.0, so it is never -0.0, and adding
    0.0 * 0.0 = +0.0 to anything but -0.0 leaves it as it is.
    """
    ptr, src, gain = [0], [], []
    for j in range(len(in_ptr) - 1):
        s, g = list(in_src[in_ptr[j]:in_ptr[j + 1]]), list(in_gain[in_ptr[j]:in_ptr[j + 1]])
        n = max(1, -(-len(s) // TERMS))
        s += [zero_row] * (n * TERMS - len(s))
        g += [0.0] * (n * TERMS - len(g))
        src += [s[k:k + TERMS] for k in range(0, len(s), TERMS)]
        gain += [g[k:k + TERMS] for k in range(0, len(g), TERMS)]
        ptr.append(ptr[-1] + n)
    return (np.array(ptr, dtype=np.int64), np.array(src, dtype=np.int64).reshape(-1, TERMS),
            np.array(gain, dtype=np.float64).reshape(-1, TERMS))


@nb.njit(inline="always", **_JIT)
def _group(wiring, k):
    """Group k's sources and gains (input_groups), read once before a loop over lanes."""
    src, gain = wiring.group_src, wiring.group_gain
    return src[k, 0], src[k, 1], src[k, 2], src[k, 3], gain[k, 0], gain[k, 1], gain[k, 2], gain[k, 3]


@nb.njit(inline="always", **_JIT)
def _add(start, sig, l, s0, s1, s2, s3, g0, g1, g2, g3):
    """start + a group's four terms, in order, at lane l."""
    return (((start + g0 * sig[s0, l]) + g1 * sig[s1, l]) + g2 * sig[s2, l]) + g3 * sig[s3, l]


@nb.njit(inline="always", **_JIT)
def _partial(j, wiring, sig, acc):
    """The sum of amplifier j's input groups but the last into acc[0]; returns the row of acc the
    last group adds to (1, the zero row, when there is one group) and that group's index. A
    loop's sources and gains are locals, read before it: loaded from arrays inside it, they
    would be read again for every lane, as a store to sig might have changed them."""
    lo, hi = wiring.group_ptr[j], wiring.group_ptr[j + 1] - 1
    for k in range(lo, hi):
        s0, s1, s2, s3, g0, g1, g2, g3 = _group(wiring, k)
        b = 1 if k == lo else 0
        for l in range(acc.shape[1]):
            acc[0, l] = _add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3)
    return (0 if hi > lo else 1), hi


@nb.njit(**_JIT)
def state_rows(na):
    """(first amplifier, actuator, first filter, force, at-limit) rows of the slopes for na
    amplifiers (see P_ROWS); the rows before the force's are the integrated states."""
    act = P_ROWS + na
    force = act + 1 + FILTER_ROWS
    return P_ROWS, act, act + 1, force, force + 1


@nb.njit(inline="always", **_JIT)
def quantised(x, quantum):
    """x as an encoder reports it: the nearest whole count of ``quantum`` (0: x itself)."""
    return x if quantum == 0.0 else quantum * math.floor(x / quantum + 0.5)


@nb.njit(**_JIT)
def sensor_filters(X, XF, sensors, K, rf, st):
    """The sensors' filter states at RK4 stage st: filter k holds (y, y') in rows 2k, 2k + 1 of
    a quantised position (of X, the stage's plant states) through
    wn^2 / (s^2 + 2 zeta wn s + wn^2), and y' is the sensor's reading (a velocity from a filter,
    as a lab without a tachometer has it): their slopes at stage st into K[st], from row rf. The velocity is
    the one rate a lab's sensors read (patchgen.plant.cart_pendulum.MEASURED), so there is at most
    one filter: FILTER_ROWS rows, a fixed count, as the step's loops run fastest over."""
    for i in range(sensors.state.shape[0]):
        k = sensors.filt[i]
        if k < 0:
            continue
        q, d, wn, ze = sensors.source[i], sensors.quantum[i], sensors.wn[i], sensors.zeta[i]
        for l in range(X.shape[1]):
            u = quantised(X[q, l], d)
            y = 2 * k
            K[st, rf + y, l] = XF[y + 1, l]
            K[st, rf + y + 1, l] = wn * wn * (u - XF[y, l]) - 2.0 * ze * wn * XF[y + 1, l]


@nb.njit(**_JIT)
def circuit(X, Z, XF, s_ref, nz, sensors, sensor_gain, wiring, drift, sat, clip, sig, raw, K, ra, st, acc):
    """Sensors and amplifiers in evaluation order: sig (clipped if clip; its last row stays 0),
    raw (before clipping; at stage 0 only, the one the summaries read), and the amplifier state
    derivatives into K[st], from row ra (a summer's stay 0).
    sensors: patchgen.bench.kernel's Sensors (a sensor reads its plant state, quantised, or its
    filter's output in XF); wiring: patchgen.bench.kernel's Wiring; X, Z, XF, nz, drift and
    sensor_gain (sensor, lane) are per lane."""
    amp_kind = wiring.kind
    param1, param2 = wiring.param1, wiring.param2
    ns = sensors.state.shape[0]
    nl = acc.shape[1]
    hi = sat if clip else np.inf
    for i in range(ns):
        q, k, d = sensors.state[i], sensors.filt[i], sensors.quantum[i]
        if k >= 0:
            for l in range(nl):
                sig[i, l] = sensor_gain[i, l] * XF[2 * k + 1, l] + nz[i, l]
            continue
        ref = s_ref if q == S_INDEX else 0.0
        if d == 0.0:  # a continuous reading (a pot, a tachometer): no count to take
            for l in range(nl):
                sig[i, l] = sensor_gain[i, l] * (X[q, l] - ref) + nz[i, l]
        else:
            for l in range(nl):
                sig[i, l] = sensor_gain[i, l] * (d * math.floor(X[q, l] / d + 0.5) - ref) + nz[i, l]
    # outputs in evaluation order (integrators and lags, whose outputs are their states, first);
    # each amplifier a loop over lanes or two, its inputs summed inside (at most a pass more per
    # TERMS inputs), each loop storing into few arrays so that LLVM vectorises it
    for j in range(amp_kind.shape[0]):
        kd, a = amp_kind[j], ns + j
        if kd == INTEGRATOR or kd == LAG:
            if st == 0:
                for l in range(nl):
                    v = Z[j, l] + nz[a, l]
                    raw[j, l] = v
                    sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
            else:
                for l in range(nl):
                    v = Z[j, l] + nz[a, l]
                    sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
            continue
        b, k = _partial(j, wiring, sig, acc)
        s0, s1, s2, s3, g0, g1, g2, g3 = _group(wiring, k)
        if kd == SUMMER and st == 0:
            for l in range(nl):
                v = -_add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3) + nz[a, l]
                raw[j, l] = v
                sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
        elif kd == SUMMER:
            for l in range(nl):
                v = -_add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3) + nz[a, l]
                sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
        else:  # DIFFERENTIATOR with roll-off: its state's slope, then its output
            p1, p2 = param1[j], param2[j]
            for l in range(nl):
                K[st, ra + j, l] = p2 * (_add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3) - Z[j, l])
            if st == 0:
                for l in range(nl):
                    v = -p1 * (_add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3) - Z[j, l]) + nz[a, l]
                    raw[j, l] = v
                    sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
            else:
                for l in range(nl):
                    v = -p1 * (_add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3) - Z[j, l]) + nz[a, l]
                    sig[a, l] = hi if v > hi else (-hi if v < -hi else v)
    # last, the integrating amplifiers' inputs, now that every signal of this instant is known
    for j in range(amp_kind.shape[0]):
        kd = amp_kind[j]
        if kd == INTEGRATOR or kd == LAG:
            b, k = _partial(j, wiring, sig, acc)
            s0, s1, s2, s3, g0, g1, g2, g3 = _group(wiring, k)
            p1 = param1[j]
            if kd == INTEGRATOR:
                for l in range(nl):
                    K[st, ra + j, l] = -p1 * _add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3) + drift[j, l]
            else:
                for l in range(nl):
                    x = _add(acc[b, l], sig, l, s0, s1, s2, s3, g0, g1, g2, g3)
                    K[st, ra + j, l] = p1 * (-x - Z[j, l]) + drift[j, l]


@nb.njit(**_JIT)
def actuator_rates(ap):
    """Fill rows A_INV_TAU and A_KU_TAU of ap (N_ACTUATOR_ROWS, lane) from its K_U and tau: the
    same quotients drive used to take at every stage, taken once per block."""
    for l in range(ap.shape[1]):
        ap[A_INV_TAU, l] = 1.0 / ap[A_TAU, l]
        ap[A_KU_TAU, l] = ap[A_K_U, l] / ap[A_TAU, l]


@nb.njit(inline="always", **_JIT)
def _dead(u, dz):
    """A command u through a dead zone of half-width dz."""
    return u - dz if u > dz else (u + dz if u < -dz else 0.0)


@nb.njit(inline="always", **_JIT)
def _limit(force, flim):
    """(force clipped to +/- flim, whether it reached the limit)."""
    return (flim if force > flim else (-flim if force < -flim else force)), (force >= flim) | (force <= -flim)


@nb.njit(inline="always", **_JIT)
def _store(K, st, l, rx, rate, force, limited, tripped):
    """Lane l's actuator at stage st into K[st]'s rows rx (its slope, force, at-limit): a tripped
    run's motor is cut."""
    K[st, rx[0], l] = rate
    K[st, rx[1], l] = 0.0 if tripped else force
    K[st, rx[2], l] = 1.0 if limited else 0.0


@nb.njit(**_JIT)
def drive(X, XA, sig, out_index, tripped, pc, act, ap, f_cart, f_tip, nz, K, rx, st, kind):
    """Actuator (dead zone, model, force limit; off once tripped) and plant slopes per lane,
    into K[st]: the plant's rows, and rows rx: the actuator state's slope, the force, and 1.0
    where the command sits at the actuator's limit, else 0.0. act: the actuator's model ACT_*;
    ap (N_ACTUATOR_ROWS, lane): each lane's
    K_U, tau, dead zone, force limit, back-EMF, then 1 / tau and K_U / tau (actuator_rates); a
    motor's command K_U v is limited at the amplifier (force limit = a V_limit), then the back-EMF
    takes b s_dot from it, through the electrical lag tau when it has one;
    X (plant state), XA (actuator state) and pc (the plant's coefficients) are per lane. f_cart and
    f_tip are the scenario's pushes (N); the last two rows of nz, the bench's random forces on
    the cart and at the tip (N), per lane. ``kind``: the plant, PLANT_CART (f_cart a force on the
    cart, the actuator's output a force) or PLANT_ROTARY (f_cart a torque on the arm, N m, the
    actuator's output the motor's voltage)."""
    fc, ft = nz.shape[0] - 2, nz.shape[0] - 1
    # Two lane loops, not one: the actuator's branches and the plant's trigonometry in one
    # body keep LLVM from vectorising either; split, both run on whole SIMD registers. Each
    # stores into one array (K): a store more, and LLVM can no longer prove the arrays
    # apart and runs the loop a lane at a time.
    if act == ACT_MOTOR:  # a loop per model: the model's branch outside, nothing left in the loop
        for l in range(XA.shape[0]):
            cmd = ap[A_K_U, l] * _dead(sig[out_index, l], ap[A_DEAD_ZONE, l])
            cmd, limited = _limit(cmd, ap[A_FORCE_LIMIT, l])
            net = cmd - ap[A_BACK_EMF, l] * X[2, l]
            xa = XA[l]
            lagged = ap[A_TAU, l] > 0.0
            force = xa if lagged else net
            _store(K, st, l, rx, (net - xa) * ap[A_INV_TAU, l] if lagged else 0.0, force, limited, tripped[l])
    elif act == ACT_GAIN:
        for l in range(XA.shape[0]):
            force, limited = _limit(ap[A_K_U, l] * _dead(sig[out_index, l], ap[A_DEAD_ZONE, l]), ap[A_FORCE_LIMIT, l])
            _store(K, st, l, rx, 0.0, force, limited, tripped[l])
    elif act == ACT_LAG:
        for l in range(XA.shape[0]):
            v, xa = _dead(sig[out_index, l], ap[A_DEAD_ZONE, l]), XA[l]
            force, limited = _limit(xa, ap[A_FORCE_LIMIT, l])
            _store(K, st, l, rx, (ap[A_K_U, l] * v - xa) * ap[A_INV_TAU, l], force, limited, tripped[l])
    else:
        for l in range(XA.shape[0]):
            v, xa = _dead(sig[out_index, l], ap[A_DEAD_ZONE, l]), XA[l]
            force, limited = _limit(ap[A_KU_TAU, l] * (v - xa), ap[A_FORCE_LIMIT, l])
            _store(K, st, l, rx, (v - xa) * ap[A_INV_TAU, l], force, limited, tripped[l])
    if kind == PLANT_ROTARY:
        for l in range(XA.shape[0]):
            ad, thd = X[2, l], X[3, l]
            sn, cs = sincos(X[1, l])
            add, thdd = rotary_accel(pc, l, sn, cs, ad, thd, K[st, rx[1], l], f_cart + nz[fc, l], f_tip + nz[ft, l])
            K[st, 0, l] = ad
            K[st, 1, l] = thd
            K[st, 2, l] = add
            K[st, 3, l] = thdd
        return
    for l in range(XA.shape[0]):
        sd, thd = X[2, l], X[3, l]
        sn, cs = sincos(X[1, l])
        sdd, thdd = plant_accel(pc, l, sn, cs, sd, thd, K[st, rx[1], l] + (f_cart + nz[fc, l]),
                                f_tip + nz[ft, l])
        K[st, 0, l] = sd
        K[st, 1, l] = thd
        K[st, 2, l] = sdd
        K[st, 3, l] = thdd
