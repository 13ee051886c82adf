"""Noise in a SPICE deck: white-noise sources from the deck's seeded generator, and the one table
an XSPICE filesource plays them from (patchgen.spice.deck writes the rest of the deck)."""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import lfilter

from patchgen.bench.engine import noise_process
from patchgen.bench.noise_drift import NoiseAndDrift
from patchgen.spice.elements import DeckLines

NOISE_NAME = "patch.noise"


def noise_source(d: DeckLines, name: str, plus: str, minus: str, rms: float, bandwidth_Hz: float,
                 duration_s: float, step_s: float = 0.0) -> None:
    """Noise of the given rms over ``bandwidth_Hz`` as a voltage source ``name`` (an E element)
    in series between ``minus`` and ``plus``, its samples joined linearly.

    With ``step_s`` 0, white samples of that rms at twice the bandwidth (an ideal-free deck that
    stands alone). With ``step_s`` the step of patchgen's engine, the engine's own noise process
    at that step (patchgen.bench.engine.noise_process: n' = a n + std w, the same low-frequency
    density rms^2 / B, no band above the step's Nyquist frequency), so ngspice's run has the
    statistics of the Monte Carlo it is judged against; measured on a 20 s hold, samples at twice
    each band instead put ngspice's RMS theta 1 to 3 of the Monte Carlo's 5-95 % widths higher
    (the sensors' noise, differentiated, dithers the actuator's dead zone differently).

    The samples come from the deck's seeded generator (ngspice's TRNOISE cannot be seeded
    reproducibly in batch mode) and are played from the noise table by one XSPICE filesource (a
    PWL source of this length is quadratically slow)."""
    if step_s > 0:
        a, std = noise_process(rms, bandwidth_Hz, step_s)
        n = int(math.ceil(duration_s / step_s)) + 1
        w = d.rng.normal(0.0, 1.0, n)
        w[0] *= std / math.sqrt(1.0 - a * a)  # started in its stationary state
        w[1:] *= std
        d.noise.append((f"nz_{len(d.noise)}", step_s, lfilter([1.0], [1.0, -a], w)))
    else:
        dt = 0.5 / bandwidth_Hz
        n = int(math.ceil(duration_s / dt)) + 1
        d.noise.append((f"nz_{len(d.noise)}", dt, d.rng.normal(0.0, rms, n)))
    d.add(f"{name} {plus} {minus} {d.noise[-1][0]} 0 1")


def random_forces(d: DeckLines, push: dict[str, str], levels: NoiseAndDrift, duration_s: float,
                  step_s: float = 0.0) -> dict[str, str]:
    """The bench's random forces on the cart and at the tip (patchgen.bench.noise_drift), as noise
    sources added to the scenario's pushes."""
    out = dict(push)
    for key, rms in (("cart", levels.cart_force_N_rms), ("tip", levels.tip_force_N_rms)):
        if rms > 0:
            d.comment(f"Random force on the {key}: {rms:g} N rms to {levels.force_bandwidth_Hz:g} Hz")
            noise_source(d, f"E_force_{key}_noise", f"fz_{key}", "0", rms, levels.force_bandwidth_Hz, duration_s,
                         step_s)
            out[key] = "+".join(p for p in (push[key], f"v(fz_{key})") if p)
    return out


def noise_table(d: DeckLines, duration_s: float) -> tuple[str, float]:
    """The noise samples of every source on one time grid (the finest), and that grid's step.
    Rows are formatted a block at a time (one % per block: half the time of a join per row,
    the same text)."""
    dt = min(step for _, step, _ in d.noise)
    t = np.arange(int(math.ceil(duration_s / dt)) + 1) * dt
    table = np.column_stack([t] + [np.interp(t, np.arange(len(v)) * step, v) for _, step, v in d.noise])
    row = "%.9g" + " %.6g" * len(d.noise) + "\n"
    block = 4096
    return "".join((row * len(b)) % tuple(b.ravel().tolist())
                   for b in (table[i:i + block] for i in range(0, len(table), block))), dt


def play_noise(d: DeckLines, seed: int, duration_s: float) -> tuple[dict[str, str], float]:
    """The filesource that plays every noise source's samples, and a 1 Mohm load on each of its
    outputs. Returns the noise table by file name and its time step (no table and an infinite
    step when the deck has no noise)."""
    if not d.noise:
        return {}, math.inf
    table, dt = noise_table(d, duration_s)
    nodes = " ".join(name for name, _, _ in d.noise)
    ones = " ".join("1" for _ in d.noise)
    zeros = " ".join("0" for _ in d.noise)
    d.comment(f"Noise samples (seed {seed}), one column per source, from {NOISE_NAME}")
    d.add(f"A_noise [{nodes}] noise_table",
          f'.model noise_table filesource (file="{NOISE_NAME}" amploffset=[{zeros}] '
          f"amplscale=[{ones}] timeoffset=0 timescale=1 timerelative=false amplstep=false)")
    d.add(*(f"R_{name} {name} 0 1e6" for name, _, _ in d.noise))
    return {NOISE_NAME: table}, dt
