"""The compiled Monte-Carlo loop, runs side by side: blocks of up to LANES runs, every state an
array (quantity, lane), every inner loop over lanes (patchgen.bench.lanes, patchgen.bench.noise), so that LLVM
vectorises each operation across runs.

One step of one block: draw the lanes' noise (sensors, amplifiers, random forces on the plant),
four RK4 stages of plant + actuator + circuit,
clip integrating amplifiers at the rails, check limit switches, fall and overloads. A lane whose
run has ended (the limit switches cut the motor) keeps being computed with the others but is no
longer recorded; the block stops when every lane has ended or at the scenario's end.

The loop takes a few records (named tuples, which numba compiles as structs): the runs' draws,
the scalar settings with the actuator's, the sensors, the noise, the wiring, the disturbances and
the outputs it fills. Columns of the outputs are named: RESULTS for the per-run figures,
HISTORY_CHANNELS (then the amplifier outputs) for the history. numba's cache index names the
records' classes: renaming or removing one leaves a cache that no longer loads (delete the
__pycache__ folders' .nbi and .nbc files).

The arithmetic is plain IEEE, without fast-math, not even fused multiply-add (it is 7 % faster,
but LLVM fuses differently in a loop's vectorised body and its scalar remainder), so each lane's
result is bit for bit the same whatever the number of lanes in its block, its place in the
block, the number of threads or the order of the blocks: a run depends only on its own inputs
(tests/bench/test_kernel.py checks it).

numba's disk cache is stamped with the content of the file of the function it compiled, and does
not see a change in a callee elsewhere: COMPILED_IN holds a digest of COMPILED_FILES, whose code
is compiled into this file's, so that changing them changes this file (tests/bench/test_kernel.py
says when it is out of date).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba as nb
import numpy as np

from patchgen.bench.circuit import DIFFERENTIATOR
from patchgen.bench.lanes import (
    N_ACTUATOR,
    N_ACTUATOR_ROWS,
    PLANT_ROTARY,
    actuator_rates,
    circuit,
    drive,
    quantised,
    sensor_filters,
    state_rows,
)
from patchgen.bench.noise import WORDS, fill_normals
from patchgen.plant.compiled import N_COEF, P_HALF_TRACK, plant_coefficients
from patchgen.plant.equations import PLANT_STATES
from patchgen.plant.rotary_compiled import P_ARM_LIMIT, rotary_coefficients

COMPILED_FILES = ("bench/lanes.py", "bench/noise.py", "plant/compiled.py", "plant/rotary_compiled.py")  # patchgen/
COMPILED_IN = "35449ecf00df60f6"  # sha256 of COMPILED_FILES in that order, first 16 hex digits
LANES = 128  # runs per block (fewer, and the per-step work that is not per lane weighs more)
PAD = 16  # a block computes a multiple of this many lanes: four AVX2 registers of four lanes
DIST_CART_FORCE, DIST_TIP_FORCE, DIST_STEP = 0, 1, 2
N_STATES = len(PLANT_STATES)
S, THETA = PLANT_STATES.index("s"), PLANT_STATES.index("theta")

# per-run results: event times (NaN: never), maxima, RMS theta, then the final plant state
SUMMARIES = ("trip_time", "fall_time", "max_abs_theta", "max_abs_s", "rms_theta", "max_abs_u_c",
             "max_abs_force", "limit_time")
RESULTS = SUMMARIES + tuple(f"final_{q}" for q in PLANT_STATES)
R_TRIP, R_FALL, R_MAX_TH, R_MAX_S, R_RMS_TH, R_MAX_UC, R_MAX_F, R_LIMIT = (RESULTS.index(c) for c in SUMMARIES)
R_FINAL = RESULTS.index(f"final_{PLANT_STATES[0]}")  # the final state, N_STATES columns
# history channels before the amplifier outputs
HISTORY_CHANNELS = ("t",) + PLANT_STATES + ("s_ref", "u_c", "force")
H_T, H_S_REF, H_U_C, H_FORCE = (HISTORY_CHANNELS.index(c) for c in ("t", "s_ref", "u_c", "force"))
H_STATE = HISTORY_CHANNELS.index(PLANT_STATES[0])  # the plant state, N_STATES channels
H_AMPS = len(HISTORY_CHANNELS)  # the amplifier outputs, in evaluation order
# each lane's running figures: sum of theta^2, the maxima of |theta|, |s|, |u_c|, |force|, the time at the limit
F_SUM_TH2, F_MAX_TH, F_MAX_S, F_MAX_UC, F_MAX_F, F_LIMIT = range(6)
N_FIGURES = 6
# cached on disk; IEEE arithmetic (see above); no Python exceptions for x / 0
_JIT = {"cache": True, "error_model": "numpy"}


class Draws(NamedTuple):
    """Each run's random draws, a row per run (see patchgen.bench.engine.draw_batch)."""

    keys: np.ndarray  # (runs, 2) uint64: the key of the run's counter-based noise
    signs: np.ndarray  # (runs, amplifiers) +/-1: which way each amplifier drifts
    plants: np.ndarray  # (runs, len(PLANT_VECTOR)): the run's plant
    actuators: np.ndarray  # (runs, N_ACTUATOR): the run's actuator, ACTUATOR_VECTOR of patchgen.bench.lanes
    sensor_gains: np.ndarray  # (runs, sensors): the run's sensor constants, V per SI unit
    noise_std: np.ndarray  # (runs, channels): the run's innovation std of each noise channel (see Noise)


class Settings(NamedTuple):
    """The scalar settings of a batch with the actuator's, and the initial plant state (flat:
    one record, not records nested in one another)."""

    dt: float  # s
    steps: int
    stride: int  # record every stride-th step into the history
    saturation: float  # V
    clip: bool  # clip outputs at +/- saturation (overloads are recorded either way)
    limit_switches: bool
    fall_angle: float  # rad
    output: int  # signal index of the control voltage u_c
    x0: np.ndarray  # plant state at t = 0
    actuator: int  # model: ACT_* of patchgen.bench.lanes (its values are each run's, in Draws)
    plant: int  # PLANT_* of patchgen.bench.lanes: the cart (Draws' plants PLANT_VECTOR's) or the rotary
    # pendulum (ROTARY_VECTOR's); its position's limit is the cart's switch or the arm's cable


class Sensors(NamedTuple):
    """Per sensor: the plant state it reads (index), its nominal gain (V per SI unit; each run's
    own is in Draws), its encoder's count (SI units; 0: continuous), and for a velocity from a
    filter, the filter's index (-1: none), the position it filters, its wn (rad/s) and zeta."""

    state: np.ndarray
    gain: np.ndarray
    quantum: np.ndarray
    filt: np.ndarray
    source: np.ndarray
    wn: np.ndarray
    zeta: np.ndarray


class Noise(NamedTuple):
    """Per channel (the sensors, the amplifiers, then the random forces on the cart and at the
    tip, N): held noise n' = a n + std w (std nominal; each run's own is in Draws)."""

    a: np.ndarray
    std: np.ndarray  # V


class Wiring(NamedTuple):
    """The compiled circuit (patchgen.bench.circuit.Circuit's arrays) and each amplifier's drift.
    The loop sums inputs from the groups; the plain input list (in_ptr, in_src, in_gain) stays for
    what reads the circuit as patched, the per-run reference loop of tests/bench among them, which
    so checks the grouping rather than sharing it."""

    kind: np.ndarray
    in_ptr: np.ndarray
    in_src: np.ndarray
    in_gain: np.ndarray
    param1: np.ndarray
    param2: np.ndarray
    ic: np.ndarray  # V
    drift: np.ndarray  # V/s magnitude (its sign is drawn per run)
    group_ptr: np.ndarray  # each amplifier's inputs in groups of TERMS, as the loop sums them
    group_src: np.ndarray  # (patchgen.bench.lanes.input_groups)
    group_gain: np.ndarray


class Disturbances(NamedTuple):
    """Per disturbance: DIST_* kind, start and end (s), force (N) or step (m)."""

    kind: np.ndarray
    t0: np.ndarray
    t1: np.ndarray
    value: np.ndarray


class Outputs(NamedTuple):
    """What the loop fills: RESULTS per run (event times NaN beforehand), overloads per run and
    amplifier (first time NaN beforehand), and the histories of the first history.shape[0] runs."""

    results: np.ndarray  # (runs, len(RESULTS))
    overload_first: np.ndarray  # (runs, amplifiers) s
    overload_time: np.ndarray  # (runs, amplifiers) s
    amp_peak: np.ndarray  # (runs, amplifiers) V: the largest |output| at a step's start, rails ignored, while
    # the pendulum is up (a fallen pendulum's swings are not what the patch was scaled for)
    history: np.ndarray  # (history runs, samples, H_AMPS + amplifiers)
    history_length: np.ndarray  # samples recorded per history run


@nb.njit(nogil=True, **_JIT)
def run_block(lo, nl, draws, settings, sensors, noise, wiring, disturbances, out):
    """Runs lo .. lo + nl - 1 side by side, into the rows of ``out`` (an Outputs) that are theirs.

    Parameters
    ----------
    lo, nl : int
        The first run of the block and how many runs it holds (at most LANES). Past PAD runs,
        the block computes a whole number of PAD lanes, the last run copied into the lanes past
        nl, which are never recorded: a loop over lanes then runs on whole vector registers,
        without a remainder taken a lane at a time (a lane so taken costs about three in a
        register). A smaller block is computed as it is: a single run stays a single lane.
    draws, settings, sensors, noise, wiring, disturbances : Draws, Settings, Sensors, Noise, Wiring, Disturbances
        The batch, as the records of this module.
    out : Outputs
        Filled for these runs (histories for those below ``out.history.shape[0]``).
    """
    h, sat, n_steps, stride = settings.dt, settings.saturation, settings.steps, settings.stride
    limit_on, clip, out_index = settings.limit_switches, settings.clip, settings.output
    keys, signs, plants = draws.keys, draws.signs, draws.plants
    ns, na = sensors.state.shape[0], wiring.kind.shape[0]
    nch = noise.a.shape[0]  # ns + na voltages, then the two forces
    nr, nl = nl, (nl if nl <= PAD else (nl + PAD - 1) // PAD * PAD)  # the block's runs, the lanes computed
    pc = np.empty((N_COEF, nl))
    act = np.empty((N_ACTUATOR_ROWS, nl))  # each lane's actuator, sensor gains and noise levels
    gain = np.empty((ns, nl))
    nstd = np.empty((nch, nl))
    half = np.empty(nl)
    k0 = np.empty(nl, dtype=np.uint64)
    k1 = np.empty(nl, dtype=np.uint64)
    drift = np.empty((na, nl))  # each integrating amplifier drifts one way, drawn per run
    ra, rx, rf, r_force, r_limit = state_rows(na)
    n_int = r_force  # the integrated states: the rows before the force's
    # the integrated states, rows of one array, and each RK4 stage's (patchgen.bench.lanes.state_rows)
    state, staged = np.zeros((n_int, nl)), np.zeros((n_int, nl))
    xp, za, xa, xf = state[:ra], state[ra:rx], state[rx], state[rf:r_force]  # xf: the velocity filter's
    xt, zt, xat, xft = staged[:ra], staged[ra:rx], staged[rx], staged[rf:r_force]
    K = np.zeros((4, r_limit + 1, nl))  # each stage's slopes, then the actuator's force and at-limit
    flat, flat_staged, flat_K = state.reshape(n_int * nl), staged.reshape(n_int * nl), K.reshape((4, K[0].size))
    act_rows = (rx, r_force, r_limit)
    force, at_limit = K[0, r_force], K[0, r_limit]  # at the step's start: recorded and summarised
    over = np.empty((3, na, nl))  # each lane's overloads (first time, time) and peak, copied out at its end
    for l in range(nl):
        r = lo + min(l, nr - 1)  # a lane past the block's runs computes its last run again
        if settings.plant == PLANT_ROTARY:
            rotary_coefficients(plants[r], pc[:, l])
            half[l] = plants[r, P_ARM_LIMIT]
        else:
            plant_coefficients(plants[r], pc[:, l])
            half[l] = plants[r, P_HALF_TRACK]
        k0[l], k1[l] = keys[r, 0], keys[r, 1]
        for i in range(N_ACTUATOR):
            act[i, l] = draws.actuators[r, i]
        for i in range(ns):
            gain[i, l] = draws.sensor_gains[r, i]
        for c in range(nch):
            nstd[c, l] = draws.noise_std[r, c]
        for j in range(na):
            drift[j, l] = wiring.drift[j] * signs[r, j]
            za[j, l] = 0.0 if math.isnan(wiring.ic[j]) else wiring.ic[j]
            over[0, j, l], over[1, j, l] = out.overload_first[r, j], out.overload_time[r, j]
            over[2, j, l] = out.amp_peak[r, j]
        for i in range(N_STATES):
            xp[i, l] = settings.x0[i]
        for i in range(ns):  # a filter starts settled: on its position, at the rate the run starts with
            k = sensors.filt[i]
            if k >= 0:
                xf[2 * k, l] = quantised(settings.x0[sensors.source[i]], sensors.quantum[i])
                xf[2 * k + 1, l] = settings.x0[sensors.state[i]]
    actuator_rates(act)
    nz = np.zeros((nch, nl))
    rows = (nch + WORDS - 1) // WORDS * WORDS
    z = np.empty((rows, nl))
    words = np.empty((WORDS, nl), dtype=np.uint64)
    noisy = np.any(nstd > 0.0)
    if noisy:  # start the noise in its stationary distribution
        fill_normals(np.int64(0), k0, k1, z, words, nch)  # typed, not a literal: one compilation of it
        for c in range(nch):
            for l in range(nl):
                nz[c, l] = z[c, l] * nstd[c, l] / math.sqrt(1.0 - noise.a[c] * noise.a[c])
    sig = np.zeros((nch + 1, nl))  # signals, and a row of zeros (the input of an unwired amplifier)
    raw = np.zeros((na, nl))
    acc = np.zeros((2, nl))  # a partial sum of inputs, and zeros
    # a differentiator starts settled on its input (the angle was held before the run): set its
    # filter state to its input, in evaluation order (one pass per amplifier reaches every chain)
    quiet = np.zeros((nch, nl))
    for _ in range(na):
        circuit(xp, za, xf, 0.0, quiet, sensors, gain, wiring, drift, sat, np.bool_(False), sig, raw, K, ra,
                np.int64(0), acc)  # typed, not literals: one compilation of the circuit
        for j in range(na):
            if wiring.kind[j] == DIFFERENTIATOR:
                for l in range(nl):
                    za[j, l] -= raw[j, l] / wiring.param1[j]
    slope0 = np.zeros(nl)
    # an integrator with no IC (NaN) starts settled too: a lag closed through a difference, its slope
    # linear in its own state, so two slopes place it where the slope is zero
    for j in range(na):
        if math.isnan(wiring.ic[j]):
            circuit(xp, za, xf, 0.0, quiet, sensors, gain, wiring, drift, sat, np.bool_(False), sig, raw, K, ra,
                    np.int64(0), acc)
            for l in range(nl):
                slope0[l] = K[0, ra + j, l]
                za[j, l] += 1.0
            circuit(xp, za, xf, 0.0, quiet, sensors, gain, wiring, drift, sat, np.bool_(False), sig, raw, K, ra,
                    np.int64(0), acc)
            for l in range(nl):
                dk = K[0, ra + j, l] - slope0[l]
                za[j, l] += -1.0 - slope0[l] / dk if dk != 0.0 else -1.0
    tripped = np.zeros(nl, dtype=np.bool_)
    fallen = np.zeros(nl, dtype=np.bool_)
    alive = np.arange(nl) < nr  # the padding lanes are never running
    pinned = np.zeros((na, nl), dtype=np.bool_)  # clipped at a rail by the last update
    fig = np.zeros((N_FIGURES, nl))  # each lane's running figures (F_*)
    n_alive = nr
    n_hist = max(0, min(nr, out.history.shape[0] - lo))
    for n in range(n_steps + 1):
        t = n * h
        if noisy and n > 0:  # new noise for this step
            fill_normals(n, k0, k1, z, words, nch)
            for c in range(nch):
                a = noise.a[c]
                for l in range(nl):
                    nz[c, l] = a * nz[c, l] + nstd[c, l] * z[c, l]
        f_cart, f_tip, s_ref = _disturbances(disturbances, t, h)
        for st in range(4):  # stage 0 reads the step's start itself, the others their own states
            if st > 0:  # the step's start + c * the last stage's slopes, every state in one loop
                c = h if st == 3 else 0.5 * h
                for i in range(flat.shape[0]):
                    flat_staged[i] = flat[i] + c * flat_K[st - 1, i]
            X, Z, XA, XF = (xp, za, xa, xf) if st == 0 else (xt, zt, xat, xft)
            sensor_filters(X, XF, sensors, K, rf, st)
            circuit(X, Z, XF, s_ref, nz, sensors, gain, wiring, drift, sat, clip, sig, raw, K, ra, st, acc)
            drive(X, XA, sig, out_index, tripped, pc, settings.actuator, act, f_cart, f_tip, nz, K, act_rows, st,
                  settings.plant)
            if st == 0:  # record and summarise time t; a run ends at the scenario's end or at a trip
                for l in range(n_hist):
                    if alive[l] and (n % stride == 0 or n == n_steps or tripped[l]):
                        _record(out, lo + l, l, t, xp, s_ref, sig, out_index, force, ns)
                n_alive -= _summaries(n, t, n == n_steps, lo, alive, tripped, fallen, xp, raw, pinned,
                                      sig, out_index, force, at_limit, settings, fig, over, out)
        if n_alive == 0:
            break
        for i in range(flat.shape[0]):  # every state's RK4 step, in one loop
            flat[i] += h / 6.0 * (flat_K[0, i] + 2.0 * flat_K[1, i] + 2.0 * flat_K[2, i] + flat_K[3, i])
        if clip:  # then the rails: a capacitor cannot charge past them
            for j in range(na):
                if wiring.kind[j] != DIFFERENTIATOR:
                    for l in range(nl):
                        v = za[j, l]
                        pinned[j, l] = (v > sat) | (v < -sat)
                        za[j, l] = sat if v > sat else (-sat if v < -sat else v)
        trips = 0
        for l in range(nl):
            trips += alive[l] & (not tripped[l]) & (abs(xp[S, l]) >= half[l])
        if limit_on and trips:
            for l in range(nl):
                if alive[l] and not tripped[l] and abs(xp[S, l]) >= half[l]:
                    tripped[l] = True
                    out.results[lo + l, R_TRIP] = t + h


@nb.njit(**_JIT)
def _disturbances(dist, t, h):
    """(cart force, tip force, s reference) over the step from t, each disturbance averaged over
    the step (so an impulse keeps its area at any step)."""
    f_cart = 0.0
    f_tip = 0.0
    s_ref = 0.0
    for k in range(dist.kind.shape[0]):
        overlap = min(t + h, dist.t1[k]) - max(t, dist.t0[k])
        if overlap > 0.0:
            v = dist.value[k] * overlap / h
            if dist.kind[k] == DIST_CART_FORCE:
                f_cart += v
            elif dist.kind[k] == DIST_TIP_FORCE:
                f_tip += v
            else:
                s_ref += v
    return f_cart, f_tip, s_ref


@nb.njit(**_JIT)
def _summaries(n, t, end, lo, alive, tripped, fallen, xp, raw, pinned, sig, out_index, force, at_lim,
               settings, fig, over, out):
    """Figures at time t of the lanes still running; the results of those whose run ends here.
    Returns how many ended. The running figures are updated in every lane (an ended lane's are
    no longer read), so that loop vectorises (the tests for an event with & and |, not the
    branches of and / or); so are a step's overloads, in over (first time, time overloaded),
    when there is one; the rarer events (a fall, a trip, the end) are looked at lane by lane."""
    sat, h, fall = settings.saturation, settings.dt, settings.fall_angle
    res = out.results
    nl = alive.shape[0]
    events = 0
    for l in range(nl):
        th, s, u, f = abs(xp[THETA, l]), abs(xp[S, l]), abs(sig[out_index, l]), abs(force[l])
        fig[F_SUM_TH2, l] += xp[THETA, l] * xp[THETA, l]
        fig[F_MAX_TH, l] = th if th > fig[F_MAX_TH, l] else fig[F_MAX_TH, l]
        fig[F_MAX_S, l] = s if s > fig[F_MAX_S, l] else fig[F_MAX_S, l]
        fig[F_MAX_UC, l] = u if u > fig[F_MAX_UC, l] else fig[F_MAX_UC, l]
        fig[F_MAX_F, l] = f if f > fig[F_MAX_F, l] else fig[F_MAX_F, l]
        at_limit = (at_lim[l] != 0.0) & (not (end | tripped[l]))
        fig[F_LIMIT, l] = fig[F_LIMIT, l] + h if at_limit else fig[F_LIMIT, l]
    for l in range(nl):  # apart: a loop storing into one array (fig) vectorises
        events += alive[l] & (tripped[l] | ((abs(xp[THETA, l]) > fall) & (not fallen[l])))
    overloads = 0
    for j in range(raw.shape[0]):  # and each amplifier's peak, before the rails, while the pendulum is up
        for l in range(nl):  # (to the step its fall is seen at; an ended lane's no longer read)
            a = abs(raw[j, l])
            over[2, j, l] = a if (a > over[2, j, l]) & (not fallen[l]) else over[2, j, l]
            overloads += alive[l] & ((a > sat) | pinned[j, l])
    if overloads:  # the first time, and the time up to the run's last sample
        for j in range(raw.shape[0]):
            for l in range(nl):
                o = alive[l] & ((abs(raw[j, l]) > sat) | pinned[j, l])
                over[0, j, l] = t if o & math.isnan(over[0, j, l]) else over[0, j, l]
                over[1, j, l] = over[1, j, l] + h if o & (not (end | tripped[l])) else over[1, j, l]
    if events == 0 and not end:
        return 0
    ended = 0
    for l in range(nl):
        if not alive[l]:
            continue
        r = lo + l
        last = end or tripped[l]
        if not fallen[l] and abs(xp[THETA, l]) > fall:
            fallen[l] = True
            res[r, R_FALL] = t
        if last:
            for j in range(raw.shape[0]):
                out.overload_first[r, j], out.overload_time[r, j] = over[0, j, l], over[1, j, l]
                out.amp_peak[r, j] = over[2, j, l]
            res[r, R_MAX_TH], res[r, R_MAX_S] = fig[F_MAX_TH, l], fig[F_MAX_S, l]
            res[r, R_RMS_TH] = math.sqrt(fig[F_SUM_TH2, l] / (n + 1))
            res[r, R_MAX_UC], res[r, R_MAX_F], res[r, R_LIMIT] = fig[F_MAX_UC, l], fig[F_MAX_F, l], fig[F_LIMIT, l]
            for i in range(N_STATES):
                res[r, R_FINAL + i] = xp[i, l]
            alive[l] = False
            ended += 1
    return ended


@nb.njit(**_JIT)
def _record(out, r, l, t, xp, s_ref, sig, out_index, force, ns):
    """One history sample of run r (lane l): the HISTORY_CHANNELS, then the amplifier outputs."""
    hist = out.history
    k = out.history_length[r]
    hist[r, k, H_T] = t
    for i in range(N_STATES):
        hist[r, k, H_STATE + i] = xp[i, l]
    hist[r, k, H_S_REF], hist[r, k, H_U_C], hist[r, k, H_FORCE] = s_ref, sig[out_index, l], force[l]
    for j in range(hist.shape[2] - H_AMPS):
        hist[r, k, H_AMPS + j] = sig[ns + j, l]
    out.history_length[r] = k + 1
