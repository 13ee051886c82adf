"""patchgen simulate as one function: the spec's patch on the bench, its Monte Carlo, the corners of
the bench's ranges, and the wired loop linearised, into one report that the command prints and
writes (summary.json is the report's ``summary()``, and ``--json`` prints the same)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from patchgen.bench.diagnosis import LoopPoles, diagnose
from patchgen.bench.results import SimResult
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.scaling import scaled_patch
from patchgen.profiles.bench import BenchProfile
from patchgen.studies import bench_corners


@dataclass(frozen=True)
class SimulatePlan:
    """How to run: runs over noise seeds, the seed (None: the scenario's), every imperfection off,
    a spread of the plant's parameters, each run's bench drawn from its ranges (and every corner
    of them, with corner_runs runs each; None: as many as runs)."""

    runs: int = 1
    seed: int | None = None
    ideal: bool = False
    spread: dict[str, float] | None = None
    bench_spread: bool = False
    corner_runs: int | None = None


@dataclass(frozen=True)
class SimulateReport:
    """What a simulation found: the runs and their distribution, the corners of the bench's ranges
    (with --bench-spread), and the wired loop's poles linearised with the ideal actuator and the
    bench's (the verdicts it prints)."""

    netlist: Netlist
    result: SimResult
    corners: bench_corners.BenchStudy | None
    loops: tuple[LoopPoles, ...]
    bench: BenchProfile

    def summary(self) -> dict:
        """Every figure and verdict, as plain JSON-able data (summary.json, --json)."""
        out = self.result.summary()
        out["linear"] = [{"actuator": lp.actuator, "verdict": lp.verdict, "rightmost_pole": [lp.worst.real,
                                                                                               lp.worst.imag],
                          "conserved": lp.conserved, "line": lp.line()} for lp in self.loops]
        out["linear_notes"] = self.notes()
        if self.corners is not None:
            out["bench_spread"] = self.corners.as_dict()
        return out

    def notes(self) -> list[str]:
        """What the linear verdicts leave out, in words."""
        act = self.bench.actuator
        if act.dead_zone_V and not self.result.ideal:
            return [f"the bench's dead zone (+/-{act.dead_zone_V:g} V) and force limit ({act.force_limit_N:g} N) "
                    "are in the simulation, not in these poles"]
        return []


def run_simulate(inputs: Inputs, scenario: Scenario, plan: SimulatePlan,
                 progress: Callable[[int], None] | None = None) -> SimulateReport:
    """Design the spec on its machine and bench, patch it, and simulate the patch on the bench.

    Parameters
    ----------
    inputs : Inputs
        The spec, machine and bench, resolved and checked.
    scenario : Scenario
        What happens, checked against the spec's track.
    plan : SimulatePlan
        Runs, seed, ideal, spreads.
    progress : callable, optional
        Called with the runs done after each batch of the Monte Carlo.

    Returns
    -------
    SimulateReport
        The runs, the corners and the linear verdicts.
    """
    spec, machine, bench = inputs
    if plan.bench_spread and not bench.uncertainty.ranges:
        raise InputError("bench_spread", "", f"the bench {bench.id} states no [uncertainty] ranges")
    d = design_on(spec, machine, bench)
    net = scaled_patch(d, machine, bench).netlist
    plant = d.plant
    result = simulate(net, plant, bench, machine, scenario, seed=plan.seed, runs=plan.runs, ideal=plan.ideal,
                      spread=plan.spread, bench_spread=plan.bench_spread, progress=progress)
    corners = None
    if plan.bench_spread:
        corners = bench_corners.study(net, plant, bench, machine, scenario, seed=plan.seed,
                                      corner_runs=plan.corner_runs or plan.runs, drawn=result, ideal=plan.ideal)
    return SimulateReport(net, result, corners, tuple(diagnose(net, plant, bench)), bench)
