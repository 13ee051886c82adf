"""A patch predicted on the bench, for its sheet: the standard scenarios simulated
(patchgen.bench.prediction), the wired loop linearised on the bench, and, when the bench states
ranges, the long hold at their corners (every corner, or the worst searched for past three ranges:
patchgen.studies.bench_corners). Computed here; render/bench_sheet only words it."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

from patchgen.design.lqg import Design
from patchgen.patch.netlist import Netlist
from patchgen.plant.plant_model import CART, PLANT_MODELS
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
class AmplifierLevel:
    """How much of its range an amplifier uses on the bench: its expected peak (the largest |output|
    over the prediction's runs) as a share of the reference, and that peak over the machine's noise
    floor (amplifier noise and integrator offset together) in dB."""

    amplifier: str
    quantity: str
    peak_V: float
    peak_share: float
    snr_dB: float

    def as_dict(self) -> dict:
        """Plain JSON-ready values."""
        return {"amplifier": self.amplifier, "quantity": self.quantity, "peak_V": self.peak_V,
                "peak_share": self.peak_share, "snr_dB": self.snr_dB}


def noise_floor_V(machine: MachineProfile) -> float:
    """The error voltage every amplifier of the machine carries whatever its signal: its noise (rms)
    and an integrator's input offset, combined as independent errors."""
    im = machine.imperfections
    return math.hypot(im.amplifier_noise_V_rms, im.integrator_offset_V)


def amplifier_levels(net: Netlist, machine: MachineProfile, peaks_V: dict[str, float]) -> tuple[AmplifierLevel, ...]:
    """Each amplifier's expected peak and signal-to-noise ratio, in the netlist's order."""
    floor = noise_floor_V(machine)
    out = []
    for a in net.amplifiers:
        p = peaks_V.get(a.id, 0.0)
        snr = 20 * math.log10(p / floor) if p > 0 and floor > 0 else math.inf
        out.append(AmplifierLevel(a.id, a.carries.quantity, p, p / net.reference_V, snr))
    return tuple(out)


@dataclass(frozen=True)
class BenchPrediction:
    """What the sheet's 'Predicted on the bench' says: one prediction per scenario, the wired
    loop's poles with each actuator, and the corners of the bench's ranges (None without ranges)."""

    predictions: tuple[Prediction, ...]
    loops: tuple[LoopPoles, ...]
    corners: BenchStudy | None
    runs_hold: int
    levels: tuple[AmplifierLevel, ...] = ()  # each amplifier's expected peak and signal-to-noise ratio
    plant: str = CART.name  # the plant model predicted for: its words name the figures

    def peaks_V(self) -> dict[str, float]:
        """Each amplifier's largest |output| over every scenario's runs (V, before the rails)."""
        out: dict[str, float] = {}
        for p in self.predictions:
            for a, v in p.amp_peaks_V.items():
                out[a] = max(out.get(a, 0.0), v)
        return out

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
                               "max_abs_theta_deg": p.max_theta_deg,
                               PLANT_MODELS[self.plant].position_key: p.max_s_m,
                               "overloads": p.overloads} for p in self.predictions],
                "linear": [{"actuator": lp.actuator, "verdict": lp.verdict, "line": lp.line()} for lp in self.loops],
                "amplifier_levels": [lv.as_dict() for lv in self.levels],
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
    pred = BenchPrediction(tuple(preds), tuple(diagnose(net, d.plant, bench)), corners if spread else None,
                           runs_hold, plant=d.spec.plant_model.name)
    return replace(pred, levels=amplifier_levels(net, machine, pred.peaks_V()))
