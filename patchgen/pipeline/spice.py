"""patchgen spice as two functions: the deck of the spec's patch on its bench (written even where
ngspice is missing), then ngspice's run compared with patchgen's own simulation of the same
scenario, into a report whose ``summary()`` is comparison.json and ``--json``.

Ideal, both runs are the same deterministic circuit and the verdict is point by point (every
signal within the tolerance of its peak). With noise, each simulator draws its own realisation:
the verdict is statistical (patchgen.spice.verdict), ngspice's run against patchgen's Monte Carlo,
and the point-by-point differences from the Monte Carlo's first run are reported as information.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.bench.noise_drift import noise_and_drift
from patchgen.bench.simulate import simulate
from patchgen.design.lqg import Design, design_on
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.patch.netlist import Netlist
from patchgen.pipeline.inputs import Inputs
from patchgen.pipeline.scaling import scaled_patch
from patchgen.plant.equations import PlantParams
from patchgen.plant.plant_model import CART
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.measured_plant import as_on_bench
from patchgen.spice.compare import Comparison, compare
from patchgen.spice.deck import OPAMP_MODEL, SpiceDeck, SpiceSettings, spice_deck
from patchgen.spice.run import SpiceResult, run_ngspice
from patchgen.spice.verdict import MC_RUNS, StatisticalVerdict, run_figures, statistical_verdict

RECORD_EVERY_STEP_S = 1e-6  # a history interval below any engine step: the reference at every step
# ngspice's relative tolerance with noise on: SPICE's own default. The statistical verdict needs
# ngspice's run to within a small part of the Monte Carlo's spread, not to 1e-5 (the ideal check's):
# measured on a 20 s hold, the figures move by at most 6 % of the Monte Carlo's 5-95 % width between
# the two, and ngspice runs four times faster.
NOISY_RELTOL = 1e-3


@dataclass(frozen=True)
class SpicePlan:
    """Ideal (noise, drift off, the actuator a pure gain) or the bench's; the transient's output
    step (s); the agreement required, as a fraction of each signal's peak."""

    ideal: bool = False
    step_s: float = 0.005
    tolerance: float = 0.01


@dataclass(frozen=True)
class SpiceJob:
    """The deck of a patch on its bench, and what the comparison needs to run after it."""

    design: Design
    netlist: Netlist
    plant: PlantParams
    bench: BenchProfile
    machine: MachineProfile
    scenario: Scenario
    plan: SpicePlan
    deck: SpiceDeck
    settings: SpiceSettings | None = None  # what the deck was written from (another seed: another deck)


@dataclass(frozen=True)
class SpiceReport:
    """ngspice's run against patchgen's: the comparison, ngspice's run time and its data file;
    with noise, the statistical verdict (None: ideal, the verdict is the comparison's)."""

    job: SpiceJob
    comparison: Comparison
    run_time_s: float
    data: bytes | None
    statistical: StatisticalVerdict | None = None

    @property
    def agrees(self) -> bool:
        """The verdict: ideal, every signal within the tolerance of its peak; else statistical."""
        if self.statistical is None:
            return self.comparison.agrees(self.job.plan.tolerance)
        return self.statistical.agrees

    @property
    def compared_at(self) -> str:
        """Where the runs were compared: ngspice's own time points, or (a deck with noise) its
        solution at the output step."""
        n, step = len(self.comparison.t), self.job.deck.output_step_s
        return f"ngspice's {n} time points" if step is None else f"{n} points of ngspice's solution, every {step:g} s"

    def summary(self) -> dict:
        """Every figure and the verdict, as plain JSON-able data (comparison.json, --json)."""
        cmp, plan = self.comparison, self.job.plan
        out = {"design": self.job.design.spec.name, "scenario": self.job.scenario.name, "ideal": plan.ideal,
               "tolerance": plan.tolerance, "ngspice_run_time_s": self.run_time_s,
               "compared_at": self.compared_at, "opamp_model": OPAMP_MODEL,
               "statistical": not plan.ideal,
               "signals": {k: {"rms_rel": v.rms_rel, "max_rel": v.max_rel, "peak": v.peak}
                           for k, v in cmp.signals.items()},
               "agrees": self.agrees}
        if self.statistical is not None:  # the point-by-point figures are information; no tolerance applies
            del out["tolerance"]
            out["signals_information_only"] = True
            out["verdict"] = self.statistical.as_dict()
        return out


class _Own:
    """patchgen's own run as a trajectory (t and named signals, SI and volts)."""

    def __init__(self, history: dict[str, np.ndarray]):
        self.t = history["t"]
        self.signals = {k: v for k, v in history.items() if k != "t"}


def spice_job(inputs: Inputs, scenario: Scenario, plan: SpicePlan) -> SpiceJob:
    """Design and patch the spec, and write its deck for the scenario (SPICE settings from the
    profiles or, ideal, with noise and drift off and the actuator a pure gain)."""
    spec, machine, bench = inputs
    if machine.programmed:  # its elements are not op-amps with resistors and capacitors a deck could model
        raise InputError(spec.path, "machine", f"{machine.name} is programmed, not patched: its profile's "
                         "[components] are placeholders and no SPICE deck models it; patchgen export writes the "
                         "configuration it loads, which its client's simulator checks")
    d = design_on(spec, machine, bench)
    net = scaled_patch(d, machine, bench).netlist
    plant = as_on_bench(d.plant, bench)
    levels = noise_and_drift([s.id for s in net.sensors], bench, machine, scenario, plan.ideal)
    noisy = {} if plan.ideal else {"reltol": NOISY_RELTOL, "noise_step_s": engine_step(net, plant, bench, machine,
                                                                                        scenario)}
    pm = spec.plant_model
    pushes = scenario.on_pendulum(plant) if pm is CART else scenario.on_arm(plant)
    settings = SpiceSettings(duration_s=scenario.duration_s, step_s=plan.step_s,
                             x0=tuple(scenario.initial.vector(pm)), noise_and_drift=levels,
                             actuator="ideal" if plan.ideal else "bench", seed=scenario.seed,
                             disturbances=tuple(pushes.disturbances), **noisy)
    deck = spice_deck(_settled(net, plant, bench, machine, scenario), plant, bench, machine, settings)
    return SpiceJob(d, net, plant, bench, machine, scenario, plan, deck, settings)


def _settled(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
             scenario: Scenario) -> Netlist:
    """The netlist with each integrator that starts settled on its input (no IC: the lag of a
    difference) given, as its IC, the value patchgen's simulator settles it at for this scenario's
    start: a deck's operating point holds an IC, it does not settle one."""
    settling = [a.id for a in net.amplifiers if a.role == "integrator" and a.ic_V is None]
    if not settling:
        return net
    brief = scenario.model_copy(update={"duration_s": scenario.dt_s or 1e-3})  # its start is all it is run for
    start = simulate(net, plant, bench, machine, brief, ideal=True).history  # noise-free (offsets: a 6 ms lag's)
    return net.model_copy(update={"amplifiers": [
        a.model_copy(update={"ic_V": float(start[a.id][0])}) if a.id in settling else a for a in net.amplifiers]})


def engine_step(net: Netlist, plant: PlantParams, bench: BenchProfile, machine: MachineProfile,
                scenario: Scenario) -> float:
    """The step (s) patchgen's engine takes on the scenario with noise on: its noise carries no
    band above this step's Nyquist frequency, so neither need the deck's."""
    return engine_config(compile_circuit(net, machine, bench), plant, bench, machine, scenario)[1].dt_s


def run_spice(job: SpiceJob) -> SpiceReport:
    """Run the deck in ngspice and compare with patchgen's own run at every step of its
    integrator, evaluated at the points ngspice wrote (its own, or the output step's); with
    noise, judge ngspice's run against patchgen's Monte Carlo (MC_RUNS runs; the first is the
    run compared point by point).

    Raises
    ------
    patchgen.spice.run.NgspiceMissing, patchgen.spice.run.NgspiceError
        Without ngspice, or when it fails (the deck is still worth writing).
    """
    with tempfile.TemporaryDirectory() as tmp:
        result = run_ngspice(job.deck, tmp)
        path = Path(tmp, "patch.data")
        data = path.read_bytes() if path.exists() else None
    every_step = job.scenario.model_copy(update={"record_dt_s": RECORD_EVERY_STEP_S})
    runs = 1 if job.plan.ideal else MC_RUNS
    own = simulate(job.netlist, job.plant, job.bench, job.machine, every_step, ideal=job.plan.ideal, runs=runs)
    pm = job.design.spec.plant_model
    cmp = compare(result, _Own(own.history), (pm.angle, pm.position))
    if job.plan.ideal:
        return SpiceReport(job, cmp, result.run_time_s, data)
    return SpiceReport(job, cmp, result.run_time_s, data, statistical_verdict(_figures(job, result), own.runs))


def _figures(job: SpiceJob, result: SpiceResult):
    """ngspice's run's figures, counted as the engine counts a run's."""
    pm = job.design.spec.plant_model
    if pm is CART:
        cut = job.bench.track.cut_at(job.plant.d)
    else:  # the cable's wind-up ends a rotary pendulum's run
        cut = job.plant.alpha_limit if math.isfinite(job.plant.alpha_limit) else None
    return run_figures(result.t, result.signals[pm.position], result.signals[pm.angle], cut,
                       math.radians(job.scenario.fall_angle_deg))
