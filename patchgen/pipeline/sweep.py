"""patchgen sweep as one function: the spec designed again with each plant parameter off by a
fraction, and the nominal patch (as wired) run on each of those plants."""

from __future__ import annotations

from dataclasses import dataclass

from patchgen.design.lqg import Design, design_on
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.scaling import scaled_patch
from patchgen.studies.sweep import SweepRow, sweep


@dataclass(frozen=True)
class SweepPlan:
    """The parameters varied, the relative change, worker processes (0: one per core) and the noise
    seeds of each row's predicted outcome."""

    vary: tuple[str, ...]
    by: float
    workers: int = 0
    runs: int = 1


@dataclass(frozen=True)
class SweepReport:
    """The nominal design and one row per perturbed plant."""

    design: Design
    plan: SweepPlan
    rows: tuple[SweepRow, ...]

    def summary(self) -> list[dict]:
        """Every row as plain data (``--json``)."""
        return [r.as_dict() for r in self.rows]


def run_sweep(inputs: Inputs, scenario: Scenario, plan: SweepPlan) -> SweepReport:
    """Design the spec, then again for each perturbed plant (thesis tables 4.1, 4.2), with the
    nominal patch's outcome in ``scenario`` on each; every patch carries its signals at the nominal
    patch's signal-to-noise scales (patchgen.pipeline.scaling), so the pots that change are the law's."""
    spec, machine, bench = inputs
    d = design_on(spec, machine, bench)
    try:  # the nominal patch as every command builds it, and every perturbed one at its scales
        scaling = scaled_patch(d, machine, bench).scaling
    except InputError:  # it does not fit: the sweep's rows say so
        scaling = None
    scales = None if scaling is None else scaling.factors
    rows = sweep(d.spec, machine, list(plan.vary), plan.by, plan.workers, scenario, plan.runs, bench=bench,
                 scales=scales)
    return SweepReport(d, plan, tuple(rows))
