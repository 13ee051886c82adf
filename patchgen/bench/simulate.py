"""Simulate a patched circuit on the bench: the netlist as wired, the nonlinear plant, the real
actuator, sensors and track, and the machine's imperfections; one run or a Monte Carlo.

``ideal=True`` turns every imperfection off and keeps what is wired and what is physical:

- off: sensor noise, amplifier output noise, integrator drift, amplifier saturation (outputs are
  unbounded, but an output that would leave +/- saturation_V is still recorded as an overload),
  the actuator's lag, zero, dead zone and force limit (the actuator is the pure gain K_U of the
  bench);
- kept: the nonlinear plant (eq. 2.16-2.19), every pot setting as dialled (quantised), the x1/x10
  weights and inversions, the differentiator's roll-off as wired (a pure differentiator cannot
  be patched, nor simulated), integrator initial conditions, the track's limit switches (the track
  is not an imperfection) and the scenario's disturbances.

So for small angles an ideal run is the linear closed loop of the netlist's realised coefficients
with the differentiator's roll-off (tests/bench/test_simulate.py checks this).

The pieces: patchgen.bench.configure resolves the inputs into the engine's records,
patchgen.bench.engine runs them, patchgen.bench.results summarises the runs, and
patchgen.render.simulation_files renders the result's files as bytes for patchgen.render.outputs.write_files.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numba
import numpy as np

from patchgen.bench import budget
from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config, harmless_overloads
from patchgen.bench.engine import LANES, default_step, draw_batch, run_batch
from patchgen.bench.engine import drawn as engine_drawn
from patchgen.bench.kernel import HISTORY_CHANNELS
from patchgen.bench.results import RunSummary, SimResult, distribution, run_summaries
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import CART, PlantModel, model_of
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

__all__ = ["RunSummary", "SimResult", "simulate"]


def history_channels(pm: PlantModel) -> tuple[str, ...]:
    """The history's channels (the kernel's HISTORY_CHANNELS) by the plant's names: time, its
    states, its position's reference (s_ref), the command and the plant's input (the cart's force;
    a rotary arm's motor voltage, V_m)."""
    if pm is CART:
        return HISTORY_CHANNELS
    return ("t",) + pm.state_names + (f"{pm.position}_ref", "u_c", pm.input)


def simulate(netlist: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
             scenario: Scenario, *, seed: int | None = None, runs: int = 1, ideal: bool = False,
             keep_history: bool = True,
             progress: Callable[[int], None] | None = None,
             spread: dict[str, float] | None = None, first_run: int = 0,
             bench_spread: bool = False, rails: bool = True) -> SimResult:
    """Simulate ``runs`` runs of the scenario (seed from the argument, else the scenario's).

    Run i draws from ``numpy.random.default_rng([seed, i])`` (drift signs, the key of its
    counter-based noise, its plant), so run 0 of a Monte Carlo is the single run of the same seed,
    and a Monte Carlo may be continued: ``first_run`` = k runs i = k, k + 1, ...

    Parameters
    ----------
    netlist : Netlist
        The patch, simulated as wired.
    plant : PlantParams
        The nominal plant.
    bench, machine : BenchProfile, MachineProfile
        The bench (actuator, sensors, track) and the machine (imperfections).
    scenario : Scenario
        What happens, for how long, with which noise and drift.
    seed : int, optional
        The Monte Carlo's seed (default: the scenario's).
    runs : int
        Runs of the Monte Carlo.
    ideal : bool
        Every imperfection off (see the module docstring).
    keep_history : bool
        Keep the first run's time histories.
    progress : callable, optional
        Called with the number of runs done after each batch.
    spread : dict of str to float, optional
        E.g. {"M": 0.1, "l": 0.1}: each run draws these plant parameters uniformly within those
        fractions of the nominal, so the Monte Carlo covers model error as well as noise.
    first_run : int
        The index of the first run (its draws, see above); the history is that run's.
    bench_spread : bool
        Each run draws its bench (actuator, sensor constants, noise levels, random forces) from
        the profile's ``[uncertainty]`` ranges (patchgen.bench.bench_spread), after its other draws.
    rails : bool
        False: no amplifier clips at its rails, every other imperfection kept (a scaling's envelope).

    Returns
    -------
    SimResult
        The runs' summaries, their distribution, the settings and the first run's history.
    """
    if runs < 1:  # a caller's mistake: the command line's options and the scenario's fields are bounded
        raise ValueError(f"runs must be at least 1 (got {runs})")
    circuit = compile_circuit(netlist, machine, bench)
    base_seed = scenario.seed if seed is None else seed
    if not 0 <= base_seed < 2**63:
        raise ValueError(f"seed must be between 0 and 2**63 - 1 (got {base_seed})")
    if first_run < 0:
        raise ValueError(f"first_run must be at least 0 (got {first_run})")
    cfg, settings = engine_config(circuit, plant, bench, machine, scenario, ideal=ideal, spread=spread,
                                  bench_spread=bench_spread, rails=rails)
    budget.check(scenario, runs, step=cfg.settings.dt, stride=cfg.settings.stride, history=keep_history,
                 usual_step=default_step([], ideal))

    # batches of runs, for the progress calls: whole blocks, enough of them for the threads
    per_call = LANES * numba.get_num_threads()
    chunk = per_call * max(1, math.ceil(runs / 20 / per_call))
    parts, drawn = [], []
    for start in range(0, runs, chunk):
        stop = min(start + chunk, runs)
        draws = draw_batch(cfg, [np.random.default_rng([base_seed, first_run + i]) for i in range(start, stop)])
        parts.append(run_batch(cfg, draws, 1 if keep_history and start == 0 else 0))
        drawn += engine_drawn(cfg, draws)
        if progress is not None:
            progress(stop)

    summaries = run_summaries(parts, circuit.amp_ids, first_run, drawn, harmless_overloads(circuit, cfg))
    history = None
    if keep_history:
        h = parts[0].history[0, :parts[0].history_length[0]]
        names = history_channels(model_of(plant)) + circuit.amp_ids
        history = {name: h[:, k].copy() for k, name in enumerate(names)}
    return SimResult(
        design=netlist.design, scenario=scenario, machine=machine.id, bench=bench.id, ideal=ideal,
        seed=base_seed, settings=settings, amplifiers=circuit.amp_ids, history=history,
        runs=summaries, distribution=distribution(summaries, circuit.amp_ids),
        carries={a.id: (a.carries.polarity, a.carries.quantity) for a in netlist.amplifiers},
    )
