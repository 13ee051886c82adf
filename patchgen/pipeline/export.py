"""patchgen export: the spec's patch as the configuration a programmed machine loads (the LUCIDAC),
checked by its client library's own sanity check, into a report whose ``summary()`` is ``--json``."""

from __future__ import annotations

from dataclasses import dataclass

from patchgen.design.lqg import design_on
from patchgen.inputs.errors import InputError
from patchgen.lucidac.config import configuration, lucipy_module
from patchgen.lucidac.plan import LanePlan, plan
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.prediction import BenchPrediction, predict_on_bench
from patchgen.pipeline.scaling import scaled_patch
from patchgen.profiles.machine import the_machine


@dataclass(frozen=True)
class ExportPlan:
    """How long the run script runs: the scenario's duration (s), or until stopped (None)."""

    run_s: float | None = None
    scenario: str | None = None


@dataclass(frozen=True)
class ExportReport:
    """The patch, its placement on the machine, the configuration, the client's warnings, and the
    patch predicted on the bench (as patchgen patch's sheet predicts it)."""

    netlist: Netlist
    lanes: LanePlan
    config: dict
    warnings: tuple[str, ...]
    plan: ExportPlan
    prediction: BenchPrediction | None = None

    def summary(self) -> dict:
        """Every figure the command prints, as plain JSON-able data (--json)."""
        return {"design": self.netlist.design, "machine": self.netlist.machine,
                "elements": {e.name: e.carries for e in self.lanes.elements},
                "lanes": len(self.lanes.lanes),
                "sensor_inputs": dict(self.lanes.sensor_acl), "output": self.lanes.output_acl,
                "run_s": self.plan.run_s,
                "sanity_warnings": list(self.warnings),
                "prediction": None if self.prediction is None else self.prediction.summary()}


def check_programmed(inputs: Inputs) -> None:
    """Refuse, before anything is computed, a machine that is patched rather than programmed, or
    a machine's export without its client library."""
    if not inputs.machine.programmed:
        raise InputError("--machine", inputs.machine.id, f"export targets programmed machines (lucidac); "
                         f"{the_machine(inputs.machine.name)} is patched: use patchgen patch")
    lucipy_module()  # the client library builds the configuration: without it, say so before computing


def run_export(inputs: Inputs, export_plan: ExportPlan = ExportPlan()) -> ExportReport:
    """Design and patch the spec on its (programmed) machine, place the netlist on the machine's
    elements and lanes, build the configuration with the client library, and predict the patch on
    the bench (patchgen.pipeline.prediction)."""
    check_programmed(inputs)
    spec, machine, bench = inputs
    d = design_on(spec, machine, bench)
    scaled = scaled_patch(d, machine, bench)  # the patch every command builds
    net = scaled.netlist
    lanes = plan(net, machine)
    config, warnings = configuration(lanes)
    pred = predict_on_bench(d, net, machine, bench, done=scaled.runs)  # a patch that falls is not handed out unsaid
    return ExportReport(net, lanes, config, tuple(warnings), export_plan, pred)
