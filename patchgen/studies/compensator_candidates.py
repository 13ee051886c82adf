"""Recommend's candidates for a compensator patched as one system: each Kalman candidate again,
realised by patchgen.patch.compensator_fit at its full order and at every lower order, on the
fewest slaved units that take it (up to the spec's max_units, else the profile's)."""

from __future__ import annotations

from patchgen.inputs.errors import InputError
from patchgen.inputs.spec import DesignSpec
from patchgen.patch.compensator_fit import laws
from patchgen.profiles.bench import BenchProfile
from patchgen.profiles.machine import MachineProfile
from patchgen.studies.design_memo import designed


def compensator_specs(specs: list[tuple[str, str, DesignSpec]], machine: MachineProfile,
                      bench: BenchProfile) -> list[tuple[str, str, DesignSpec]]:
    """For each Kalman candidate of ``specs``, the compensator as one system at each order.

    Parameters
    ----------
    specs : list of (label, kind, DesignSpec)
        Recommend's candidates (patchgen.studies.recommend.candidate_specs).
    machine, bench : MachineProfile, BenchProfile
        What the candidates are designed for.

    Returns
    -------
    list of (label, kind, DesignSpec)
        Highest order first; a Kalman candidate that does not design gives none.
    """
    out = []
    for label, kind, sp in specs:
        if kind != "kalman" or sp.patch.realization == "compensator":
            continue
        try:
            full = laws(designed(sp, machine, bench), machine, "truncate")[0][0]
        except (InputError, ValueError):
            continue
        for order in range(full, 0, -1):
            patch = sp.patch.model_copy(update={"realization": "compensator", "units": "auto",
                                                "order": "full" if order == full else order})
            out.append((f"{label}, compensator as one system, order {order}", kind,
                        sp.model_copy(update={"patch": patch})))
    return out
