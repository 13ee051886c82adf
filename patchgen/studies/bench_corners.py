"""A patch over the bench's uncertainty: the held fraction over runs whose bench is drawn from the
profile's ranges, every corner of the box of ranges, the worst corner, and the parameter whose end
hurts most.

A run *holds* as recommend counts it (patchgen.studies.ranking.outcome): up, inside the switches
and no amplifier past the rails for the whole scenario. Every corner and every end runs the same
seeds (run i of the Monte Carlo's seed), so corners differ by the bench alone.

A box of k ranges has 2^k corners: up to patchgen.studies.worst_case.EXACT_RANGES ranges every
corner is run; past that the worst corner is searched for (patchgen.studies.worst_case), every
range taking part, and the study says how many points it screened. Points run together go to the
engine as one batch (patchgen.bench.points), on every core.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, replace

import numba
import numpy as np

from patchgen.bench.bench_spread import active_ranges
from patchgen.bench.points import simulate_points
from patchgen.bench.results import RunSummary
from patchgen.bench.simulate import SimResult
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.uncertainty import nominal
from patchgen.studies import worst_case
from patchgen.studies.ranking import ScenarioOutcome, outcome

MAX_CORNER_PARAMETERS = 6  # 64 corners: corner_values's cap (the study itself searches past EXACT_RANGES)
CORNERS_A_CORE = 2  # corners run at once per core by a study in steps (see study_in_steps)


@dataclass(frozen=True)
class CornerOutcome:
    """The runs at one corner (or one end of one range): the values set, and how many held."""

    values: dict[str, float]
    outcome: ScenarioOutcome

    def as_dict(self) -> dict:
        """Plain JSON-ready values."""
        d = self.outcome.as_dict()
        d.pop("scenario")
        return {"values": dict(self.values), **d}

    def label(self) -> str:
        """``tau 0.3, dead_zone_V 0.4``."""
        return ", ".join(f"{k} {v:g}" for k, v in self.values.items())

    def held_text(self) -> str:
        """``64/64 (100.0 %)`` at ``label()``."""
        o = self.outcome
        return f"{o.held}/{o.runs} ({100 * o.fraction:.1f} %) at {self.label()}"


@dataclass(frozen=True)
class BenchStudy:
    """A patch over the bench's ranges in one scenario: the drawn Monte Carlo, each corner, and
    (when asked for) each end of each range with the others at the profile's values."""

    scenario: str
    ranges: dict[str, tuple[float, float]]
    distribution: str
    drawn: ScenarioOutcome | None
    corners: tuple[CornerOutcome, ...]
    at_nominal: tuple[str, ...]  # ranges left at the profile's value in the corners (past the cap)
    ends: tuple[CornerOutcome, ...] = ()
    screened: int = 0  # points screened by the search for the worst corner (0: every corner run)

    def how(self) -> str:
        """How the corners were chosen, in words: every corner, or the search and its cost."""
        if not self.screened:
            return f"every corner of the ranges in {self.scenario}"
        runs = self.corners[0].outcome.runs if self.corners else 0
        return (f"the corners of the ranges in {self.scenario}, the worst searched for ({self.screened} points "
                f"screened with {worst_case.SCREEN_RUNS} seeds each, the {len(self.corners)} harshest run again "
                f"with {runs})")

    @property
    def worst_corner(self) -> CornerOutcome | None:
        """The corner held least (ties: the lower interval top, then the one that takes the cart
        furthest, by the 95th percentile of max |s|, then the first)."""
        return min(self.corners, key=lambda c: (c.outcome.fraction, c.outcome.interval[1], -cart_excursion(c)),
                   default=None)

    @property
    def weakest_parameter(self) -> CornerOutcome | None:
        """The end of a range, the others at the profile's values, held least (ties: the one that
        takes the cart furthest, by the 95th percentile of max |s|; then the first); None: no ends run."""
        return min(self.ends, key=lambda c: (c.outcome.fraction, c.outcome.interval[1], -cart_excursion(c)),
                   default=None)

    def as_dict(self) -> dict:
        """Plain JSON-ready values."""
        w, p = self.worst_corner, self.weakest_parameter
        return {"scenario": self.scenario, "ranges": {k: list(v) for k, v in self.ranges.items()},
                "distribution": self.distribution, "drawn": None if self.drawn is None else self.drawn.as_dict(),
                "corners": [c.as_dict() for c in self.corners], "corners_at_nominal": list(self.at_nominal),
                "worst_corner": None if w is None else w.as_dict(),
                "ends": [c.as_dict() for c in self.ends],
                "weakest_parameter": None if p is None else p.as_dict(),
                "searched": {"screened": self.screened, "screen_runs": worst_case.SCREEN_RUNS} if self.screened
                else None}


def cart_excursion(c: CornerOutcome) -> float:
    """The 95th percentile over the runs of max |s| (m): how near the switches the cart came."""
    return float(np.percentile([r.max_abs_s_m for r in c.outcome.results], 95)) if c.outcome.results else 0.0


def corner_values(bench: BenchProfile, ranges: dict[str, tuple[float, float]],
                  cap: int = MAX_CORNER_PARAMETERS) -> tuple[list[dict[str, float]], tuple[str, ...]]:
    """Every corner of the box (low ends first, the first range slowest), and the ranges past
    ``cap`` left at the profile's value (the narrowest relative to their nominal value)."""
    def width(k):
        lo, hi = ranges[k]
        return (hi - lo) / max(abs(nominal(bench, k)), 1e-300)

    keep = sorted(ranges, key=lambda k: -width(k))[:cap]
    keys = [k for k in ranges if k in keep]
    rest = tuple(k for k in ranges if k not in keep)
    return [dict(zip(keys, ends)) for ends in itertools.product(*(ranges[k] for k in keys))], rest


def _worst_swing(runs: Sequence[RunSummary], saturation_V: float) -> float:
    """The largest |u_c| of the runs (the rails when any overloaded)."""
    swing = max([0.0] + [r.max_abs_u_c_V for r in runs])
    return saturation_V if any(r.overloads for r in runs) else swing


def study(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile, scenario: Scenario,
          *, seed: int | None = None, corner_runs: int, drawn: SimResult | None = None, ends: bool = False,
          ideal: bool = False, known: Sequence[CornerOutcome] = (),
          progress: Callable[[int, int], None] | None = None) -> BenchStudy:
    """The patch at every corner of the bench's ranges (and each end of each range, if asked).

    Parameters
    ----------
    net : Netlist
        The patch.
    plant : PlantParams
        The nominal plant.
    bench, machine : BenchProfile, MachineProfile
        The bench with its ``[uncertainty]`` ranges, and the machine.
    scenario : Scenario
        The scenario.
    seed : int, optional
        The Monte Carlo's seed (default: the scenario's).
    corner_runs : int
        Runs at each corner and each end.
    drawn : SimResult, optional
        The Monte Carlo over drawn benches (``simulate(..., bench_spread=True)``), counted here.
    ends : bool
        Also run each end of each range, the others at the profile's values (the weakest parameter).
    ideal : bool
        Every imperfection off (only the ranges an ideal run feels).
    known : sequence of CornerOutcome, optional
        Corners already run with these very inputs (the same patch, plant, bench, machine,
        scenario, seed, runs and mode: the robust search's): taken as they are, not run again.
    progress : callable, optional
        ``progress(done, total)`` after the corners and after the ends.

    Returns
    -------
    BenchStudy
    """
    box = _Box(net, plant, bench, machine, scenario, seed, corner_runs, ideal)
    counted = None if drawn is None else outcome(scenario.name, drawn.runs, box.worst_swing(drawn.runs))
    if box.searched:
        return replace(box.search(progress, ends), drawn=counted)
    singles = [{k: v} for k, r in box.ranges.items() for v in r] if ends else []
    total = len(box.corners) + len(singles)
    corners = box.batch(box.corners, known)  # every corner at once
    if progress is not None:
        progress(len(corners), total)
    done_ends = box.batch(singles, known)
    if progress is not None and singles:
        progress(total, total)
    return BenchStudy(scenario.name, box.ranges, bench.uncertainty.distribution, counted, tuple(corners), box.rest,
                      tuple(done_ends))


def study_in_steps(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
                   scenario: Scenario, *, seed: int | None = None, corner_runs: int,
                   ideal: bool = False) -> Iterator[tuple[BenchStudy, bool]]:
    """The corners of :func:`study` (no ends, no drawn runs) a few at a time, in the box's order:
    each step yields the study so far and whether it is whole (the last step's: the same as
    :func:`study`'s).

    A search that can drop a patch on its first corners (patchgen.studies.robust) asks for the next
    step only while it needs it. A step runs CORNERS_A_CORE corners a core at once: the robust
    search's corners of 64 runs then fill blocks of 128 (an engine run-step costs less in a full
    block than the corner a dropped patch computes for nothing: recommend over uw-1991-uncertain
    15.7 s against 16.4 a corner at a time). Past worst_case.EXACT_RANGES ranges the searched
    study is one step.
    """
    box = _Box(net, plant, bench, machine, scenario, seed, corner_runs, ideal)
    if box.searched:
        yield box.search(None, False), True
        return
    group = max(1, CORNERS_A_CORE * numba.get_num_threads())
    done: list[CornerOutcome] = []
    for i in range(0, len(box.corners), group):
        done += box.batch(box.corners[i:i + group], ())
        yield (BenchStudy(scenario.name, box.ranges, bench.uncertainty.distribution, None, tuple(done), box.rest),
               len(done) == len(box.corners))


class _Box:
    """One patch and scenario at points of the bench's box of ranges: the ranges it feels, its
    corners, and batches of points run on the engine."""

    def __init__(self, net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
                 scenario: Scenario, seed: int | None, corner_runs: int, ideal: bool):
        self.args = (net, plant, bench, machine, scenario)
        self.seed, self.corner_runs, self.ideal = seed, corner_runs, ideal
        self.ranges = active_ranges(bench, ideal, scenario.noise.mode == "profile")
        self.sat = machine.imperfections.saturation_V
        self.searched = len(self.ranges) > worst_case.EXACT_RANGES
        self.corners, self.rest = ([], ()) if self.searched else corner_values(bench, self.ranges)

    def worst_swing(self, runs: Sequence[RunSummary]) -> float:
        """The largest |u_c| of the runs (the rails when any overloaded)."""
        return _worst_swing(runs, self.sat)

    def counted(self, values: dict, runs: list[RunSummary]) -> CornerOutcome:
        """The runs at one point as a CornerOutcome."""
        return CornerOutcome(values, outcome(self.args[4].name, runs, self.worst_swing(runs)))

    def batch(self, points: list[dict], known: Sequence[CornerOutcome]) -> list[CornerOutcome]:
        """The points' outcomes: those in ``known`` as they are, the rest run in one batch (every core)."""
        todo = [v for v in points if not any(k.values == v for k in known)]
        ran = iter(simulate_points(*self.args, todo, runs=self.corner_runs, seed=self.seed, ideal=self.ideal)
                   if todo else [])
        return [next((k for k in known if k.values == v), None) or self.counted(v, next(ran)) for v in points]

    def search(self, progress: Callable[[int, int], None] | None, ends: bool) -> BenchStudy:
        """The study past EXACT_RANGES ranges: the worst corner searched for (patchgen.studies.worst_case)."""
        bench, scenario = self.args[2], self.args[4]
        confirmed, screened_ends, screened = worst_case.search(
            *self.args, self.ranges, seed=self.seed, corner_runs=self.corner_runs, ideal=self.ideal,
            progress=progress)
        return BenchStudy(scenario.name, self.ranges, bench.uncertainty.distribution, None,
                          tuple(self.counted(v, r) for v, r in confirmed), (),
                          tuple(self.counted(v, r) for v, r in screened_ends) if ends else (), screened)
