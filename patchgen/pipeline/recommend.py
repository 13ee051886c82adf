"""patchgen recommend as one function: every realisation of the spec on the bench in every
scenario, ranked (patchgen.studies.recommend), and the chosen patch judged and predicted for its
sheet, reusing the runs the ranking already made."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

from patchgen.bench.diagnosis import as_patched_on_bench
from patchgen.bench.prediction import STANDARD, standard_runs
from patchgen.inputs.scenario import Scenario, load_scenario
from patchgen.patch.as_patched import AsPatched
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.prediction import BenchPrediction, predict_on_bench
from patchgen.pipeline.scaling import ENVELOPE_RUNS, scaled_patch
from patchgen.studies.candidate import Candidate, Recommendation
from patchgen.studies.recommend import RUNS, recommend


@dataclass(frozen=True)
class RecommendPlan:
    """The most runs per realisation and scenario, the base seed (None: each scenario's), and
    whether to stop a realisation's runs once it clearly holds or fails."""

    runs: int = RUNS
    seed: int | None = None
    early_stop: bool = True


@dataclass(frozen=True)
class RecommendReport:
    """The ranked realisations, and the chosen one's patch judged as patched and predicted on the
    bench (both None when none holds)."""

    recommendation: Recommendation
    judged: AsPatched | None
    prediction: BenchPrediction | None
    rescaled: bool = False  # the chosen patch's signals scaled for signal-to-noise after the ranking

    @property
    def best(self) -> Candidate | None:
        """The chosen realisation, if any holds."""
        return self.recommendation.best


def reusable_runs(rec: Recommendation, best: Candidate) -> dict:
    """The chosen candidate's runs of each standard scenario, for the sheet's bench prediction,
    where the recommendation ran that very scenario from its own seed (run i depends on its seed
    alone, so they are the prediction's runs)."""
    done = {}
    for sc in rec.scenarios:
        if sc.name in STANDARD and sc == load_scenario(sc.name) and rec.seed_of(sc) == sc.seed:
            done[sc.name] = best.results(sc.name)
    return done


def run_recommend(inputs: Inputs, scenarios: Sequence[Scenario], plan: RecommendPlan = RecommendPlan(),
                  progress: Callable[[str, int, int], None] | None = None) -> RecommendReport:
    """Rank every realisation of the spec on the bench, then judge and predict the chosen patch.

    Parameters
    ----------
    inputs : Inputs
        The spec, machine and bench, resolved and checked.
    scenarios : sequence of Scenario
        The scenarios every realisation must hold, each checked against the spec's track.
    plan : RecommendPlan
        Runs, seed, early stop.
    progress : callable, optional
        Called with (stage, done, total) as the ranking runs.

    Returns
    -------
    RecommendReport
    """
    spec, machine, bench = inputs
    rec = recommend(spec, machine, bench, scenarios, plan.runs, plan.seed, early_stop=plan.early_stop,
                    progress=progress)
    best = rec.best
    if best is None:
        return RecommendReport(rec, None, None)
    done = reusable_runs(rec, best)
    scaled = scaled_patch(best.design, machine, bench, best.netlist, runs_of=lambda net, rails=True,
                          hold=ENVELOPE_RUNS: standard_runs(
        net, best.design.plant, bench, machine, hold, done=done if net is best.netlist and rails else None,
        bench_spread=bool(bench.uncertainty.ranges), rails=rails))
    rescaled = scaled.netlist is not best.netlist
    if rescaled:  # the chosen patch as patchgen patch gives it (ranked at its sensor constants), so the
        best = replace(best, netlist=scaled.netlist)  # sheet's prediction is of it, its own runs reused
        rec = replace(rec, ranked=(best, *rec.ranked[1:]))
        done, corners = dict(scaled.runs or {}), None
    else:
        corners = best.bench_study
    judged = as_patched_on_bench(best.design, best.netlist, machine, bench)
    pred = predict_on_bench(best.design, best.netlist, machine, bench, done=done, corners=corners)
    return RecommendReport(rec, judged, pred, rescaled)
