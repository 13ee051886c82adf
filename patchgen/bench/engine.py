"""The simulator's engine: fixed-step RK4 of the nonlinear plant, the actuator and the patched
circuit, runs side by side in blocks (``patchgen.bench.kernel``), per-run summaries and optional histories.

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
import sys
from dataclasses import dataclass

import numpy as np

from patchgen.bench import kernel
from patchgen.bench.kernel import DIST_CART_FORCE, DIST_STEP, DIST_TIP_FORCE, LANES  # noqa: F401  (the engine's interface)
from patchgen.bench.lanes import ACT_GAIN, ACT_LAG, ACT_LAG_ZERO, plant_rhs  # noqa: F401

BENCH_DT_S = 0.002
IDEAL_DT_S = 0.01
STEPS_PER_TIME_CONSTANT = 1.0
COMPILE_NOTICE = "compiling simulation kernels (first run after installation; cached for later runs)..."

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
    """Each run's random draws, from its own generator: the drift sign of each amplifier, the
    two 32-bit words that key its noise (drawn in the compiled loop, see patchgen.bench.kernel), then,
    with a parameter spread, the run's plant. A run's draws depend on nothing but its generator."""
    runs = len(rngs)
    n_amp = len(cfg.amp_kind)
    signs = np.empty((runs, n_amp))
    keys = np.empty((runs, 2), dtype=np.uint64)
    plants = np.repeat(cfg.plant[None, :], runs, axis=0)
    spread = cfg.plant_spread.any()
    for r, rng in enumerate(rngs):
        signs[r] = np.where(rng.random(n_amp) < 0.5, 1.0, -1.0)
        keys[r] = rng.integers(0, 2**32, size=2, dtype=np.uint64)
        if spread:
            plants[r] *= 1.0 + cfg.plant_spread * rng.uniform(-1.0, 1.0, cfg.plant.shape[0])
    return signs, keys, plants


def kernel_args(cfg: EngineConfig, draws: tuple[np.ndarray, np.ndarray, np.ndarray],
                out: dict[str, np.ndarray]) -> tuple:
    """The compiled loop's arguments for ``draws`` (see draw_batch), writing into ``out``."""
    signs, keys, plants = draws
    fpar = np.zeros(7)
    fpar[[kernel.F_DT, kernel.F_SAT, kernel.F_K_U, kernel.F_TAU, kernel.F_DEAD, kernel.F_FLIM,
          kernel.F_FALL]] = (cfg.dt, cfg.saturation_V, cfg.K_U, cfg.tau, cfg.dead_zone_V,
                             cfg.force_limit_N, cfg.fall_angle)
    ipar = np.zeros(6, dtype=np.int64)
    ipar[[kernel.I_STEPS, kernel.I_STRIDE, kernel.I_LIMIT, kernel.I_CLIP, kernel.I_OUT,
          kernel.I_ACT]] = (cfg.n_steps, cfg.stride, cfg.limit_switches, cfg.clip,
                            cfg.output_index, cfg.actuator)
    f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)
    i64 = lambda a: np.ascontiguousarray(a, dtype=np.int64)
    return (keys, f64(signs), f64(plants), fpar, ipar, f64(cfg.x0), i64(cfg.sensor_state),
            f64(cfg.sensor_gain), f64(np.concatenate([cfg.sensor_noise_a, cfg.amp_noise_a])),
            f64(np.concatenate([cfg.sensor_noise_std, cfg.amp_noise_std])),
            i64(cfg.amp_kind), i64(cfg.in_ptr), i64(cfg.in_src), f64(cfg.in_gain), f64(cfg.param1),
            f64(cfg.param2), f64(cfg.ic_V), f64(cfg.drift), i64(cfg.dist_kind), f64(cfg.dist_t0),
            f64(cfg.dist_t1), f64(cfg.dist_value), out["res"], out["ovl_first"], out["ovl_time"],
            out["hist"], out["hist_len"])


def run_batch(cfg: EngineConfig, draws: tuple[np.ndarray, np.ndarray, np.ndarray],
              n_history: int) -> BatchOutput:
    """One run per row of ``draws`` (see draw_batch), in blocks of LANES runs side by side, the
    blocks in parallel threads without the GIL; histories for the first n_history runs."""
    runs, n_amp = draws[0].shape
    n_samples = cfg.n_steps // cfg.stride + 2  # stride samples, and the last one off-stride
    res = np.zeros((runs, kernel.N_RESULTS))
    res[:, [kernel.R_TRIP, kernel.R_FALL]] = np.nan
    out = {"res": res, "ovl_first": np.full((runs, n_amp), np.nan), "ovl_time": np.zeros((runs, n_amp)),
           "hist": np.zeros((n_history, n_samples, len(HISTORY_CHANNELS) + n_amp)),
           "hist_len": np.zeros(n_history, dtype=np.int64)}
    args = kernel_args(cfg, draws, out)
    if runs <= LANES:  # one block: no thread launch, it costs more than the block on a busy machine
        _notice_if_compiling(kernel.run_block, (0, runs) + args)
        kernel.run_block(0, runs, *args)
    else:
        _notice_if_compiling(kernel.run_blocks, args)
        kernel.run_blocks(*args)
    return BatchOutput(
        trip_time=res[:, kernel.R_TRIP], fall_time=res[:, kernel.R_FALL],
        max_abs_theta=res[:, kernel.R_MAX_TH], max_abs_s=res[:, kernel.R_MAX_S],
        rms_theta=res[:, kernel.R_RMS_TH], max_abs_u_c=res[:, kernel.R_MAX_UC],
        max_abs_force=res[:, kernel.R_MAX_F], overload_first=out["ovl_first"],
        overload_time=out["ovl_time"], final_state=res[:, kernel.R_FINAL:kernel.R_FINAL + 4],
        history=out["hist"], history_length=out["hist_len"],
    )


def will_compile(dispatcher, args: tuple) -> bool:
    """Whether calling ``dispatcher`` with ``args`` is going to compile it: not yet compiled in
    this process for these argument types, and not in numba's disk cache for this source, this
    machine and this bytecode (numba's own index key). False when numba's cache layout is not
    the one this reads: then nothing is claimed."""
    try:
        sig = tuple(dispatcher.typeof_pyval(a) for a in args)
        if sig in dispatcher.overloads:
            return False
        cache = dispatcher._cache
        key = cache._index_key(sig, dispatcher.targetctx.codegen())
        return key not in cache._cache_file._load_index()
    except Exception:  # numba internals moved: better silent than wrong
        return False


_noticed = False


def _notice_if_compiling(dispatcher, args: tuple) -> None:
    """One line on stderr (once per process) before a first call that compiles: it takes a
    while, once per installation."""
    global _noticed
    if not _noticed and will_compile(dispatcher, args):
        _noticed = True
        print(COMPILE_NOTICE, file=sys.stderr, flush=True)
