"""The simulator's engine: fixed-step RK4 of the nonlinear plant, the actuator and the patched
circuit, runs side by side in blocks (``patchgen.bench.kernel``), per-run summaries and optional histories.

Everything the loop needs arrives as a few records of arrays and scalars (``EngineConfig``;
the records are patchgen.bench.kernel's), so a run is ``steps`` iterations of: draw the noise
held over the step, four RK4 stages of plant + actuator + circuit, clip integrating amplifiers
at the rails, check limit switches, fall and overloads. A run ends at the scenario's end or when
the limit switches cut the motor: the bench experiment is then over, and what the cart does
next depends on end stops no profile describes. Noise is held over each step (zero-order hold)
with the low-frequency density of the given rms over its bandwidth (``noise_process``).
Disturbances are averaged over each step, so a push keeps its impulse whatever the step.

Default step (``default_step``), chosen by measurement (tests/bench/test_engine.py; noise off,
since a noise realisation depends on the step): on the bench (dead zone, lag, clipping,
switches: events that make RK4 first order) 2 ms, where halving moves theta by at most 2e-5 rad
RMS on the standard scenarios (at 5 ms, up to 1e-3 rad); ideal (smooth) 10 ms, where halving
moves theta by 1e-7 rad RMS. Either way no more than the fastest time constant in the loop (a
differentiator's roll-off, a lag, the actuator's tau): RK4 is stable to 2.8 time constants and
damps such a mode within 2 % per step there.
"""

from __future__ import annotations

import math
import sys
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numba as nb
import numpy as np

from patchgen.bench import bench_spread, kernel
from patchgen.bench.kernel import (
    H_AMPS,
    LANES,
    N_STATES,
    R_FALL,
    R_FINAL,
    R_TRIP,
    RESULTS,
    SUMMARIES,
    Disturbances,
    Draws,
    Noise,
    Outputs,
    Sensors,
    Settings,
    Wiring,
)
from patchgen.plant.compiled import PLANT_VECTOR

BENCH_DT_S = 0.002
IDEAL_DT_S = 0.01
STEPS_PER_TIME_CONSTANT = 1.0
SPLIT_FROM = 32  # the fewest runs of a block split off to use another thread (plan_blocks)
COMPILE_NOTICE = "compiling simulation kernels (first run after installation; cached for later runs)..."


@dataclass(frozen=True)
class EngineConfig:
    """Everything one batch of runs needs: the compiled loop's records (patchgen.bench.kernel),
    and the nominal plant each run draws its own from."""

    settings: Settings
    sensors: Sensors
    noise: Noise  # per channel: the sensors, then the amplifiers
    wiring: Wiring
    disturbances: Disturbances
    plant: np.ndarray  # PLANT_VECTOR of patchgen.plant.compiled: M, m, l, g, b_VF, c, half track, J
    plant_spread: np.ndarray  # per plant parameter (the plant vector's first ones, configure.SPREAD_ORDER): each
    # run draws it uniformly within +/- this fraction
    actuator: np.ndarray  # ACTUATOR_VECTOR of patchgen.bench.lanes: K_U, tau, dead zone, force limit, back-EMF
    bench_spread: bench_spread.BenchSpread | None = None  # each run's bench drawn from these ranges

    @property
    def records(self) -> tuple[Settings, Sensors, Noise, Wiring, Disturbances]:
        """The records the compiled loop takes after the draws, in its order."""
        return self.settings, self.sensors, self.noise, self.wiring, self.disturbances


def default_step(time_constants: list[float], ideal: bool) -> float:
    """The fixed step (s) when a scenario gives none (see the module docstring).

    Parameters
    ----------
    time_constants : list of float
        The loop's time constants (s): lags, roll-offs, the actuator's tau; zeros are ignored.
    ideal : bool
        Every imperfection off (a smooth loop: a coarser step does).

    Returns
    -------
    float
        BENCH_DT_S or IDEAL_DT_S, or the fastest time constant if that is shorter.
    """
    base = IDEAL_DT_S if ideal else BENCH_DT_S
    return min([base] + [tc / STEPS_PER_TIME_CONSTANT for tc in time_constants if tc > 0])


def noise_process(rms: float, bandwidth_Hz: float, dt: float) -> tuple[float, float]:
    """(memory a, innovation std) of held noise n_k+1 = a n_k + std w_k that has rms ``rms``
    over ``bandwidth_Hz``, i.e. one-sided density rms^2 / B at low frequency, at step dt.

    With q = 1 / (2 dt B): a coarse step (q <= 1, Nyquist below B) carries only the in-band
    part, white, std = rms sqrt(q); a fine step uses a = (q - 1) / (q + 1), which gives the same
    density with stationary rms ``rms`` (the two meet at q = 1).

    Parameters
    ----------
    rms : float
        The noise's rms over its band (V); 0 for none.
    bandwidth_Hz : float
        Its bandwidth B.
    dt : float
        The step (s).

    Returns
    -------
    tuple of float
        (a, std): the memory and the innovation's standard deviation.
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
    limit_time: np.ndarray  # s the command sat at the actuator's limit (a motor's: the amplifier's)
    overload_first: np.ndarray  # (runs, amps) s, NaN if never
    overload_time: np.ndarray  # (runs, amps) total time overloaded, s
    amp_peak: np.ndarray  # (runs, amps) the largest |output| (V, before the rails)
    final_state: np.ndarray  # (runs, 4)
    history: np.ndarray  # (n_history, samples, channels)
    history_length: np.ndarray  # samples recorded per history run (a run ends at a trip)


def draw_batch(cfg: EngineConfig, rngs: list[np.random.Generator]) -> Draws:
    """Each run's random draws, from its own generator.

    The drift sign of each amplifier, the two 32-bit words that key its noise (drawn in the
    compiled loop, see patchgen.bench.kernel), then, with a parameter spread, the run's plant,
    then, with a bench spread, the run's bench (patchgen.bench.bench_spread). A run's draws
    depend on nothing but its generator.

    Parameters
    ----------
    cfg : EngineConfig
        The batch's configuration (amplifiers, plant and its spread).
    rngs : list of numpy.random.Generator
        One generator per run.

    Returns
    -------
    Draws
        A row per run.
    """
    runs = len(rngs)
    n_amp = len(cfg.wiring.kind)
    signs = np.empty((runs, n_amp))
    keys = np.empty((runs, 2), dtype=np.uint64)
    plants = np.repeat(cfg.plant[None, :], runs, axis=0)
    actuators = np.repeat(cfg.actuator[None, :], runs, axis=0)
    gains = np.repeat(cfg.sensors.gain[None, :], runs, axis=0)
    noise_std = np.repeat(cfg.noise.std[None, :], runs, axis=0)
    spread, bench = cfg.plant_spread.any(), cfg.bench_spread
    for r, rng in enumerate(rngs):
        signs[r] = np.where(rng.random(n_amp) < 0.5, 1.0, -1.0)
        keys[r] = rng.integers(0, 2**32, size=2, dtype=np.uint64)
        if spread:
            n = cfg.plant_spread.shape[0]  # the first n of the plant vector
            plants[r, :n] *= 1.0 + cfg.plant_spread * rng.uniform(-1.0, 1.0, n)
        if bench is not None:
            bench_spread.apply(bench, bench_spread.draw(bench, rng), actuators[r], gains[r], noise_std[r])
    return Draws(keys=keys, signs=signs, plants=plants, actuators=actuators, sensor_gains=gains,
                 noise_std=noise_std)


def run_batch(cfg: EngineConfig, draws: Draws, n_history: int) -> BatchOutput:
    """One run per row of ``draws``, in blocks of at most LANES runs side by side.

    The blocks (plan_blocks) run in parallel threads (run_block releases the GIL;
    numba.get_num_threads() of them, the cores by default); a batch of one block runs in this
    thread (a thread launch costs more than the block on a busy machine). Threads of Python,
    not a numba parallel loop: that loop would be a second compilation of the whole kernel (about 9 s on a first run).

    Parameters
    ----------
    cfg : EngineConfig
        The batch's configuration.
    draws : Draws
        The runs' draws (see draw_batch).
    n_history : int
        How many of the first runs keep their histories.

    Returns
    -------
    BatchOutput
        Per-run figures, and the histories.
    """
    runs, n_amp = draws.signs.shape
    n_samples = cfg.settings.steps // cfg.settings.stride + 2  # stride samples, and the last one off-stride
    results = np.zeros((runs, len(RESULTS)))
    results[:, [R_TRIP, R_FALL]] = np.nan
    out = Outputs(results=results, overload_first=np.full((runs, n_amp), np.nan),
                  overload_time=np.zeros((runs, n_amp)), amp_peak=np.zeros((runs, n_amp)),
                  history=np.zeros((n_history, n_samples, H_AMPS + n_amp)),
                  history_length=np.zeros(n_history, dtype=np.int64))
    args = (draws, *cfg.records, out)
    _notice_if_compiling(kernel.run_block, (0, min(runs, LANES)) + args)
    blocks = plan_blocks(runs, nb.get_num_threads())
    if len(blocks) == 1:
        kernel.run_block(*blocks[0], *args)
    else:  # the blocks write disjoint rows of out and release the GIL
        with ThreadPoolExecutor(min(len(blocks), nb.get_num_threads())) as pool:
            for _ in pool.map(lambda block: kernel.run_block(*block, *args), blocks):
                pass
    return BatchOutput(
        **{name: results[:, RESULTS.index(name)] for name in SUMMARIES},
        final_state=results[:, R_FINAL:R_FINAL + N_STATES], overload_first=out.overload_first,
        overload_time=out.overload_time, amp_peak=out.amp_peak, history=out.history, history_length=out.history_length,
    )


def plan_blocks(runs: int, threads: int) -> list[tuple[int, int]]:
    """(first run, runs) of each block: at most LANES runs each, as even as they come, and a
    multiple of ``threads`` blocks when every block still holds SPLIT_FROM runs (two blocks of
    64 run side by side in about the time of one of 32 lanes; a block of fewer runs pays the
    per-step work that is not per lane for little: it runs alone). A run's result does not
    depend on its block (patchgen.bench.kernel)."""
    n = -(-runs // LANES)
    if threads > 1 and n % threads:
        more = -(-n // threads) * threads
        n = more if runs >= more * SPLIT_FROM else n
    size = -(-runs // n)
    return [(lo, min(size, runs - lo)) for lo in range(0, runs, size)]


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


def drawn(cfg: EngineConfig, draws: Draws) -> list[tuple[tuple[str, float], ...]]:
    """Each run's drawn parameters, (name, value) in a fixed order: the plant's parameters that
    --spread varies (by name), then the bench's ranges (by their [uncertainty] key). Empty tuples
    when nothing is drawn."""
    varied = [(i, PLANT_VECTOR[i]) for i in range(cfg.plant_spread.shape[0]) if cfg.plant_spread[i] != 0]
    spread = cfg.bench_spread
    out = []
    for r in range(draws.plants.shape[0]):
        row = [(name, float(draws.plants[r, i])) for i, name in varied]
        if spread is not None:
            vals = bench_spread.drawn_values(spread, draws.actuators[r], draws.sensor_gains[r], draws.noise_std[r])
            row += [(k, float(v)) for k, v in zip(spread.keys, vals)]
        out.append(tuple(row))
    return out
