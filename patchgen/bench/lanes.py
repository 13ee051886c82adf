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

ACT_GAIN, ACT_LAG, ACT_LAG_ZERO, ACT_MOTOR = 0, 1, 2, 3
# a run's actuator: N/V, s, V, N, N s/m (a motor's back-EMF damping; 0 for the others)
ACTUATOR_VECTOR = ("K_U", "tau", "dead_zone", "force_limit", "back_emf")
A_K_U, A_TAU, A_DEAD_ZONE, A_FORCE_LIMIT, A_BACK_EMF = range(len(ACTUATOR_VECTOR))
N_ACTUATOR = len(ACTUATOR_VECTOR)
A_INV_TAU, A_KU_TAU = N_ACTUATOR, N_ACTUATOR + 1  # rows actuator_rates adds: 1 / tau, K_U / tau
N_ACTUATOR_ROWS = N_ACTUATOR + 2
S_INDEX = PLANT_STATES.index("s")  # the sensor whose reference a step command moves
FILTER_ROWS = 2  # a sensor filter's states (y, y'): at most one filter, the velocity's
_JIT = {"cache": True, "error_model": "numpy"}  # as patchgen.bench.kernel's


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


@nb.njit(inline="always", **_JIT)
def quantised(x, quantum):
    """x as an encoder reports it: the nearest whole count of ``quantum`` (0: x itself)."""
    return x if quantum == 0.0 else quantum * math.floor(x / quantum + 0.5)


@nb.njit(**_JIT)
def sensor_filters(X, XF, sensors, kf, st):
    """The sensors' filter states at RK4 stage st: filter k holds (y, y') in rows 2k, 2k + 1 of
    a quantised position (of X, the stage's plant states) through
    wn^2 / (s^2 + 2 zeta wn s + wn^2), and y' is the sensor's reading (a velocity from a filter,
    as a lab without a tachometer has it): their slopes at stage st into kf[st]. The velocity is
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
            kf[st, y, l] = XF[y + 1, l]
            kf[st, y + 1, l] = wn * wn * (u - XF[y, l]) - 2.0 * ze * wn * XF[y + 1, l]


@nb.njit(**_JIT)
def circuit(X, Z, XF, s_ref, nz, sensors, sensor_gain, wiring, drift, sat, clip, sig, raw, dz, st, acc):
    """Sensors and amplifiers in evaluation order: sig (clipped if clip; its last row stays 0),
    raw (before clipping), and the amplifier state derivatives into dz[st] (a summer's stay 0).
    sensors: patchgen.bench.kernel's Sensors (a sensor reads its plant state, quantised, or its
    filter's output in XF); wiring: patchgen.bench.kernel's Wiring; X, Z, XF, nz, drift and
    sensor_gain (sensor, lane) are per lane."""
    amp_kind, in_ptr, in_src, in_gain = wiring.kind, wiring.in_ptr, wiring.in_src, wiring.in_gain
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
def actuator_rates(ap):
    """Fill rows A_INV_TAU and A_KU_TAU of ap (N_ACTUATOR_ROWS, lane) from its K_U and tau: the
    same quotients drive used to take at every stage, taken once per block."""
    for l in range(ap.shape[1]):
        ap[A_INV_TAU, l] = 1.0 / ap[A_TAU, l]
        ap[A_KU_TAU, l] = ap[A_K_U, l] / ap[A_TAU, l]


@nb.njit(**_JIT)
def drive(X, XA, sig, out_index, tripped, pc, act, ap, f_cart, f_tip, nz, kp, kx, forces, at_limit, st):
    """Actuator (dead zone, model, force limit; off once tripped) and plant slopes per lane,
    into kp[st], kx[st], forces[st], and at stage 0 whether the command sits at the actuator's
    limit into at_limit. act: the actuator's model ACT_*; ap (N_ACTUATOR_ROWS, lane): each lane's
    K_U, tau, dead zone, force limit, back-EMF, then 1 / tau and K_U / tau (actuator_rates); a
    motor's command K_U v is limited at the amplifier (force limit = a V_limit), then the back-EMF
    takes b s_dot from it, through the electrical lag tau when it has one;
    X (plant state), XA (actuator state) and pc (plant_coefficients) are per lane. f_cart and
    f_tip are the scenario's pushes (N); the last two rows of nz, the bench's random forces on
    the cart and at the tip (N), per lane."""
    fc, ft = nz.shape[0] - 2, nz.shape[0] - 1
    # Two lane loops, not one: the actuator's branches and the plant's trigonometry in one
    # body keep LLVM from vectorising either; split, both run on whole SIMD registers.
    for l in range(XA.shape[0]):
        K_U, dz, flim = ap[A_K_U, l], ap[A_DEAD_ZONE, l], ap[A_FORCE_LIMIT, l]
        inv_tau, ku_tau = ap[A_INV_TAU, l], ap[A_KU_TAU, l]
        u = sig[out_index, l]
        v = u - dz if u > dz else (u + dz if u < -dz else 0.0)
        xa = XA[l]
        if act == ACT_MOTOR:
            cmd = K_U * v
            limited = (cmd >= flim) | (cmd <= -flim)
            cmd = flim if cmd > flim else (-flim if cmd < -flim else cmd)
            net = cmd - ap[A_BACK_EMF, l] * X[2, l]
            lagged = ap[A_TAU, l] > 0.0
            force, dx = (xa, (net - xa) * inv_tau) if lagged else (net, 0.0)
        else:
            if act == ACT_GAIN:
                force, dx = K_U * v, 0.0
            elif act == ACT_LAG:
                force, dx = xa, (K_U * v - xa) * inv_tau
            else:
                force, dx = ku_tau * (v - xa), (v - xa) * inv_tau
            limited = (force >= flim) | (force <= -flim)
            force = flim if force > flim else (-flim if force < -flim else force)
        if st == 0:
            at_limit[l] = limited
        kx[st, l] = dx
        forces[st, l] = 0.0 if tripped[l] else force
    for l in range(XA.shape[0]):
        sd, thd = X[2, l], X[3, l]
        sn, cs = sincos(X[1, l])
        sdd, thdd = plant_accel(pc, l, sn, cs, sd, thd, forces[st, l] + (f_cart + nz[fc, l]),
                                f_tip + nz[ft, l])
        kp[st, 0, l] = sd
        kp[st, 1, l] = thd
        kp[st, 2, l] = sdd
        kp[st, 3, l] = thdd
