"""The patch stage: design + machine -> netlist (scaling, then allocation)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from patchgen.design.lqg import Design
from patchgen.inputs.errors import Cure, InputError, ResourceError
from patchgen.patch import compensator_fit, differences
from patchgen.patch.allocation import allocate
from patchgen.patch.netlist import Netlist
from patchgen.patch.parts import parts_for
from patchgen.patch.realization import Realization, realize
from patchgen.patch.snr_scaling import rescaled
from patchgen.profiles.machine import MachineProfile, the_machine


def build_patch(design: Design, machine: MachineProfile, units: int | str | None = None,
                suggest: bool = True, scales: Mapping[str, float] | None = None) -> Netlist:
    """Scale the design into machine volts and place it on ``units`` slaved machines (default: the
    spec's [patch] units; "auto" takes the fewest that fit, up to the spec's max_units, else the
    profile's). With ``[patch] realization = "compensator"`` the law is placed as one system
    (patchgen.patch.compensator_fit): the spec's order and form, or the cheapest form of the full
    order that fits (at the full order, with its fast modes residualised or kept), first among
    those that keep compensator_fit.KEEP_PM_SHARE of the design's phase margin as dialled.

    A patch that does not fit the spec's own [patch] settings (``units`` not given) is refused
    with the [patch] change that makes it fit, when one does and ``suggest`` asks for it (a study
    that judges the error, not a user, need not pay for the search): :func:`fitting_change`.

    ``scales`` multiplies each named block's voltage, the law unchanged
    (patchgen.patch.snr_scaling.snr_scales chooses them for signal-to-noise): :func:`scaled_placed`
    on the realisation placed."""
    net, real = placed(design, machine, units, suggest)
    return scaled_placed(design, machine, net, real, scales) if scales else net


def placed(design: Design, machine: MachineProfile, units: int | str | None = None,
           suggest: bool = True) -> tuple[Netlist, Realization]:
    """:func:`build_patch`'s patch and the realisation it placed: the law as its states (its
    differentiators built from lags on a machine without them), or the compensator's realisation
    chosen (patchgen.patch.compensator_fit), which a scaling for signal-to-noise rescales."""
    try:
        return _build(design, machine, units)
    except ResourceError as exc:
        cure = fitting_change(design, machine) if units is None and suggest else None
        if cure is None:
            raise
        raise ResourceError(exc.source, exc.field, exc.message, cure) from None


def scaled_placed(design: Design, machine: MachineProfile, net: Netlist, real: Realization,
                  scales: Mapping[str, float]) -> Netlist:
    """``net``, placed from ``real``, with each block's voltage multiplied by its factor
    (patchgen.patch.snr_scaling.rescaled): placed again on as many units, with the notes the
    placement added beyond the allocator's (a compensator's realisations compared)."""
    plain = allocate(real, machine.slaved(net.units), design.spec.path)
    extra = net.notes[len(plain.notes):] if net.notes[:len(plain.notes)] == plain.notes else []
    scaled = rescaled(real, scales)
    _check_law_reaches_pots(scaled, machine, design.spec)
    out = _place(design, scaled, machine, net.units)
    return out.model_copy(update={"notes": [*out.notes, *extra]})


def fitting_change(design: Design, machine: MachineProfile) -> Cure | None:
    """The one [patch] field whose change makes the spec's patch fit the machine, checked by
    building the patch with it: more slaved units (up to the machine profile's max_units), then
    the other realisation (the law as its states, or as one compensator)."""
    spec, p = design.spec, design.spec.patch
    most = machine.max_units
    tries: list[tuple[str, int | str, str]] = []
    if p.units == "auto":
        tries += [("patch.max_units", n, f"lets it take {n} slaved units") for n in range((p.max_units or most) + 1,
                                                                                          most + 1)]
    else:
        tries += [("patch.units", n, f"places it on {n} slaved units") for n in range(p.units + 1, most + 1)]
    if design.controller is not None:
        other = "compensator" if p.realization == "states" else "states"
        tries.append(("patch.realization", other, "fits it"))
    for field, value, gives in tries:
        try:
            net = _build(replace(design, spec=spec.changed(field, value)), machine, None)[0]
        except InputError:  # it does not fit, or that realisation refuses the law for its own reason
            continue
        if field == "patch.realization":
            gives = f"fits it on {net.units} unit{'s' if net.units > 1 else ''}"
        return Cure(field, value, gives)
    return None


def _build(design: Design, machine: MachineProfile, units: int | str | None) -> tuple[Netlist, Realization]:
    """:func:`placed` without a suggestion."""
    spec = design.spec
    units = spec.patch.units if units is None else units
    cap = spec.patch.max_units or machine.max_units
    tries = list(range(1, cap + 1)) if units == "auto" else [units]
    if spec.patch.realization == "compensator" and design.controller is not None:
        return _place_compensator(design, machine, tries)  # plain state feedback has no other form
    real = differences.without_differentiators(realize(design, machine), machine)
    _check_law_reaches_pots(real, machine, spec)
    for n in tries:
        try:
            return _place(design, real, machine, n), real
        except ResourceError:
            if n == tries[-1]:
                raise
    raise AssertionError("unreachable")


def _place_compensator(design: Design, machine: MachineProfile, tries: list[int]) -> tuple[Netlist, Realization]:
    """The compensator at the spec's order and form on the fewest of ``tries`` units that takes it."""
    spec = design.spec
    p = spec.patch
    full = compensator_fit.laws(design, machine, "truncate")[0][0]
    if p.order != "full" and p.order > full:
        raise spec.error("patch.order", f"the minimal compensator has {full} states (got {p.order})")
    order = full if p.order == "full" else p.order
    tried = compensator_fit.fits(design, machine, tries, p.form, p.reduction, [order], fast_kept=p.order == "full")
    chosen = compensator_fit.best(tried, design.lqg_margins)
    if chosen is None:  # the spec's order all unstable is the design's fault, whether the fast modes kept fit or not
        own = [f for f in tried if f.method != compensator_fit.FAST_KEPT]
        if own and all(f.error == compensator_fit.UNSTABLE_LAW for f in own):
            raise _degenerate(design, order, full)
        raise ResourceError(spec.path, "machine", no_fit_line(tried, machine, tries[-1]))
    net = chosen.netlist
    notes = list(net.notes) + [f"realisation compared: {f.line()}" for f in tried] + _choice_notes(chosen, design)
    net = net.model_copy(update={"description": spec.description, "notes": notes})
    return net.model_copy(update={"parts": parts_for(net, machine)}), chosen.real


def _choice_notes(chosen: compensator_fit.Fit, design: Design) -> list[str]:
    """A note when the realisation patched keeps less than KEEP_PM_SHARE of the design's phase
    margin as dialled: none tried that fits the machine keeps it (compensator_fit.best)."""
    designed = design.lqg_margins
    if compensator_fit.keeps_margin(chosen, designed):
        return []
    m = chosen.dialled_margins
    return [f"no realisation tried keeps {100 * compensator_fit.KEEP_PM_SHARE:.0f} % of the design's phase margin "
            f"({designed.pm_deg:.1f} deg) as dialled; the one patched keeps {m.pm_deg:.1f} deg"]


def _degenerate(design: Design, order: int, full: int):
    """The design's own fault: no form of its compensator keeps the loop stable on the design model."""
    spec, e = design.spec, design.estimator
    what = (f"no form of the order-{order} compensator keeps the loop stable on the design model (the machine "
            "is not tried)")
    if order < full:
        return spec.error("patch.order", f"{what}: the reduction drops a mode the loop needs (the minimal "
                          f"compensator has {full} states)")
    if e is not None and e.kind == "kalman" and spec.estimator.rho != "auto":
        slow = -float(max(e.poles.real))
        return spec.error("estimator.rho", f"{what}: at rho = {e.rho:g} the filter's slowest pole is at "
                          f"-{slow:.3g} 1/s and the compensator all but cancels it; a larger rho or W")
    return spec.error("patch.realization", f"{what}: the law as one system loses a mode the loop needs; "
                      "realization = 'states' wires the estimator as its states")


def no_fit_line(tried: list, machine: MachineProfile, cap: int) -> str:
    """One line: the smallest realisation found and what it needs."""
    short = [f for f in tried if f.error is not None and "unstable" not in f.error]
    if not short:
        placed = [f for f in tried if f.netlist is not None]
        if placed:
            f = min(placed, key=lambda f: f.peak_fraction)
            return (f"no realisation keeps every amplifier within the reference and the loop stable as dialled; "
                    f"the nearest, order {f.order} in {f.form} form, reaches {f.peak_fraction:.2f} of the reference")
        return "no realisation of the compensator at this order keeps the loop stable"
    f = short[0]
    return (f"no realisation fits {cap} unit(s) of {the_machine(machine.name)}; the smallest tried, order {f.order} "
            f"({f.method}) in {f.form} form: {f.error}")


def _check_law_reaches_pots(real, machine: MachineProfile, spec) -> None:
    """Refuse a patch whose control voltage would have every pot from the plant's signals at the
    dial's resolution floor: it would realise nothing of the law (K_U, the force per command volt,
    divides every such gain; the actuator model's own feedback does not see the plant)."""
    res = machine.pot_resolution
    mags = [abs(t.coeff) for t in real.block("u_c").terms if t.coeff != 0 and "actuator" not in t.signal]
    if not mags or max(mags) < 1.5 * res:
        largest = f"{max(mags):.3g}" if mags else "0"
        raise spec.error("actuator.K_U", f"every coefficient from the plant's signals to the control voltage "
                         f"(K_i / (sensor constant x K_U), largest {largest}) would land at the pot resolution "
                         f"{res:g} or below: the patch would realise nothing of the law with K_U = {real.K_U:g} N/V "
                         "(a smaller K_U or larger gains scale the coefficients up)")


def _place(design: Design, real, machine: MachineProfile, units: int) -> Netlist:
    net = allocate(real, machine.slaved(units), design.spec.path)
    net = net.model_copy(update={"description": design.spec.description, "units": units,
                                 "machine_name": machine.name})
    return net.model_copy(update={"parts": parts_for(net, machine)})
