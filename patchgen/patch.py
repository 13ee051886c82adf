"""The patch stage: design + machine -> netlist (scaling, then allocation)."""

from __future__ import annotations

from .allocation import allocate
from .design import Design
from .machine import MachineProfile
from .netlist import Netlist
from .realization import realize


def build_patch(design: Design, machine: MachineProfile) -> Netlist:
    """Scale the design into machine volts and place it on the machine."""
    real = realize(design, machine)
    net = allocate(real, machine, design.spec.path)
    return net.model_copy(update={"description": design.spec.description})
