"""What a simulation would cost, estimated before anything is allocated, and the bounds it must keep.

A scenario's duration over the step gives the steps of one run; times the runs, the work. The
engine draws its noise inside the compiled loop (counter-based, nothing drawn ahead), so what a
run keeps in memory is its summary and, for the first run, its history (steps / stride
samples). Past a bound the command is refused at once, naming the field that made it absurd,
instead of running for days or filling the disk with a history. docs/simulation.md states the
bounds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario

MAX_RUN_STEPS = 10**10  # steps x runs: about half an hour at the engine's ~80 ns per run-step on two cores
MAX_HISTORY_SAMPLES = 10**6  # the first run's history (a CSV of some 100 MB, and its plot)


@dataclass(frozen=True)
class Cost:
    """One simulation's size: steps per run, steps over all runs, samples of the first run's history."""

    steps: int
    run_steps: int
    history_samples: int


def estimate(steps: int, runs: int, stride: int, history: bool) -> Cost:
    """The cost of ``runs`` runs of ``steps`` steps, the first recorded every ``stride`` steps.

    Parameters
    ----------
    steps, runs : int
        Steps of one run, and runs.
    stride : int
        Steps between two history samples.
    history : bool
        Whether the first run keeps its history.

    Returns
    -------
    Cost
        Steps per run, over all runs, and history samples.
    """
    return Cost(steps, steps * runs, steps // stride + 1 if history else 0)


def check(scenario: Scenario, runs: int, *, step: float, stride: int, history: bool, usual_step: float) -> Cost:
    """Refuse a simulation past the bounds, before anything is allocated.

    The error names the scenario field (or --runs) at fault: dt_s when the scenario asks for a
    step finer than ``usual_step`` (the engine's own), else duration_s; record_dt_s for a history
    too long.

    Parameters
    ----------
    scenario : Scenario
        Its duration, step and path (for the message).
    runs : int
        Runs of the Monte Carlo.
    step : float
        The step the engine will take (s).
    stride : int
        Steps between two history samples.
    history : bool
        Whether the first run keeps its history.
    usual_step : float
        The engine's own step (s), to tell a scenario's fine step from a long duration.

    Returns
    -------
    Cost
        The simulation's size, within the bounds.

    Raises
    ------
    InputError
        Past MAX_RUN_STEPS or MAX_HISTORY_SAMPLES.
    """
    steps = max(1, math.ceil(scenario.duration_s / step - 1e-9))
    cost = estimate(steps, runs, stride, history)
    fine = scenario.dt_s is not None and scenario.dt_s < usual_step
    length = "dt_s" if fine else "duration_s"
    at = f"{steps:.3g} steps of {step:.3g} s"
    if steps > MAX_RUN_STEPS:
        raise InputError(scenario.path, length, f"one run would take {at}; at most {MAX_RUN_STEPS:.0e} steps "
                         "are allowed (see docs/simulation.md)")
    if cost.run_steps > MAX_RUN_STEPS:
        raise InputError("runs", "", f"{runs} runs of {at} would take {cost.run_steps:.3g} steps; at most "
                         f"{MAX_RUN_STEPS:.0e} are allowed (fewer runs; see docs/simulation.md)")
    if cost.history_samples > MAX_HISTORY_SAMPLES:
        raise InputError(scenario.path, "record_dt_s", f"the history would keep {cost.history_samples:.3g} samples "
                         f"(duration_s / record_dt_s); at most {MAX_HISTORY_SAMPLES:.0e} (a coarser record_dt_s "
                         "or a shorter duration_s)")
    return cost
