"""Candidates robust to the bench's uncertainty (the actuator's dead zone and lag above all): when a
bench profile states ranges, the gains are chosen over the corners of those ranges, not on one
nominal model.

The design is the spec's LQR with the bench's actuator model, its Bryson excursions scaled by each
point of a small grid (WEIGHT_GRID; tighter excursions on the states raise the loop gain, which
shrinks the limit cycle a dead zone drives; the force's excursion stays the spec's), with and
without the integral of the cart position. Every point that designs and fits the machine is run
at the corners of the ranges in every scenario, SEARCH_RUNS seeds per corner; the point held best
at its worst corner wins (ties: the smaller cart excursion over the corners, i.e. the most room
before the limit switches; then the grid order). The search runs best first: further corners can
only lower a point's worst and widen its excursion, so the point whose corners so far rank highest
runs its next few, and the search ends when that point has run them all. The choice is the one a
full run of every point would make, and a point that cannot win stops after its first corners.

Other ways to beat a dead zone, and why a patch here does not use them (``ALTERNATIVES``): dither
needs a periodic source the machine profiles do not list, and a dead-zone inverse needs diodes or a
comparator they do not have either. The sheet says so.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field

from patchgen.design.lqg import Design, design_on
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import Netlist
from patchgen.plant.cart_pendulum import ANGLE, POSITION, RATE_OF
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.studies.bench_corners import BenchStudy, cart_excursion, study_in_steps

# Bryson excursions times these (theta, s, s_dot, u); integral of s off, then on
WEIGHT_GRID = {ANGLE: (1.0, 0.5), POSITION: (1.0, 0.5), RATE_OF[POSITION]: (1.0, 1 / 3), "u": (1.0,)}
INTEGRAL_OPTIONS = (False, True)
SEARCH_RUNS = 64  # seeds per corner while searching (one block of the simulator)
LABEL = "corner-robust gains"

ALTERNATIVES = (
    "dither, since the machine has no periodic source (no oscillator or function generator in its "
    "profile) and the bench profile states none",
    "a dead-zone inverse, since it needs diodes or a comparator (a precision rectifier), which the "
    "machine's profile does not list",
)
WHY_GAINS = ("tighter excursions raise the loop gain, so the dead zone's limit cycle stays small and the cart "
             "inside the switches at every corner")


@dataclass(frozen=True)
class RobustChoice:
    """The grid point chosen over the corners: its spec, the multipliers, its worst corner's runs
    held of those run (and which scenario), and how many points were tried."""

    spec: DesignSpec
    factors: dict[str, float]
    integral_s: bool
    held: int
    runs: int
    worst_corner: dict[str, float]
    tried: int
    scenario: str  # where its worst corner is
    netlist: Netlist | None = field(default=None, compare=False, repr=False)  # its patch
    studies: tuple[BenchStudy, ...] = field(default=(), compare=False, repr=False)  # its corners, every scenario

    def detail(self) -> str:
        """The choice in a few words, for the table and the sheet."""
        f = ", ".join(f"{k} x{v:.3g}" for k, v in self.factors.items() if v != 1.0) or "the spec's"
        integ = ", integral of s" if self.integral_s else ""
        corner = ", ".join(f"{k} {v:g}" for k, v in self.worst_corner.items())
        return (f"Bryson excursions {f}{integ}, the best of {self.tried} designs run at every corner in every "
                f"scenario: held {self.held}/{self.runs} at its worst ({self.scenario}, {corner})")


def grid_specs(spec: DesignSpec, bench: BenchProfile) -> list[tuple[dict[str, float], bool, DesignSpec]]:
    """Every grid point as a spec: the bench's actuator model, scaled Bryson excursions (or, for a
    spec without Bryson weights, a scaled R only), with and without the integral of s."""
    b = bench.actuator
    act = spec.actuator.model_copy(update={"model": b.model, "K_U": b.K_U, "tau": b.tau,
                                           "dead_zone_V": b.dead_zone_V})
    w = spec.weights
    out = []
    names = [k for k in WEIGHT_GRID if w.bryson and k in w.bryson] if w.bryson else ["u"]
    for integral in INTEGRAL_OPTIONS:
        for combo in itertools.product(*(WEIGHT_GRID[k] for k in names)):
            factors = dict(zip(names, combo))
            if w.bryson:
                weights = w.model_copy(update={"bryson": {k: float(f"{v * factors.get(k, 1.0):.6g}")
                                                          for k, v in w.bryson.items()}})
            elif w.R is not None:
                weights = w.model_copy(update={"R": w.R / factors["u"] ** 2})
            elif w.R_V is not None:
                weights = w.model_copy(update={"R_V": w.R_V / factors["u"] ** 2})
            else:
                weights = w
            integ = spec.integrators.model_copy(update={"int_s": spec.integrators.int_s or integral})
            if integral and spec.integrators.int_s:
                continue  # the spec has it already
            est = spec.estimator.model_copy(update={"rolloff_s": None, "observer_pole": None})
            out.append((factors, integral, spec.model_copy(update={
                "actuator": act, "weights": weights, "integrators": integ, "estimator": est})))
    return out


def excursion(st: BenchStudy) -> float:
    """The cart's excursion at the study's worst corner for it: the largest 95th percentile of
    max |s| (m) over the corners."""
    return max(cart_excursion(c) for c in st.corners)


def _key(held: int, room: float) -> tuple[int, float]:
    """A point's rank: runs held at its worst corner, then the least cart excursion (m)."""
    return held, -round(room, 4)


class _Point:
    """A grid point under search: its patch, its studies so far (the last may be partial) and the
    best rank it can still reach (its corners so far: more corners only lower the runs held at
    its worst and raise its excursion)."""

    def __init__(self, index: int, factors: dict[str, float], integral: bool, design: Design, net: Netlist):
        self.index, self.factors, self.integral, self.design, self.net = index, factors, integral, design, net
        self.studies: list[BenchStudy] = []  # complete, in the search's scenario order
        self.partial: BenchStudy | None = None  # the present scenario's so far
        self.steps: Iterator[tuple[BenchStudy, bool]] | None = None
        self.held, self.room = SEARCH_RUNS, 0.0

    @property
    def bound(self) -> tuple[int, float]:
        """The best rank the point can still reach (its rank, once complete)."""
        return _key(self.held, self.room)

    def complete(self, scenarios: int) -> bool:
        """Every scenario's study run to its end."""
        return len(self.studies) == scenarios

    def advance(self, sc: Scenario, machine: MachineProfile, bench: BenchProfile, seed: int | None) -> None:
        """Run the next few corners of scenario ``sc`` (the present one, or the next when none is under way)."""
        if self.steps is None:
            self.steps = study_in_steps(self.net, self.design.plant, bench, machine, sc, seed=seed,
                                        corner_runs=SEARCH_RUNS)
        st, whole = next(self.steps)
        new = st.corners[len(self.partial.corners) if self.partial else 0:]
        self.held = min([self.held] + [c.outcome.held for c in new])
        self.room = max([self.room] + [cart_excursion(c) for c in new])
        self.partial = st
        if whole:
            self.studies.append(st)
            self.partial, self.steps = None, None

    def choice(self, tried: int) -> RobustChoice:
        """The point as the search's choice: its worst corner the first scenario's that holds least."""
        scenario, worst = None, None
        for st in self.studies:
            w = st.worst_corner
            if worst is None or w.outcome.held < worst.outcome.held:
                scenario, worst = st.scenario, w
        return RobustChoice(self.design.spec, self.factors, self.integral, worst.outcome.held, worst.outcome.runs,
                            worst.values, tried, scenario, self.net, tuple(self.studies))


def search(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile, scenarios: Sequence[Scenario],
           seed: int | None = None, progress: Callable[[int, int], None] | None = None) -> RobustChoice | None:
    """The grid point held best at its worst corner of the bench's ranges (see the module docstring).

    Best first: the point whose corners so far rank highest (ties: the earlier point) runs its next
    few corners (patchgen.studies.bench_corners.study_in_steps; scenarios the shortest first), until
    that point has run every corner of every scenario. Its rank then is at least the best any other
    point can still reach, so it is the point a full run of every point would choose, and points
    that cannot win stop after their first corners whatever order the grid is in.

    Parameters
    ----------
    spec : DesignSpec
        The spec whose weights are varied.
    machine, bench : MachineProfile, BenchProfile
        The machine the patches are allocated on; the bench with its ranges.
    scenarios : sequence of Scenario
        Every one is run at every corner by the chosen point (the shortest first).
    seed : int, optional
        Its base seed (default: its own).
    progress : callable, optional
        ``progress(done, total)``: grid points ruled out so far, of the grid.

    Returns
    -------
    RobustChoice or None
        None when the bench states no ranges or no grid point designs and fits.
    """
    if not bench.uncertainty.ranges or not scenarios:
        return None
    order = sorted(scenarios, key=lambda sc: sc.duration_s)  # the short ones first: a loser drops early
    grid = grid_specs(spec, bench)
    if progress is not None:
        progress(0, len(grid))
    points = []
    for i, (factors, integral, sp) in enumerate(grid):
        try:
            d = design_on(sp, machine, bench)
            points.append(_Point(i, factors, integral, d, build_patch(d, machine, 1)))
        except InputError:
            continue
    if not points:
        return None
    settled = 0
    while True:
        top = max(points, key=lambda p: (p.bound, -p.index))
        if top.complete(len(order)):
            break
        top.advance(order[len(top.studies)], machine, bench, seed)
        if progress is not None:  # ruled out for now: below the top (the top's bound only falls)
            settled = max(settled, len(grid) - len(points) + sum(p.bound < top.bound for p in points))
            progress(settled, len(grid))
    if progress is not None:
        progress(len(grid), len(grid))
    return top.choice(len(points))
