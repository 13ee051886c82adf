"""Robustness sweeps: the design re-run with plant parameters off by a given fraction
(thesis tables 4.1 and 4.2), with margins, changed pot settings and, when a simulator
outcome function is given, the predicted outcome of the nominal patch on each perturbed plant."""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field

from patchgen.design.lqg import design
from patchgen.design.margins import Margins
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.build import build_patch
from patchgen.profiles.machine import MachineProfile

VARIABLE = ("M", "m", "l", "b_VF", "c", "g")


@dataclass(frozen=True)
class SweepRow:
    label: str
    factors: dict[str, float]
    K: list[float]
    lqr_margins: Margins
    lqg_margins: Margins | None
    pot_changes: dict[str, tuple[float, float]] = field(default_factory=dict)  # pot -> (nominal, this row)
    patch_error: str | None = None
    outcome: dict | None = None


def parse_vary(text: str, option: str = "--vary") -> list[str]:
    names = [t.strip() for t in text.split(",") if t.strip()]
    for n in names:
        if n not in VARIABLE:
            raise InputError(option, "", f"unknown parameter {n!r} (choose from {', '.join(VARIABLE)})")
    if not names:
        raise InputError(option, "", "name at least one parameter")
    return names


def parse_by(text: str, option: str = "--by") -> float:
    t = text.strip()
    try:
        v = float(t[:-1]) / 100 if t.endswith("%") else float(t)
    except ValueError:
        raise InputError(option, "", f"{text!r} is not a fraction or a percentage (e.g. 10%)") from None
    if not (0 < v < 1):
        raise InputError(option, "", f"{text!r} must be between 0 and 100%")
    return v


def cases(names: list[str], by: float, both_signs: bool = True) -> list[tuple[str, dict[str, float]]]:
    """Nominal, each parameter +by (and -by), then all parameters +by together (as the thesis's last row)."""
    out = [("nominal", {})]
    for n in names:
        out.append((f"{n} +{by:.0%}", {n: 1 + by}))
        if both_signs:
            out.append((f"{n} -{by:.0%}", {n: 1 - by}))
    out.append((f"all +{by:.0%}", {n: 1 + by for n in names}))
    return out


def _outcome(net, plant, spec, machine, scenario_path, runs) -> dict:
    """The nominal patch (as wired) on this plant, with the bench actuator, noise and drift."""
    from patchgen.bench.simulate import simulate
    from patchgen.inputs.scenario import load_scenario
    from patchgen.profiles.bench import load_bench

    sc = load_scenario(scenario_path)
    r = simulate(net, plant, load_bench(spec.bench, spec.path), machine, sc, runs=runs, keep_history=False)
    return {"scenario": sc.name, "runs": runs, "fraction_held": r.distribution.fraction_held,
            "max_abs_theta_deg": max(x.max_abs_theta_deg for x in r.runs),
            "max_abs_s_m": max(x.max_abs_s_m for x in r.runs)}


def _row(args) -> SweepRow:
    spec, machine, label, factors, rolloff, nominal_pots, nominal_net, scenario_path, runs = args
    plant = plant_params(spec).scaled(**factors)
    d = design(spec, plant=plant, default_rolloff_s=rolloff)
    changes: dict[str, tuple[float, float]] = {}
    err = None
    try:
        net = build_patch(d, machine)
        for p in net.pots:
            if p.id in nominal_pots and nominal_pots[p.id] != p.setting:
                changes[p.id] = (nominal_pots[p.id], p.setting)
    except InputError as exc:
        err = exc.message
    outcome = None
    if nominal_net is not None and scenario_path is not None:
        outcome = _outcome(nominal_net, plant, spec, machine, scenario_path, runs)
    return SweepRow(label, factors, [float(k) for k in d.K[0]], d.lqr_margins, d.lqg_margins, changes, err,
                    outcome)


def sweep(spec: DesignSpec, machine: MachineProfile, names: list[str], by: float, workers: int = 0,
          scenario_path=None, runs: int = 1) -> list[SweepRow]:
    """Design for each perturbed plant, rows spread over the machine's cores (workers=0: all).
    With a scenario, each row also predicts how the nominal patch (as wired) does on that plant."""
    rolloff = machine.imperfections.differentiator_rolloff_s
    nominal = design(spec, default_rolloff_s=rolloff)
    try:
        net = build_patch(nominal, machine)
        nominal_pots = {p.id: p.setting for p in net.pots}
    except InputError:
        net, nominal_pots = None, {}
    jobs = [(spec, machine, label, f, rolloff, nominal_pots, net, scenario_path, runs) for label, f in cases(names, by)]
    if workers == 1 or len(jobs) < 4:
        return [_row(j) for j in jobs]
    with ProcessPoolExecutor(max_workers=workers or None) as ex:
        return list(ex.map(_row, jobs))
