"""The patch stage: design + machine -> netlist (scaling, then allocation)."""

from __future__ import annotations

from .allocation import allocate
from .design import Design
from .errors import ResourceError
from .machine import MachineProfile
from .netlist import Netlist
from .realization import realize


def build_patch(design: Design, machine: MachineProfile, units: int | str | None = None) -> Netlist:
    """Scale the design into machine volts and place it on ``units`` slaved machines (default: the
    spec's [patch] units; "auto" takes the fewest that fit, up to the profile's max_units)."""
    spec = design.spec
    units = spec.patch.units if units is None else units
    real = realize(design, machine)
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


def _place(design: Design, real, machine: MachineProfile, units: int) -> Netlist:
    net = allocate(real, machine.slaved(units), design.spec.path)
    return net.model_copy(update={"description": design.spec.description, "units": units,
                                  "machine_name": machine.name})
