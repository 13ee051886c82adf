"""What a simulation would cost, estimated before anything is allocated, and the bounds it must keep.

A scenario's duration over the step gives the steps of one run; times the runs, the work; the
noise drawn ahead for a batch of runs (steps x channels x 4 bytes per run, two batches alive)
and the first run's history (steps / stride samples) give the memory. Past a bound the command
is refused at once, naming the field that made it absurd, instead of running for days or
asking the machine for a hundred gigabytes. docs/simulation.md states the bounds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import InputError
from .scenario import Scenario

MAX_RUN_STEPS = 10**10  # steps x runs: about an hour at a few million steps per second on two cores
MAX_MEMORY_BYTES = 2 * 2**30  # noise drawn ahead for the batches in flight
MAX_HISTORY_SAMPLES = 10**6  # the first run's history (a CSV of some 100 MB, and its plot)
BATCH_NOISE_BYTES = 64 * 2**20  # as patchgen.simulate batches its runs
NOISE_BYTES = 4  # float32 normals


@dataclass(frozen=True)
class Cost:
    """One simulation command's size: steps per run, steps over all runs, bytes, history samples."""

    steps: int
    run_steps: int
    memory_bytes: int
    history_samples: int


def estimate(steps: int, runs: int, channels: int, stride: int, noisy: bool, history: bool,
             threads: int) -> Cost:
    """The cost of ``runs`` runs of ``steps`` steps (batched as patchgen.simulate does)."""
    per_run = (steps + 1) * channels * NOISE_BYTES if noisy else 0
    chunk = max(2 * threads, min(math.ceil(runs / 20), BATCH_NOISE_BYTES // max(per_run, 1)))
    batch = min(chunk, runs)
    in_flight = min(2, math.ceil(runs / batch))
    return Cost(steps, steps * runs, in_flight * batch * per_run, steps // stride + 1 if history else 0)


def check(scenario: Scenario, runs: int, *, step: float, stride: int, channels: int, noisy: bool,
          history: bool, threads: int, usual_step: float) -> Cost:
    """Refuse a simulation past the bounds; the error names the scenario field (or --runs) at fault:
    dt_s when the scenario asks for a step finer than ``usual_step`` (the engine's own), else
    duration_s."""
    steps = max(1, math.ceil(scenario.duration_s / step - 1e-9))
    cost = estimate(steps, runs, channels, stride, noisy, history, threads)
    one = estimate(steps, 1, channels, stride, noisy, history, threads)
    fine = scenario.dt_s is not None and scenario.dt_s < usual_step
    length = "dt_s" if fine else "duration_s"
    at = f"{steps:.3g} steps of {step:.3g} s"
    if one.run_steps > MAX_RUN_STEPS or one.memory_bytes > MAX_MEMORY_BYTES:
        raise InputError(scenario.path, length, f"one run would take {at} and {_gib(one.memory_bytes)} of noise; "
                         f"at most {MAX_RUN_STEPS:.0e} steps and {_gib(MAX_MEMORY_BYTES)} are allowed "
                         "(see docs/simulation.md)")
    if cost.run_steps > MAX_RUN_STEPS or cost.memory_bytes > MAX_MEMORY_BYTES:
        raise InputError("--runs", "", f"{runs} runs of {at} would take {cost.run_steps:.3g} steps and "
                         f"{_gib(cost.memory_bytes)}; at most {MAX_RUN_STEPS:.0e} steps and "
                         f"{_gib(MAX_MEMORY_BYTES)} are allowed (fewer runs; see docs/simulation.md)")
    if cost.history_samples > MAX_HISTORY_SAMPLES:
        raise InputError(scenario.path, "record_dt_s", f"the history would keep {cost.history_samples:.3g} samples "
                         f"(duration_s / record_dt_s); at most {MAX_HISTORY_SAMPLES:.0e} (a coarser record_dt_s "
                         "or a shorter duration_s)")
    return cost


def _gib(n: int) -> str:
    return f"{n / 2**30:.3g} GiB"
