"""A patch predicted on the bench, for its sheet: the standard scenarios simulated
(patchgen.bench.prediction), the wired loop linearised on the bench, and, when the bench states
ranges, the long hold at their corners (every corner, or the worst searched for past three ranges:
patchgen.studies.bench_corners). Computed here; render/bench_sheet only words it."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from patchgen.design.lqg import Design
from patchgen.patch.netlist import Netlist
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

if TYPE_CHECKING:  # pragma: no cover - the simulator loads numba, only when a prediction is made
    from patchgen.bench.diagnosis import LoopPoles
    from patchgen.bench.prediction import Prediction
    from patchgen.bench.results import RunSummary
    from patchgen.studies.bench_corners import BenchStudy

PREDICTION_TARGET = 0.95  # a scenario held in fewer of its runs than this is a predicted failure
HOLD_RUNS = 20  # noise seeds of the sheet's 120 s hold unless asked otherwise (patchgen patch --runs)
HOLD_SCENARIO = "hold-120s"  # the scenario run at the corners of the bench's ranges


@dataclass(frozen=True)
class BenchPrediction:
    """What the sheet's 'Predicted on the bench' says: one prediction per scenario, the wired
    loop's poles with each actuator, and the corners of the bench's ranges (None without ranges)."""

    predictions: tuple[Prediction, ...]
    loops: tuple[LoopPoles, ...]
    corners: BenchStudy | None
    runs_hold: int

    @property
    def failing(self) -> tuple[Prediction, ...]:
        """The scenarios held in fewer than PREDICTION_TARGET of their runs."""
        return tuple(p for p in self.predictions if p.fraction_held < PREDICTION_TARGET)

    @property
    def holds(self) -> bool:
        """The wired loop is stable on the bench and every scenario holds."""
        return self.loops[-1].verdict == "stable" and not self.failing

    def summary(self) -> dict:
        """Every figure and verdict as plain data (the patch commands' --json)."""
        return {"holds": self.holds, "runs_hold": self.runs_hold,
                "scenarios": [{"name": p.scenario, "runs": p.runs, "fraction_held": p.fraction_held,
                               "first_trip_s": p.first_trip_s, "first_fall_s": p.first_fall_s,
                               "max_abs_theta_deg": p.max_theta_deg, "max_abs_s_m": p.max_s_m,
                               "overloads": p.overloads} for p in self.predictions],
                "linear": [{"actuator": lp.actuator, "verdict": lp.verdict, "line": lp.line()} for lp in self.loops],
                "bench_spread": None if self.corners is None else self.corners.as_dict()}


def predict_on_bench(d: Design, net: Netlist, machine: MachineProfile, bench: BenchProfile,
                     runs_hold: int = HOLD_RUNS, done: dict[str, list[RunSummary]] | None = None,
                     corners: BenchStudy | None = None) -> BenchPrediction:
    """The patch in the bench's scenarios, its wired loop linearised there, and its corners.

    Parameters
    ----------
    d : Design
        The design the patch realises (its plant).
    net : Netlist
        The patch.
    machine, bench : MachineProfile, BenchProfile
        The machine the patch is on and the bench it is simulated against.
    runs_hold : int
        Noise seeds of the long hold (and of each corner).
    done : dict, optional
        Runs already simulated, by scenario name (see patchgen.bench.prediction.predict).
    corners : BenchStudy, optional
        The patch at the corners of the bench's ranges, when already run; when the bench states
        ranges and none is given, the hold is run at its corners (patchgen.studies.bench_corners.study).

    Returns
    -------
    BenchPrediction
    """
    from patchgen.bench.diagnosis import diagnose
    from patchgen.bench.prediction import predict  # the simulator: numba
    from patchgen.inputs.scenario import load_scenario
    from patchgen.studies.bench_corners import study

    spread = bool(bench.uncertainty.ranges)
    preds = predict(net, d.plant, bench, machine, runs_hold=runs_hold, done=done, bench_spread=spread)
    if spread and corners is None:
        corners = study(net, d.plant, bench, machine, load_scenario(HOLD_SCENARIO), corner_runs=runs_hold)
    return BenchPrediction(tuple(preds), tuple(diagnose(net, d.plant, bench)), corners if spread else None,
                           runs_hold)
