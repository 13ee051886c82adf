"""The floor the engine is measured against: a lean loop of one closed loop over the lanes of a
block (runs side by side), the shipped bench-recommended patch on its bench (uw-1991) in
hold-120s, written out by hand.

The same plant equations (patchgen.plant.compiled), the same random numbers (patchgen.bench.noise:
the engine's keys, steps and channels), the same held noise, actuator (lag, dead zone, force
limit), RK4 step, rails and limit switches, in the engine's order of operations: for the same
draws it ends every run in the same state, to the bit (benchmarks/bench_engine.py checks it
before it times anything). What it leaves out is patchgen's generality: the circuit is five
amplifiers written as expressions (no netlist read per step), one loop over the lanes per RK4
stage, and of the per-run figures only |theta|'s maximum and the trip.
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from patchgen.bench.noise import WORDS, fill_normals
from patchgen.plant.compiled import N_COEF, P_HALF_TRACK, plant_accel, plant_coefficients, sincos

CHANNELS = 10  # three sensors, five amplifiers, the random forces on the cart and at the tip


@nb.njit(inline="always", error_model="numpy")
def _clip(v, hi):
    return hi if v > hi else (-hi if v < -hi else v)


@nb.njit(nogil=True, error_model="numpy")
def lean_block(keys, signs, plants, gains, nstd, a, x0, act, w, drift_rate, dt, steps, sat):
    """Runs (one per row of keys) side by side (w: the wiring's ten input gains in its order, then
    the integrator's rate and the differentiator's two roll-off rates); returns (final state (4, lanes), max |theta|,
    trip step (-1: never), run-steps done)."""
    nl = keys.shape[0]
    pc = np.empty((N_COEF, nl))
    half = np.empty(nl)
    k0, k1 = np.empty(nl, dtype=np.uint64), np.empty(nl, dtype=np.uint64)
    g = np.zeros((5, nl))  # sensor gains, then the drift and whether tripped (1.0), per lane
    sd_ = np.empty((CHANNELS, nl))
    for l in range(nl):
        plant_coefficients(plants[l], pc[:, l])
        half[l] = plants[l, P_HALF_TRACK]
        k0[l], k1[l] = keys[l, 0], keys[l, 1]
        for i in range(3):
            g[i, l] = gains[l, i]
        for c in range(CHANNELS):
            sd_[c, l] = nstd[l, c]
        g[3, l] = drift_rate * signs[l, 0]
    rows = (CHANNELS + WORDS - 1) // WORDS * WORDS
    z = np.empty((rows, nl))
    words = np.empty((WORDS, nl), dtype=np.uint64)
    nz = np.zeros((CHANNELS, nl))
    fill_normals(np.int64(0), k0, k1, z, words, CHANNELS)
    for c in range(CHANNELS):
        for l in range(nl):
            nz[c, l] = z[c, l] * sd_[c, l] / math.sqrt(1.0 - a[c] * a[c])
    x = np.zeros((7, nl))  # the plant's states, then A1's, A5's and the actuator's
    for i in range(4):
        for l in range(nl):
            x[i, l] = x0[i]
    for _ in range(5):  # the differentiator settled on its input, as the engine settles it
        for l in range(nl):
            raw = -w[11] * ((0.0 + w[2] * (g[1, l] * (x0[1] - 0.0) + 0.0)) - x[5, l]) + 0.0
            x[5, l] -= raw / w[11]
    k = np.zeros((4, 8, nl))  # slopes of the 7 states, then the force
    xs = np.zeros((7, nl))
    tripped = np.zeros(nl, dtype=np.bool_)
    w0, w1, w2, w3, w4, w5, w6, w7, w8, w9, w10, w11, w12 = (w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7],
                                                             w[8], w[9], w[10], w[11], w[12])
    K_U, dzone, flim, inv_tau = act[0], act[1], act[2], act[3]
    alive = np.ones(nl, dtype=np.bool_)
    mth = np.zeros(nl)
    trip = np.full(nl, -1)
    done = 0
    h = dt
    for n in range(steps + 1):
        t = n * h
        if n > 0:
            fill_normals(n, k0, k1, z, words, CHANNELS)
            for c in range(CHANNELS):
                ac = a[c]
                for l in range(nl):
                    nz[c, l] = ac * nz[c, l] + sd_[c, l] * z[c, l]
        f_tip = 0.5 * max(0.0, min(t + h, 30.1) - max(t, 30.0)) / h
        f_cart = 5.0 * max(0.0, min(t + h, 70.1) - max(t, 70.0)) / h
        for st in range(4):
            c = 0.0 if st == 0 else (h if st == 3 else 0.5 * h)
            p = max(st - 1, 0)
            kp, ks = k[p], k[st]  # the last stage's slopes, this stage's (apart: no aliasing to fear)
            for l in range(nl):
                for i in range(7):
                    xs[i, l] = x[i, l] + c * kp[i, l]
            # two loops, as the engine's drive has them, each reading few arrays (more, and LLVM
            # gives up proving they do not overlap, and runs the loop a lane at a time)
            for l in range(nl):
                y0 = g[0, l] * (xs[0, l] - 0.0) + nz[0, l]
                y1 = g[1, l] * (xs[1, l] - 0.0) + nz[1, l]
                y2 = g[2, l] * (xs[2, l] - 0.0) + nz[2, l]
                a1 = _clip(xs[4, l] + nz[3, l], sat)  # A1, integrator: its state
                e = (0.0 + w2 * y1) - xs[5, l]  # A5, differentiator with roll-off: one input
                a5 = _clip(-w11 * e + nz[4, l], sat)
                a7 = _clip(-((0.0 + w3 * y0 + w4 * y1) + w5 * y2) + nz[5, l], sat)
                a8 = _clip(-(((0.0 + w6 * a5) + w7 * a1) + w8 * a7) + nz[6, l], sat)  # u_c
                a6 = _clip(-(0.0 + w9 * a8) + nz[7, l], sat)  # an inverter: -u_c
                v = a8 - dzone if a8 > dzone else (a8 + dzone if a8 < -dzone else 0.0)
                xl = xs[6, l]
                f = flim if xl > flim else (-flim if xl < -flim else xl)
                ks[7, l] = 0.0 if g[4, l] != 0.0 else f  # the motor cut once tripped
                ks[4, l] = -w10 * ((0.0 + w0 * a6) + w1 * a1) + g[3, l]
                ks[5, l] = w12 * e
                ks[6, l] = (K_U * v - xl) * inv_tau
            for l in range(nl):
                th, sd, thd = xs[1, l], xs[2, l], xs[3, l]
                sn, cs = sincos(th)
                sdd, thdd = plant_accel(pc, l, sn, cs, sd, thd, ks[7, l] + (f_cart + nz[8, l]), f_tip + nz[9, l])
                ks[0, l], ks[1, l], ks[2, l], ks[3, l] = sd, thd, sdd, thdd
        n_alive = 0
        for l in range(nl):
            th = abs(x[1, l])
            mth[l] = th if th > mth[l] else mth[l]
            done += alive[l]
            alive[l] = alive[l] & (not tripped[l]) & (n < steps)
            n_alive += alive[l]
        if n_alive == 0:
            break
        for i in range(7):  # plant, integrator, differentiator and actuator states
            for l in range(nl):
                x[i, l] += h / 6.0 * (k[0, i, l] + 2.0 * k[1, i, l] + 2.0 * k[2, i, l] + k[3, i, l])
        for l in range(nl):
            x[4, l] = _clip(x[4, l], sat)  # a capacitor cannot charge past the rails
            hit = alive[l] & (not tripped[l]) & (abs(x[0, l]) >= half[l])
            trip[l] = n + 1 if hit else trip[l]
            tripped[l] = tripped[l] | hit
            g[4, l] = 1.0 if tripped[l] else 0.0
    return x[:4], mth, trip, done - nl  # the summary at step 0 is not a step taken
