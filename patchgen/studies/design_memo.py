"""Designs remembered by what they are computed from, for the studies that design many specs.

Recommend designs every candidate's spec, and many of one run differ only in how they are patched:
the compensator candidates at each order, a variant that leaves small coefficients out, the
variants of one tier that share their weights. The design does not read the spec's ``[patch]``
table, so one design serves every spec that differs only there (its ``spec`` swapped in).
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import replace

from patchgen.design.lqg import Design, design_on
from patchgen.inputs.spec import DesignSpec
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile

SIZE = 128  # designs kept (recommend thesis-ch5 makes 48 distinct ones in 221 calls)

_kept: OrderedDict[str, Design] = OrderedDict()


def designed(spec: DesignSpec, machine: MachineProfile, bench: BenchProfile | None) -> Design:
    """:func:`patchgen.design.lqg.design_on` of ``spec``, computed once for every spec equal to it
    but for ``[patch]`` (and for the same file, machine roll-off and bench); a design that fails is
    not kept, so its error is raised again each time."""
    key = "\n".join((spec.path, spec.model_dump_json(exclude={"patch"}),
                     repr(machine.imperfections.differentiator_rolloff_s),
                     "" if bench is None else bench.model_dump_json()))
    d = _kept.get(key)
    if d is None:
        d = _kept[key] = design_on(spec, machine, bench)
        if len(_kept) > SIZE:
            _kept.popitem(last=False)
    else:
        _kept.move_to_end(key)
    return d if d.spec is spec else replace(d, spec=spec)
