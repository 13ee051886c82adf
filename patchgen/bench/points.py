"""The patch at chosen points of the bench's ranges, every point with the same seeds, all in one
batch of the engine.

A study of the bench's uncertainty asks how a patch does at many points of the box of ranges (its
corners, the ends of each range, the points a search visits). Simulating each point as a bench
of its own costs one engine call per point, each at most one block of runs, on one core. Here
every (point, run) pair is one run of a single batch: run i of every point draws exactly what run
i of a plain Monte Carlo of the scenario draws (drift signs, the key of its noise), and then its
bench is set to the point's values in its own rows of the engine's arrays, where a run of
``simulate(..., bench_spread=True)`` would draw them (patchgen.bench.bench_spread). So points
differ by their bench alone (common random numbers), and the blocks run on every core.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from patchgen.bench import bench_spread, budget
from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config, harmless_overloads
from patchgen.bench.engine import default_step, draw_batch, run_batch
from patchgen.bench.engine import drawn as engine_drawn
from patchgen.bench.kernel import Draws
from patchgen.bench.results import RunSummary, run_summaries
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile


def simulate_points(netlist: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
                    scenario: Scenario, points: Sequence[dict[str, float]], *, runs: int,
                    seed: int | None = None, ideal: bool = False) -> list[list[RunSummary]]:
    """``runs`` runs of the scenario at each point of the bench's ranges, in one batch.

    Parameters
    ----------
    netlist : Netlist
        The patch, simulated as wired.
    plant : PlantParams
        The nominal plant.
    bench, machine : BenchProfile, MachineProfile
        The bench with its ``[uncertainty]`` ranges, and the machine.
    scenario : Scenario
        What happens.
    points : sequence of dict
        Each a range key -> value (keys the simulation feels, patchgen.bench.bench_spread.active_ranges);
        a key not given stays at the profile's value.
    runs : int
        Runs per point: run i of every point has run i's seed.
    seed : int, optional
        The base seed (default: the scenario's).
    ideal : bool
        Every imperfection off.

    Returns
    -------
    list of list of RunSummary
        Per point, its runs numbered 0 .. runs - 1.
    """
    if runs < 1 or not points:
        raise ValueError(f"need at least one point and one run (got {len(points)} points, {runs} runs)")
    circuit = compile_circuit(netlist, machine, bench)
    base_seed = scenario.seed if seed is None else seed
    cfg, _ = engine_config(circuit, plant, bench, machine, scenario, ideal=ideal, bench_spread=True)
    spread = cfg.bench_spread
    keys = set() if spread is None else set(spread.keys)
    unknown = sorted({k for p in points for k in p} - keys)
    if unknown:
        raise ValueError(f"{', '.join(unknown)}: not a range this simulation feels (it feels {sorted(keys)})")
    budget.check(scenario, runs * len(points), step=cfg.settings.dt, stride=cfg.settings.stride, history=False,
                 usual_step=default_step([], ideal))
    plain = replace(cfg, bench_spread=None)  # each run's draws without a bench draw: run i's own
    one = draw_batch(plain, [np.random.default_rng([base_seed, i]) for i in range(runs)])
    draws = Draws(*(np.tile(a, (len(points),) + (1,) * (a.ndim - 1)) for a in one))
    for j, point in enumerate(points):
        for r in range(j * runs, (j + 1) * runs):
            bench_spread.apply_values(spread, point, draws.actuators[r], draws.sensor_gains[r], draws.noise_std[r])
    out = run_batch(plain, draws, 0)
    summaries = run_summaries([out], circuit.amp_ids, 0, engine_drawn(cfg, draws), harmless_overloads(circuit, cfg))
    return [[replace(s, run=i) for i, s in enumerate(summaries[j * runs:(j + 1) * runs])] for j in range(len(points))]
