"""Robustness sweeps: the design re-run with plant parameters off by a given fraction
(thesis tables 4.1 and 4.2), with margins, changed pot settings and, when a simulator
outcome function is given, the predicted outcome of the nominal patch on each perturbed plant."""

from __future__ import annotations

from collections.abc import Mapping
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

from patchgen.design.lqg import design_on
from patchgen.design.margins import Margins
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.build import build_patch
from patchgen.plant.plant_model import CART, PLANT_MODELS, PlantModel
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.profiles.measured_plant import scaled_measured


def variable(plant: PlantModel) -> tuple[str, ...]:
    """The plant parameters a sweep may vary (its ``scaled``): those a bench may have wrong, and gravity."""
    return plant.uncertain + ("g",)


VARIABLE = variable(CART)  # the cart's
PARALLEL_FROM = 4  # rows from which a process pool pays for its start-up


@dataclass(frozen=True)
class SweepRow:
    """One perturbed plant: its gains and margins, the pots that move, and how the nominal patch does."""

    label: str
    factors: dict[str, float]
    K: list[float]
    lqr_margins: Margins
    lqg_margins: Margins | None
    pot_changes: dict[str, tuple[float, float]] = field(default_factory=dict)  # pot -> (nominal, this row)
    patch_error: str | None = None
    outcome: dict | None = None

    def as_dict(self) -> dict:
        """The row as plain JSON-ready values (``patchgen sweep --json``)."""
        lqg = self.lqg_margins
        return {"case": self.label, "factors": self.factors, "K": self.K,
                "lqr_margins": {"lower_gm_db": self.lqr_margins.lower_gm_db,
                                "upper_gm_db": self.lqr_margins.upper_gm_db, "pm_deg": self.lqr_margins.pm_deg},
                "lqg_margins": None if lqg is None else {"lower_gm_db": lqg.lower_gm_db, "upper_gm_db": lqg.upper_gm_db,
                                                         "pm_deg": lqg.pm_deg, "stable": lqg.stable},
                "pot_changes": self.pot_changes, "patch_error": self.patch_error, "outcome": self.outcome}


def cases(names: list[str], by: float, both_signs: bool = True) -> list[tuple[str, dict[str, float]]]:
    """Nominal, each parameter +by (and -by), then all parameters +by together (as the thesis's last row)."""
    out = [("nominal", {})]
    for n in names:
        out.append((f"{n} +{by:.0%}", {n: 1 + by}))
        if both_signs:
            out.append((f"{n} -{by:.0%}", {n: 1 - by}))
    out.append((f"all +{by:.0%}", {n: 1 + by for n in names}))
    return out


def _outcome(net, plant, machine, bench, sc: Scenario, runs) -> dict:
    """The nominal patch (as wired) on this plant, with the bench actuator, noise and drift, and
    the wired loop's linear verdict on the bench (patchgen.bench.diagnosis, as simulate, the
    sheet and recommend give it)."""
    from patchgen.bench.diagnosis import diagnose
    from patchgen.bench.simulate import simulate

    r = simulate(net, plant, bench, machine, sc, runs=runs, keep_history=False)
    return {"scenario": sc.name, "runs": runs, "fraction_held": r.distribution.fraction_held,
            "bench_loop": diagnose(net, plant, bench)[-1].verdict,
            "max_abs_theta_deg": max(x.max_abs_theta_deg for x in r.runs),
            PLANT_MODELS[r.settings.plant].position_key: max(x.max_abs_s_m for x in r.runs)}


def _row(args) -> SweepRow:
    spec, machine, bench, label, factors, nominal_pots, nominal_net, scenario, runs, scales = args
    plant = plant_params(spec).scaled(**factors)
    d = design_on(spec, machine, bench, plant=plant)
    changes: dict[str, tuple[float, float]] = {}
    err = None
    try:
        net = build_patch(d, machine, suggest=False, scales=scales)
        for p in net.pots:
            if p.id in nominal_pots and nominal_pots[p.id] != p.setting:
                changes[p.id] = (nominal_pots[p.id], p.setting)
    except InputError as exc:
        err = exc.message
    outcome = None
    if nominal_net is not None and scenario is not None:
        outcome = _outcome(nominal_net, plant, machine, scaled_measured(bench, factors), scenario, runs)
    return SweepRow(label=label, factors=factors, K=[float(k) for k in d.K[0]], lqr_margins=d.lqr_margins,
                    lqg_margins=d.lqg_margins, pot_changes=changes, patch_error=err, outcome=outcome)


def sweep(spec: DesignSpec, machine: MachineProfile, names: list[str], by: float, workers: int = 0,
          scenario: Scenario | None = None, runs: int = 1, *, bench: BenchProfile | None = None,
          scales: Mapping[str, float] | None = None) -> list[SweepRow]:
    """Design for each perturbed plant (see :func:`cases`), rows spread over the computer's cores.

    Parameters
    ----------
    spec : DesignSpec
        The nominal spec.
    machine : MachineProfile
        The machine the patches are allocated on (and its differentiator roll-off).
    names : list of str
        Plant parameters to vary (``variable(spec.plant_model)``).
    by : float
        Relative change, 0 < by < 1.
    workers : int
        Processes; 0: one per core.
    scenario : Scenario, optional
        With a scenario (loaded by the caller), each row also predicts how the nominal patch (as
        wired) does on that plant.
    runs : int
        Noise seeds per row for that prediction.
    bench : BenchProfile, optional
        The bench the spec names, loaded by the caller: needed for the prediction and for an
        estimator shaped for the bench's noise.
    scales : mapping of str to float, optional
        Each block's voltage scale (patchgen.patch.snr_scaling), the same for every patch.

    Returns
    -------
    list of SweepRow
        In the order of :func:`cases`.
    """
    if scenario is not None and bench is None:
        raise ValueError("a sweep's predicted outcome simulates the bench: pass the bench profile")
    nominal = design_on(spec, machine, bench)
    try:
        net = build_patch(nominal, machine, suggest=False, scales=scales)
        nominal_pots = {p.id: p.setting for p in net.pots}
    except InputError:
        net, nominal_pots = None, {}
    jobs = [(spec, machine, bench, label, f, nominal_pots, net, scenario, runs, scales)
            for label, f in cases(names, by)]
    if workers == 1 or len(jobs) < PARALLEL_FROM:
        return [_row(j) for j in jobs]
    with ProcessPoolExecutor(max_workers=workers or None) as ex:
        return list(ex.map(_row, jobs))
