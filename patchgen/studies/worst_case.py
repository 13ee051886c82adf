"""The worst point of the box of the bench's ranges, searched for, not enumerated.

A box of k ranges has 2^k corners: 8 for the three ranges of a bench stated by hand, 512 for the
nine that patchgen identify writes. Every corner at 64 seeds is an hour on two cores at nine; so
past EXACT_RANGES ranges the worst corner is searched for, at a cost that grows with k, not 2^k:

1. **Screen.** The linearised wired loop on the bench (patchgen.bench.diagnosis) is cheap (a
   fraction of a millisecond), so its rightmost pole is computed at every corner of the ranges it
   feels (the actuator's gain and lag, the sensor constants), and then moved inside the box by an
   optimiser (Powell's method, bounded) from the least damped corner. The point least damped
   joins the screen, with each end of each range (the others at the profile's values), all run
   SCREEN_RUNS seeds in one batch (patchgen.bench.points: every point the same seeds).
2. **Descend over the corners.** From the corner that puts each range at its harsher end (the end
   whose runs held fewer, or took the pendulum and cart further), every corner one range away is
   run; the search moves to the harshest while it is harsher, at most MAX_MOVES times.
3. **Confirm.** The CONFIRMED harshest corners seen are run at the study's full seeds; the worst
   of them is the study's worst corner.

*Harsher* (``severity``): fewer runs held, then a larger 95th percentile of the run's excursion,
the larger of max |s| over the half track and max |theta| over the fall angle. Run i of every
point draws the same noise, so two points differ by their bench alone.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence

import numpy as np

from patchgen.bench.diagnosis import diagnose
from patchgen.bench.points import simulate_points
from patchgen.bench.results import RunSummary
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.uncertainty import bench_at

EXACT_RANGES = 3  # up to this many ranges, every corner is run (8 corners)
SCREEN_RUNS = 16  # seeds of each point screened or visited by the descent
MAX_MOVES = 3  # steps of the descent over the corners
CONFIRMED = 3  # the harshest corners seen, run again at the study's seeds
LINEAR_KEYS = ("K_U", "tau", "sensors.s", "sensors.theta", "sensors.s_dot")  # what the linear loop feels


def severity(runs: Sequence[RunSummary], half_track_m: float, fall_deg: float) -> tuple[float, float]:
    """How harsh a point was: (the fraction of runs not held, the 95th percentile of each run's
    excursion, max |s| over the half track or max |theta| over the fall angle, the larger)."""
    held = sum(r.held and not r.overloads for r in runs)
    reach = [max(r.max_abs_s_m / half_track_m, r.max_abs_theta_deg / fall_deg) for r in runs]
    return 1.0 - held / len(runs), float(np.percentile(reach, 95))


def least_damped(net: Netlist, plant: PlantParams, bench: BenchProfile,
                 ranges: dict[str, tuple[float, float]]) -> dict[str, float] | None:
    """The point of the linear ranges where the wired loop on the bench is least damped (its
    rightmost pole furthest right): the worst corner, then an optimiser inside the box from it.
    None when no range moves the linear loop."""
    keys = [k for k in ranges if k in LINEAR_KEYS]
    if not keys:
        return None

    def rightmost(values) -> float:
        return float(diagnose(net, plant, bench_at(bench, dict(zip(keys, values))))[-1].worst.real)

    from scipy.optimize import minimize  # here, not at import: most benches have no ranges to search

    corners = list(itertools.product(*(ranges[k] for k in keys)))  # at most 2^5
    start = max(corners, key=rightmost)
    lo, hi = np.array([ranges[k][0] for k in keys]), np.array([ranges[k][1] for k in keys])
    scale = np.where(hi > lo, hi - lo, 1.0)
    found = minimize(lambda z: -rightmost(lo + z * scale), (np.array(start) - lo) / scale, method="Powell",
                     bounds=[(0.0, 1.0)] * len(keys), options={"xtol": 1e-3, "ftol": 1e-9, "maxfev": 200})
    best = lo + np.clip(found.x, 0.0, 1.0) * scale
    point = best if rightmost(best) > rightmost(start) else np.array(start)
    return {k: float(v) for k, v in zip(keys, point)}


def search(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile, scenario: Scenario,
           ranges: dict[str, tuple[float, float]], *, seed: int | None, corner_runs: int, ideal: bool = False,
           progress: Callable[[int, int], None] | None = None) -> tuple[list[tuple[dict, list[RunSummary]]],
                                                                        list[tuple[dict, list[RunSummary]]], int]:
    """The worst corner of the box, searched for (see the module docstring).

    Parameters
    ----------
    net, plant, bench, machine, scenario
        The patch, the nominal plant, the bench with its ranges, the machine, the scenario.
    ranges : dict of str to (float, float)
        The ranges the simulation feels.
    seed : int, optional
        The base seed (default: the scenario's).
    corner_runs : int
        Seeds of each confirmed corner.
    ideal : bool
        Every imperfection off.
    progress : callable, optional
        ``progress(done, total)`` after each batch (total: the most batches the search can take).

    Returns
    -------
    confirmed : list of (dict, list of RunSummary)
        The harshest corners seen, each run at ``corner_runs`` seeds.
    ends : list of (dict, list of RunSummary)
        Each end of each range, the others at the profile's values, at SCREEN_RUNS seeds.
    screened : int
        The points run at SCREEN_RUNS seeds (ends, the least damped point, the descent's corners).
    """
    half, fall = plant.d / 2.0, scenario.fall_angle_deg
    total, batches = 2 + MAX_MOVES, 0

    def run(points: list[dict], runs: int) -> list[list[RunSummary]]:
        nonlocal batches
        out = simulate_points(net, plant, bench, machine, scenario, points, runs=runs, seed=seed, ideal=ideal)
        batches += 1
        if progress is not None:
            progress(batches, total)
        return out

    keys = list(ranges)
    ends = [{k: v} for k in keys for v in ranges[k]]
    damped = least_damped(net, plant, bench, ranges)
    screen = ends + ([damped] if damped is not None else [])
    seen: dict[tuple, tuple[float, float]] = {}
    first = run(screen, SCREEN_RUNS)
    harsh = {k: 0 for k in keys}  # the harsher end of each range: 0 low, 1 high
    for i, k in enumerate(keys):
        low, high = (severity(first[2 * i + e], half, fall) for e in (0, 1))
        harsh[k] = 1 if high > low or (high == low and damped is not None and k in damped
                                       and damped[k] >= sum(ranges[k]) / 2) else 0

    def corner(bits: tuple[int, ...]) -> dict[str, float]:
        return {k: ranges[k][b] for k, b in zip(keys, bits)}

    here = tuple(harsh[k] for k in keys)
    for _ in range(MAX_MOVES):
        near = [here] + [here[:i] + (1 - here[i],) + here[i + 1:] for i in range(len(keys))]
        fresh = [b for b in near if b not in seen]
        for b, runs in zip(fresh, run([corner(b) for b in fresh], SCREEN_RUNS) if fresh else []):
            seen[b] = severity(runs, half, fall)
        step = max(near, key=lambda b: seen[b])  # ties: stay
        if seen[step] <= seen[here]:
            break
        here = step
    # the harshest points seen, corners or not (an end, or the least damped point, may be harsher)
    points = [(corner(b), v) for b, v in seen.items()] + [(p, severity(r, half, fall)) for p, r in zip(screen, first)]
    top = [p for p, _ in sorted(points, key=lambda pv: pv[1], reverse=True)[:CONFIRMED]]
    confirmed = run(top, corner_runs)
    if progress is not None:
        progress(total, total)
    return (list(zip(top, confirmed)),
            [(e, r) for e, r in zip(ends, first[:len(ends)])], len(screen) + len(seen))
