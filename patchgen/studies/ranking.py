"""How recommend weighs candidates: each scenario's held fraction with its 95 % interval, the
sequential decision that ends clear winners and losers early, and the order of the ranking.

The held fraction of a scenario is a binomial proportion over noise seeds; its interval is
Wilson's score interval (Wilson 1927, "Probable inference, the law of succession, and statistical
inference", JASA 22), which stays inside [0, 1] and is honest at 0 and n held, where the normal
approximation claims a width of zero. A candidate *holds* when the lower end is at least TARGET
on every scenario, *fails* when the upper end is below TARGET on some scenario; otherwise it is
undecided and more runs are drawn, up to the command's maximum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from patchgen.bench.simulate import RunSummary

TARGET = 0.95  # the held fraction a recommended patch must reach on every scenario
Z95 = 1.959963984540054  # the standard normal's 97.5 % quantile: a two-sided 95 % interval
ROUND_RUNS = 40  # runs per scenario per round of the sequential Monte Carlo
DECISIONS = ("holds", "undecided", "fails")  # best first


def wilson(held: int, runs: int, z: float = Z95) -> tuple[float, float]:
    """Wilson's score interval of a binomial proportion.

    Parameters
    ----------
    held, runs : int
        Successes and trials (runs > 0).
    z : float
        The normal quantile of the interval's confidence (default: 95 %, two-sided).

    Returns
    -------
    (float, float)
        Lower and upper end, inside [0, 1].
    """
    if runs <= 0 or not 0 <= held <= runs:
        raise ValueError(f"need 0 <= held <= runs and runs > 0 (got {held} of {runs})")
    p, z2 = held / runs, z * z
    centre = (p + z2 / (2 * runs)) / (1 + z2 / runs)
    half = z / (1 + z2 / runs) * math.sqrt(p * (1 - p) / runs + z2 / (4 * runs * runs))
    lo = 0.0 if held == 0 else max(0.0, centre - half)  # exactly 0 and 1 at the ends, not rounding off them
    hi = 1.0 if held == runs else min(1.0, centre + half)
    return lo, hi


@dataclass(frozen=True)
class ScenarioOutcome:
    """A candidate's runs of one scenario on the bench: how many held (up, inside the switches,
    no amplifier past the rails, the whole scenario), fell, tripped, overloaded, and the largest
    amplifier swing (V); and how many had their command at the actuator's limit (a fact of the run,
    not a fault: a motor's amplifier at its limit)."""

    scenario: str
    runs: int
    held: int
    fallen: int
    tripped: int
    overloaded: int
    worst_swing_V: float
    at_limit: int = 0
    results: tuple[RunSummary, ...] = field(default=(), repr=False, compare=False)

    @property
    def fraction(self) -> float:
        """Runs held, as a fraction."""
        return self.held / self.runs

    @property
    def interval(self) -> tuple[float, float]:
        """The held fraction's 95 % Wilson interval."""
        return wilson(self.held, self.runs)

    def as_dict(self) -> dict:
        """Plain JSON-ready values."""
        lo, hi = self.interval
        return {"scenario": self.scenario, "runs": self.runs, "held": self.held, "fraction_held": self.fraction,
                "interval_95": [lo, hi], "fallen": self.fallen, "tripped": self.tripped,
                "overloaded": self.overloaded, "worst_swing_V": self.worst_swing_V,
                "at_actuator_limit": self.at_limit}


def outcome(scenario: str, runs: list[RunSummary], worst_swing_V: float) -> ScenarioOutcome:
    """A scenario's runs counted (a run held only if it also never overloaded)."""
    return ScenarioOutcome(scenario, len(runs), sum(r.held and not r.overloads for r in runs),
                           sum(r.fall_time_s is not None for r in runs),
                           sum(r.trip_time_s is not None for r in runs),
                           sum(bool(r.overloads) for r in runs), worst_swing_V,
                           sum(r.actuator_limit_time_s > 0 for r in runs), tuple(runs))


def decision(outcomes: list[ScenarioOutcome] | tuple[ScenarioOutcome, ...], target: float = TARGET) -> str:
    """"holds" (every scenario's lower end at least ``target``), "fails" (some scenario's upper
    end below it) or "undecided"."""
    if any(o.interval[1] < target for o in outcomes):
        return "fails"
    if outcomes and all(o.interval[0] >= target for o in outcomes):
        return "holds"
    return "undecided"


def weakest(outcomes: list[ScenarioOutcome] | tuple[ScenarioOutcome, ...]) -> ScenarioOutcome | None:
    """The scenario held least (ties: the one whose interval reaches least high, then the first)."""
    return min(outcomes, key=lambda o: (o.fraction, o.interval[1]), default=None)
