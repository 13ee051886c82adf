"""The LUCIDAC configuration, built with the maintained client library (lucipy) from a lane plan.

lucipy is an optional extra (``pip install patchgen[lucidac]``): it is imported here, when a
configuration is asked for, and its absence is one line naming the extra.
"""

from __future__ import annotations

from patchgen.inputs.errors import InputError
from patchgen.lucidac.plan import LanePlan

EXTRA = "lucidac"  # the optional dependency that installs lucipy (pyproject.toml)


def lucipy_module():
    """The lucipy package, or an InputError naming the extra that installs it."""
    try:
        import lucipy
    except ImportError:
        raise InputError("machine", "lucidac", f"exporting to the LUCIDAC needs lucipy: pip install "
                         f"'patchgen[{EXTRA}]'") from None
    return lucipy


def circuit(plan: LanePlan):
    """A lucipy Circuit of the plan: integrators with their k0 and IC 0, front-panel routes first
    (their lanes are fixed: ACL n is lane 24 + n), then every other lane in the plan's order; u_c's
    element on ADC channel 0."""
    lucipy = lucipy_module()
    from lucipy.circuits import Id

    c = lucipy.Circuit()
    el = {}
    for e in plan.elements:
        if e.kind == "int":
            el[e.name] = c.int(id=e.index, ic=0.0, slow=e.k0_per_s == plan.slow_k0_per_s)
        else:
            el[e.name] = c.alloc(Id, e.index)
    for lane in plan.lanes:
        if lane.source.startswith("ACL_IN"):
            c.connect(c.front_panel(int(lane.source.split()[1])), el[lane.target])
        elif lane.target.startswith("ACL_OUT"):
            c.connect(el[lane.source], c.front_panel(int(lane.target.split()[1])), weight=lane.coeff)
    for lane in plan.lanes:
        if not (lane.source.startswith("ACL_IN") or lane.target.startswith("ACL_OUT")):
            c.connect(el[lane.source], el[lane.target], weight=lane.coeff)
    out = next(ln.source for ln in plan.lanes if ln.target.startswith("ACL_OUT"))
    c.measure(el[out], adc_channel=0)  # u_c recorded by the ADC during a run, as on the front panel
    return c


def configuration(plan: LanePlan) -> tuple[dict, list[str]]:
    """The configuration the machine loads (lucipy's Circuit.generate) and lucipy's sanity-check
    warnings (an empty list when it finds nothing)."""
    c = circuit(plan)
    warnings = c.sanity_check(also_print=False)
    return c.generate(sanity_check=False), warnings
