"""The patch stage: design + machine -> netlist (scaling, then allocation)."""

from __future__ import annotations

from patchgen.design.lqg import Design
from patchgen.inputs.errors import ResourceError
from patchgen.patch.allocation import allocate
from patchgen.patch.netlist import Netlist
from patchgen.patch.parts import parts_for
from patchgen.patch.realization import realize
from patchgen.profiles.machine import MachineProfile


def build_patch(design: Design, machine: MachineProfile, units: int | str | None = None) -> Netlist:
    """Scale the design into machine volts and place it on ``units`` slaved machines (default: the
    spec's [patch] units; "auto" takes the fewest that fit, up to the profile's max_units)."""
    spec = design.spec
    units = spec.patch.units if units is None else units
    real = realize(design, machine)
    _check_law_reaches_pots(real, machine, spec)
    if units == "auto":
        for n in range(1, machine.max_units + 1):
            try:
                return _place(design, real, machine, n)
            except ResourceError:
                if n == machine.max_units:
                    raise
    if not 1 <= units <= machine.max_units:
        raise spec.error("patch.units", f"the {machine.name} profile allows 1 to {machine.max_units} slaved units "
                         f"(got {units})")
    return _place(design, real, machine, units)


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
