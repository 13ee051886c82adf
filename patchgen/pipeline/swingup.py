"""patchgen swingup as one function: the spec's patch, the pump-up from hanging with its strategy,
the hand-off and the patched hold on the bench, and, when asked, the strategies compared; into one
report whose ``summary()`` is manoeuvre.json and ``--json``."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from patchgen.bench.diagnosis import as_patched_on_bench
from patchgen.design.lqg import Design, design_on
from patchgen.inputs.errors import InputError
from patchgen.patch.as_patched import AsPatched
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.prediction import BenchPrediction, predict_on_bench
from patchgen.pipeline.scaling import scaled_patch
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import CART
from patchgen.plant.rotary_equations import RotaryParams
from patchgen.profiles.measured_plant import as_on_bench
from patchgen.swingup.manoeuvre import BENCH_HOLD_S, Manoeuvre, manoeuvre
from patchgen.swingup.rotary_manoeuvre import RotaryManoeuvre, rotary_manoeuvre
from patchgen.swingup.run import StrategySummary, compare_strategies

SHEET_HOLD_RUNS = 10  # seeds of the sheet's 120 s hold: fewer than patchgen patch's, as the manoeuvre runs too


@dataclass(frozen=True)
class SwingupPlan:
    """The strategy, the pump-up's force limit (None: the bench actuator's), the hold after the
    hand-off (s), the hold's noise seed, whether to compare the strategies too, and the seeds of
    the sheet's predicted 120 s hold."""

    strategy: str = "supervisory"
    force_limit_N: float | None = None
    hold_s: float = BENCH_HOLD_S
    seed: int = 0
    compare: bool = False
    sheet_runs_hold: int = SHEET_HOLD_RUNS


@dataclass(frozen=True)
class SwingupReport:
    """What the manoeuvre did: the design and its patch, the force the pump-up used, the manoeuvre
    (pump-up, zone, hold, schedule sensitivity) and the strategies compared."""

    design: Design
    netlist: Netlist
    plant: PlantParams
    plan: SwingupPlan
    force_limit_N: float
    manoeuvre: Manoeuvre
    comparison: tuple[StrategySummary, ...] | None
    judged: AsPatched
    prediction: BenchPrediction

    @property
    def schedule_note(self) -> str | None:
        """For the 'schedule' strategy, the note that its optimiser kept its seed (the supervisory
        switching table) unchanged; None when it moved the switches, or for another strategy."""
        return self.manoeuvre.pump.notes.get("kept_seed_note")

    def summary(self) -> dict:
        """Every figure and verdict, as plain JSON-able data (manoeuvre.json, --json)."""
        m, p = self.manoeuvre, self.manoeuvre.pump
        out = {"design": self.design.spec.name, "strategy": self.plan.strategy, "force_limit_N": self.force_limit_N,
               "reached_zone": p.reached, "handoff_time_s": p.handoff_time,
               "max_abs_s_pump_m": p.max_abs_s_pump, "track_half_m": self.plant.d / 2,
               "hold_s": self.plan.hold_s, "held": m.held,
               "hold": None if m.hold is None else {k: v for k, v in m.hold.summary()["first_run"].items()
                                                    if k != "final_state"}}
        out["switching_table"] = [{k: v.item() if hasattr(v, "item") else v for k, v in row.items()}
                                  for row in p.table_rows()]  # the switching table the command prints
        if self.plan.strategy == "schedule":
            n = p.notes
            out["schedule"] = {"optimised": bool(n["optimised"]), "kept_seed": bool(n["kept_seed"]),
                               "iterations": int(n["iterations"]), "predicted_T_F_s": float(n["predicted_T_F"]),
                               "seed_T_F_s": float(n["seed_T_F"])}
            if self.schedule_note is not None:
                out["schedule"]["note"] = self.schedule_note
        if m.sensitivity is not None:
            out["schedule_sensitivity"] = [_plain(r) for r in m.sensitivity]
        if self.comparison is not None:
            out["comparison"] = [_plain(r) for r in self.comparison]
        return out


def _plain(row) -> dict:
    """A dataclass row as plain values (numpy scalars as Python numbers)."""
    return {k: v.item() if hasattr(v, "item") else v for k, v in asdict(row).items()}


@dataclass(frozen=True)
class RotarySwingupReport:
    """A rotary pendulum's manoeuvre: the design and its patch, the energy pump-up, the hand-off and
    the patched hold on the bench, the patch judged and predicted as patchgen patch does."""

    design: Design
    netlist: Netlist
    plant: RotaryParams
    plan: SwingupPlan
    manoeuvre: RotaryManoeuvre
    judged: AsPatched
    prediction: BenchPrediction

    def summary(self) -> dict:
        """Every figure and verdict, as plain JSON-able data (manoeuvre.json, --json)."""
        return {"design": self.design.spec.name, **self.manoeuvre.summary()}


def run_rotary_swingup(inputs: Inputs, plan: SwingupPlan) -> RotarySwingupReport:
    """A rotary pendulum pumped up by energy control, handed to its patch, held on the bench.

    Raises
    ------
    InputError
        A cart's option: another strategy than energy, a force limit, the strategies compared.
    """
    spec, machine, bench = inputs
    for given, option, why in ((plan.strategy != "energy", "--strategy", "the rotary pendulum is pumped by "
                                "energy control (Astrom and Furuta): --strategy energy"),
                               (plan.force_limit_N is not None, "--force-limit", "a cart's force: the rotary "
                                "pump drives the motor to the bench amplifier's V_limit"),
                               (plan.compare, "--compare", "compares the cart's three strategies")):
        if given:
            raise InputError(option, "", why)
    d = design_on(spec, machine, bench)
    net = scaled_patch(d, machine, bench).netlist
    m = rotary_manoeuvre(net, d.plant, bench, machine, d.K[:, :4], plan.hold_s, plan.seed)
    judged = as_patched_on_bench(d, net, machine, bench)
    pred = predict_on_bench(d, net, machine, bench, plan.sheet_runs_hold)
    return RotarySwingupReport(d, net, d.plant, plan, m, judged, pred)


def run_swingup(inputs: Inputs, plan: SwingupPlan, comparing=None) -> SwingupReport | RotarySwingupReport:
    """Design and patch the spec, pump its pendulum up, hand off and hold on the bench.

    Parameters
    ----------
    inputs : Inputs
        The spec, machine and bench, resolved and checked.
    plan : SwingupPlan
        Strategy, force limit, hold, seed, comparison.
    comparing : callable, optional
        A context manager factory wrapped around the comparison (a progress note while it runs).

    Returns
    -------
    SwingupReport
        The manoeuvre and, when asked, the strategies compared.
    """
    spec, machine, bench = inputs
    if spec.plant_model is not CART:
        return run_rotary_swingup(inputs, plan)
    d = design_on(spec, machine, bench)
    net = scaled_patch(d, machine, bench).netlist
    plant = as_on_bench(d.plant, bench)
    force = plan.force_limit_N or bench.actuator.force_limit_N
    m = manoeuvre(net, plant, bench, machine, d.K[:, :4], plan.strategy, force, plan.hold_s, plan.seed)
    comparison = None
    if plan.compare:
        if comparing is None:
            comparison = tuple(compare_strategies(plant, force, d.K[:, :4], m.zone))
        else:
            with comparing():
                comparison = tuple(compare_strategies(plant, force, d.K[:, :4], m.zone))
    judged = as_patched_on_bench(d, net, machine, bench)
    pred = predict_on_bench(d, net, machine, bench, plan.sheet_runs_hold)
    return SwingupReport(d, net, plant, plan, force, m, comparison, judged, pred)
