"""A candidate realisation and the ranked recommendation: what patchgen.studies.recommend produces,
and the rank a candidate takes among the others (the order is explained there)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from patchgen.design.lqg import Design
from patchgen.design.margins import Margins
from patchgen.inputs.scenario import Scenario
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.netlist import Netlist
from patchgen.studies.bench_corners import BenchStudy
from patchgen.studies.departures import Departure
from patchgen.studies.ranking import DECISIONS, TARGET, ScenarioOutcome, decision, weakest

# Figures are rounded before ranking, so that noise in the last digits cannot reorder candidates.
FRACTION_DIGITS = 6  # fraction of runs held: below one run in a million
MARGIN_DIGITS = 1  # gain margin (dB) and phase margin (deg), as the table prints them


@dataclass(frozen=True)
class Candidate:
    """One realisation: its spec, design and patch (when it fits the machine), the wired loop's
    verdict and margins on the bench and, once simulated, its outcome in each scenario."""

    label: str
    kind: str
    spec: DesignSpec | None
    design: Design | None
    netlist: Netlist | None
    error: str | None  # why it was not simulated (design or resource error, one line)
    estimator_detail: str = ""
    bench_loop: str | None = None  # stable, marginal or unstable (patchgen.bench.diagnosis)
    bench_loop_line: str = ""
    margins: Margins | None = field(default=None, compare=False)  # the wired loop's, on the bench
    outcomes: tuple[ScenarioOutcome, ...] = ()
    bench_study: BenchStudy | None = field(default=None, compare=False)  # corners and ends of the bench's ranges
    robust_note: str = ""  # how a corner-robust candidate was chosen
    searched: tuple[BenchStudy, ...] = field(default=(), compare=False, repr=False)  # the robust search's
    # corner studies of this very patch (robust.SEARCH_RUNS seeds each), every scenario
    variant: str = ""  # the spec's variant it realises (patchgen.studies.variants); "": the spec itself
    departures: tuple[Departure, ...] = ()  # every field its written spec changes of the spec given

    @property
    def simulated(self) -> bool:
        """Run on the bench in every scenario."""
        return bool(self.outcomes)

    @property
    def decision(self) -> str | None:
        """holds, undecided or fails (patchgen.studies.ranking.decision); None before simulating."""
        return decision(self.outcomes) if self.outcomes else None

    @property
    def weakest(self) -> ScenarioOutcome | None:
        """The scenario held least."""
        return weakest(self.outcomes)

    @property
    def fraction_ok(self) -> float | None:
        """The weakest scenario's held fraction (None before simulating)."""
        w = self.weakest
        return None if w is None else w.fraction

    @property
    def runs(self) -> int:
        """Runs simulated, over every scenario."""
        return sum(o.runs for o in self.outcomes)

    @property
    def worst_swing_V(self) -> float | None:
        """The largest amplifier output over every scenario's runs."""
        return max((o.worst_swing_V for o in self.outcomes), default=None)

    @property
    def gm_db(self) -> float | None:
        """Distance to the nearer gain limit of the wired loop on the bench, dB (None: not stable)."""
        m = self.margins
        if m is None or not m.stable:
            return None
        lims = [abs(x) for x in (m.lower_gm_db, m.upper_gm_db) if x is not None]
        return min(lims) if lims else math.inf

    @property
    def pm_deg(self) -> float | None:
        """Phase margin of the wired loop on the bench, deg (None when it is not stable)."""
        m = self.margins
        return None if m is None or not m.stable else m.pm_deg

    @property
    def amplifiers(self) -> int | None:
        """Amplifiers the patch uses (None when it does not fit)."""
        return None if self.netlist is None else len(self.netlist.amplifiers)

    @property
    def pots(self) -> int | None:
        """Pots the patch uses (None when it does not fit)."""
        return None if self.netlist is None else len(self.netlist.pots)

    def results(self, scenario: str) -> list:
        """The runs of one scenario, in seed order (empty if it was not simulated)."""
        return next((list(o.results) for o in self.outcomes if o.scenario == scenario), [])

    def rank_key(self, order: int) -> tuple:
        """Sort key, best first (the order patchgen.studies.recommend's docstring gives); ``order``
        is the candidate's place."""
        if not self.simulated:
            return (1, 1, len(DECISIONS), 0.0, 0.0, 0.0, 0, 0, 0, order)

        def r(x):  # larger margins first; infinite ahead of every finite one; none last
            if x is None:
                return 0.0
            return -round(x, MARGIN_DIGITS) if math.isfinite(x) else -math.inf

        dec = self.decision
        frac = 0.0 if dec == "holds" else -round(self.fraction_ok, FRACTION_DIGITS)
        corner = self.corner_fraction
        corner = 0.0 if corner is None else -round(corner, FRACTION_DIGITS)
        units = self.netlist.units if self.netlist is not None else 1
        return (0, 0 if self.bench_loop == "stable" else 1, DECISIONS.index(dec), corner, frac, r(self.gm_db),
                r(self.pm_deg), units, self.amplifiers or 0, self.pots or 0, order)

    @property
    def corner_fraction(self) -> float | None:
        """The held fraction at the worst corner of the bench's ranges (None: not run there)."""
        st = self.bench_study
        w = None if st is None else st.worst_corner
        return None if w is None else w.outcome.fraction


@dataclass(frozen=True)
class Recommendation:
    """Every candidate, ranked, and the Monte Carlo they were ranked by."""

    spec: DesignSpec
    scenarios: tuple[Scenario, ...]
    max_runs: int
    seed: int | None  # every scenario's base seed; None: each scenario's own
    ranked: tuple[Candidate, ...]
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)  # the bench's, drawn by every run
    distribution: str = "uniform"
    variants: tuple[str, ...] = ()  # the spec's variants tried, nearest first (none held among its own)
    repeated: int = 0  # variants' realisations left out: their patch was one already run
    unfit: int = 0  # variants' realisations left out: they did not design or fit the machine

    @property
    def best(self) -> Candidate | None:
        """The first-ranked candidate if its wired loop is stable on the bench and it held in at
        least TARGET of the runs of every scenario; None otherwise (a loop that does not balance
        the pendulum is never chosen, whatever its runs did)."""
        b = self.ranked[0] if self.ranked else None
        ok = (b is not None and b.netlist is not None and b.simulated and b.bench_loop == "stable"
              and b.decision != "fails" and b.fraction_ok >= TARGET
              and (b.bench_study is None or b.corner_fraction >= TARGET))
        return b if ok else None

    def seed_of(self, scenario: Scenario) -> int:
        """The base seed a scenario ran from."""
        return scenario.seed if self.seed is None else self.seed
