"""The statistical verdict of a noisy ngspice run: is it a plausible member of patchgen's own
Monte Carlo of the same patch, bench and scenario?

With noise on, ngspice draws its own realisation and patchgen its own, so the two trajectories
cannot agree point by point. What can agree is what a run does: each figure of ngspice's one run
(FIGURES: the largest |theta|, the RMS theta, the largest |s|, as patchgen's RunSummary counts
them, up to the limit-switch trip) must lie inside the envelope of the Monte Carlo's figures, and
ngspice's run must hold (pendulum up, cart inside the switches) or not as the Monte Carlo's runs
mostly do.

The envelope of a figure is the Monte Carlo's range (its smallest and largest run) widened on
each side by SPREAD_MARGIN of its 5-95 % width and FLOOR of its median. Were ngspice's run
exchangeable with the Monte Carlo's N runs, it would fall outside their range with probability
2 / (N + 1) per figure: with N = MC_RUNS and Bonferroni over the three figures, at most 3 % of
correct runs would be refused before the widening, which brings that near zero. The widening
covers what differs between the two models by construction (patchgen.spice.deck: interpolated
noise samples against the engine's held ones, one drift sign, op-amp macromodels, a figure
sampled at ngspice's output step rather than at every engine step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from patchgen.bench.results import RunSummary

# The Monte Carlo's runs: its range then misses an exchangeable run with probability 2/201 = 1 %
# per figure, and the held fraction is known to +/-3 % (binomial, 95 %) where it matters, near 1;
# the runs of a 120 s hold cost under a second on two cores.
MC_RUNS = 200
# The envelope is the Monte Carlo's range widened each side by this fraction of its 5-95 % width:
# the deck's noise is interpolated (the engine holds it over each step), which dithers the
# actuator's dead zone a little less; measured on correct patches, ngspice's RMS theta lies up to
# 1.4 widths above the Monte Carlo's median (the range reaches about 0.85 width past it), while
# theta's pot at 90 % of its setting moves it 5.9 widths (offset-10deg).
SPREAD_MARGIN = 1.0
# ... and by this fraction of its median, for a figure the noise hardly spreads (the largest
# |theta| of a release is its initial lean): the ideal runs agree within 0.2 % of peak, and a
# maximum read every 5 ms rather than every 2 ms engine step misses up to a few tenths of a percent.
FLOOR = 0.01
# Below this median RMS theta the Monte Carlo saw no excitation (no noise, no push, upright): any
# patch, broken or not, sits still, and agreeing would prove nothing. Noise alone gives ~0.25 deg.
MIN_RMS_THETA_DEG = 0.01
# ngspice's run may hold (or not) when at least this fraction of the Monte Carlo's runs did the
# same: "held iff the Monte Carlo mostly holds", without refusing a run whose outcome is common.
HELD_PLAUSIBLE = 0.05
FIGURES = ("max_abs_theta_deg", "rms_theta_deg", "max_abs_s_m")
FIGURE_TEXT = {"max_abs_theta_deg": "largest |theta| (deg)", "rms_theta_deg": "RMS theta (deg)",
               "max_abs_s_m": "largest |s| (m)"}


@dataclass(frozen=True)
class RunFigures:
    """What one run did: its figures (FIGURES, by name) and whether it held."""

    figures: dict[str, float]
    held: bool
    fallen: bool
    tripped: bool


@dataclass(frozen=True)
class Envelope:
    """One figure: ngspice's value, the Monte Carlo's 5/50/95 % and its envelope [low, high]."""

    name: str
    value: float
    p5: float
    p50: float
    p95: float
    low: float
    high: float

    @property
    def inside(self) -> bool:
        """ngspice's value lies in the envelope."""
        return self.low <= self.value <= self.high


@dataclass(frozen=True)
class StatisticalVerdict:
    """ngspice's run against the Monte Carlo: each figure's envelope, the held outcomes, and the
    verdict with its reason."""

    runs: int
    envelopes: dict[str, Envelope]
    held: bool
    fraction_held: float
    excited: bool

    @property
    def held_plausible(self) -> bool:
        """At least HELD_PLAUSIBLE of the Monte Carlo's runs did what ngspice's did."""
        same = self.fraction_held if self.held else 1.0 - self.fraction_held
        return same >= HELD_PLAUSIBLE

    @property
    def agrees(self) -> bool:
        """Excited, the held outcome plausible, and every figure inside its envelope."""
        return self.excited and self.held_plausible and all(e.inside for e in self.envelopes.values())

    def reasons(self) -> list[str]:
        """Why the verdict is "disagree" (empty when it agrees)."""
        out = [] if self.excited else [
            f"the Monte Carlo's median RMS theta is below {MIN_RMS_THETA_DEG} deg: nothing excites the loop, "
            "so agreement would prove nothing"]
        if not self.held_plausible:
            out.append(f"ngspice's run {'held' if self.held else 'did not hold'}; "
                       f"{100 * self.fraction_held:.0f} % of the Monte Carlo's runs held")
        out += [f"{FIGURE_TEXT[e.name]} {e.value:.4g} outside [{e.low:.4g}, {e.high:.4g}]"
                for e in self.envelopes.values() if not e.inside]
        return out

    def as_dict(self) -> dict:
        """Plain JSON-able data for comparison.json."""
        return {"method": method_text(), "runs": self.runs, "spread_margin": SPREAD_MARGIN, "floor": FLOOR,
                "held": self.held, "fraction_held": self.fraction_held, "excited": self.excited,
                "agrees": self.agrees,
                "reasons": self.reasons(),
                "figures": {k: {"ngspice": e.value, "p5": e.p5, "p50": e.p50, "p95": e.p95,
                                "low": e.low, "high": e.high, "inside": e.inside}
                            for k, e in self.envelopes.items()}}


def method_text() -> str:
    """The statistical verdict in one sentence (printed and written to comparison.json)."""
    return (f"ngspice's run against {MC_RUNS} runs of patchgen's Monte Carlo: each figure inside the Monte "
            f"Carlo's range widened by {SPREAD_MARGIN:g} x its 5-95 % width "
            f"and {100 * FLOOR:g} % of its median, the run held or not as at least "
            f"{100 * HELD_PLAUSIBLE:g} % of the Monte Carlo's runs, and the Monte Carlo excited "
            f"(median RMS theta at least {MIN_RMS_THETA_DEG} deg)")


def run_figures(t: np.ndarray, s: np.ndarray, theta: np.ndarray, cut_m: float | None,
                fall_angle_rad: float) -> RunFigures:
    """A trajectory's figures as the engine counts a run's (patchgen.bench.results.RunSummary):
    up to and including the first point at or past the cut (the limit switches end the run),
    fallen when |theta| passed the fall angle before that.

    Parameters
    ----------
    t, s, theta : numpy.ndarray
        Time (s), cart position (m) and angle (rad) at evenly spaced points.
    cut_m : float or None
        |s| at which the motor is cut (BenchProfile.track.cut_at); None: never.
    fall_angle_rad : float
        The scenario's fall angle.

    Returns
    -------
    RunFigures
        The figures and the run's outcome.
    """
    n = len(t)
    over = np.flatnonzero(np.abs(s) >= cut_m) if cut_m is not None else np.array([], dtype=int)
    tripped = over.size > 0
    end = int(over[0]) + 1 if tripped else n
    th, x = theta[:end], s[:end]
    fallen = bool(np.any(np.abs(th) > fall_angle_rad))
    return RunFigures({"max_abs_theta_deg": math.degrees(float(np.max(np.abs(th)))),
                       "rms_theta_deg": math.degrees(float(np.sqrt(np.mean(th ** 2)))),
                       "max_abs_s_m": float(np.max(np.abs(x)))},
                      held=not (tripped or fallen), fallen=fallen, tripped=tripped)


def statistical_verdict(run: RunFigures, mc: list[RunSummary]) -> StatisticalVerdict:
    """Judge ngspice's run against the Monte Carlo's runs (see the module docstring).

    Parameters
    ----------
    run : RunFigures
        ngspice's run.
    mc : list of RunSummary
        patchgen's Monte Carlo of the same patch, bench and scenario.

    Returns
    -------
    StatisticalVerdict
        Each figure's envelope, the outcomes and the verdict.
    """
    envelopes = {}
    for name in FIGURES:
        v = np.array([getattr(r, name) for r in mc], dtype=float)
        p5, p50, p95 = (float(x) for x in np.percentile(v, (5, 50, 95)))
        widen = SPREAD_MARGIN * (p95 - p5) + FLOOR * abs(p50)
        envelopes[name] = Envelope(name, run.figures[name], p5, p50, p95,
                                   float(v.min()) - widen, float(v.max()) + widen)
    rms = np.median([r.rms_theta_deg for r in mc])
    return StatisticalVerdict(len(mc), envelopes, run.held, sum(r.held for r in mc) / len(mc),
                              bool(rms >= MIN_RMS_THETA_DEG))
