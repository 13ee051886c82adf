"""'Predicted on the bench': the patch simulated in the standard scenarios, for the patch sheet."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numba

from patchgen.bench.engine import SPLIT_FROM
from patchgen.bench.simulate import RunSummary, simulate
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import STANDARD_SCENARIOS, BenchProfile, bench_scenarios
from patchgen.profiles.machine import MachineProfile

STANDARD = STANDARD_SCENARIOS  # every shipped scenario: a bench's default set (profiles.bench.bench_scenarios)


SPLIT_RUNS = 8  # the fewest runs of a part of a small Monte Carlo run on a thread of its own


def _side_by_side(run, runs: int) -> list:
    """``run(first, n)``'s runs first .. first + n - 1 for runs 0 .. runs - 1, a few parts at once on
    the cores when the Monte Carlo is small (20 runs: two of 10); a run depends on its index alone,
    so the list is the one a single call gives."""
    threads = numba.get_num_threads()
    # from SPLIT_FROM runs a thread, the engine's own blocks fill the cores (plan_blocks)
    parts = min(threads, runs // SPLIT_RUNS) if runs < SPLIT_FROM * threads else 1
    if parts <= 1:
        return run(0, runs)
    bounds = [runs * k // parts for k in range(parts + 1)]
    with ThreadPoolExecutor(parts) as pool:
        chunks = list(pool.map(lambda k: run(bounds[k], bounds[k + 1] - bounds[k]), range(parts)))
    return [r for chunk in chunks for r in chunk]


@dataclass(frozen=True)
class Prediction:
    """One standard scenario on the bench: the fraction of runs held, run 0's events, the worst
    figures over the runs and the amplifiers that overloaded."""

    scenario: str
    description: str
    runs: int
    fraction_held: float
    first_trip_s: float | None
    first_fall_s: float | None
    max_theta_deg: float
    max_s_m: float
    overloads: str
    amp_peaks_V: dict[str, float] = field(default_factory=dict)  # each amplifier's largest |output| over the runs


def predict(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
            runs_hold: int = 20, scenarios: tuple[str, ...] | None = None,
            done: dict[str, list[RunSummary]] | None = None, bench_spread: bool = False) -> list[Prediction]:
    """Each standard scenario on the bench (noise and drift as the profiles say), side by side
    on the cores (the engine releases the interpreter).

    The long hold is a small Monte Carlo over noise seeds, the others one run at their own seed.

    Parameters
    ----------
    net, plant, bench, machine : Netlist, PlantParams, BenchProfile, MachineProfile
        The patch and what it runs on.
    runs_hold : int
        Runs of the hold-120s Monte Carlo.
    scenarios : tuple of str, optional
        The scenarios, by name or path (default: the bench's, profiles.bench.bench_scenarios).
    done : dict of str to list of RunSummary, optional
        Runs already simulated on this patch, bench and machine, by scenario name, from the
        scenario's own seed: run i depends on its seed alone, so their first runs stand in for
        simulating again.
    bench_spread : bool
        Each run draws its bench from the profile's ranges (patchgen.bench.bench_spread).

    Returns
    -------
    list of Prediction
        One per scenario, in order.
    """
    runs_of = standard_runs(net, plant, bench, machine, runs_hold, scenarios, done, bench_spread)

    def one(sc: Scenario) -> Prediction:
        name = sc.name
        summaries = runs_of[name]
        runs = len(summaries)
        r0 = summaries[0]
        ovl = sorted({o.amplifier for run in summaries for o in run.overloads})
        return Prediction(name, sc.description, runs, sum(r.held for r in summaries) / runs, r0.trip_time_s,
                          r0.fall_time_s, max(x.max_abs_theta_deg for x in summaries),
                          max(x.max_abs_s_m for x in summaries), ", ".join(ovl) or "none",
                          {a: max(x.amp_peak(a) for x in summaries) for a, _ in r0.amp_peaks_V})

    return [one(sc) for sc in (load_scenario(given) for given in scenarios or bench_scenarios(bench))]


def standard_runs(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
                  runs_hold: int = 20, scenarios: tuple[str, ...] | None = None,
                  done: dict[str, list[RunSummary]] | None = None,
                  bench_spread: bool = False, rails: bool = True) -> dict[str, list[RunSummary]]:
    """The runs :func:`predict` sums up, by scenario name: ``runs_hold`` noise seeds of the long
    hold, one run of each other scenario at its own seed (``done``'s where it has them), side by
    side on the cores (the engine releases the interpreter), the long hold first; with ``rails``
    False, no amplifier clips (patchgen.bench.simulate)."""
    def one(sc: Scenario) -> list[RunSummary]:
        runs = runs_hold if sc.name == "hold-120s" else 1
        if done is not None and len(done.get(sc.name, ())) >= runs:
            return done[sc.name][:runs]
        return _side_by_side(lambda first, n: simulate(net, plant, bench, machine, sc, runs=n, first_run=first,
                                                       keep_history=False, bench_spread=bench_spread,
                                                       rails=rails).runs, runs)

    loaded = [load_scenario(given) for given in scenarios or bench_scenarios(bench)]
    order = sorted(range(len(loaded)), key=lambda i: loaded[i].name != "hold-120s")
    with ThreadPoolExecutor(max(1, min(len(loaded), numba.get_num_threads()))) as pool:
        futures = {i: pool.submit(one, loaded[i]) for i in order}
        return {loaded[i].name: futures[i].result() for i in range(len(loaded))}
