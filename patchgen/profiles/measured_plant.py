"""The plant as a bench has it: a bench profile's ``[measured_plant]`` figures in place of the
spec's where a lab measured its own plant differently.

A design is made for the spec's [plant] (a manufacturer's figures, say); the bench's own pendulum
may differ (its free swing, weighed links, identify's plant.toml). Every bench stage (the kernel,
the bench's linear loop, the SPICE deck, the swing-up's pump, bench-test) simulates the plant with
the bench's measured figures, while the design keeps the spec's: the mismatch the thesis's bench
met is then simulated, not assumed away.
"""

from __future__ import annotations

from dataclasses import replace

from patchgen.inputs.errors import InputError
from patchgen.plant.plant_model import PLANT_MODELS


def check_measured(bench, source: str) -> None:
    """Every ``[measured_plant]`` key is a parameter of the bench's plant, inside its physical bounds.

    Raises
    ------
    InputError
        Naming ``measured_plant.<key>`` in ``source``.
    """
    pm = PLANT_MODELS[bench.plant]
    bounds = {p.name: p for p in pm.parameters}
    for key, value in bench.measured_plant.items():
        field = f"measured_plant.{key}"
        if key not in bounds:
            raise InputError(source, field, f"not a parameter of the {pm.name} (its parameters: "
                             + ", ".join(bounds) + ")")
        p = bounds[key]
        if not p.lo <= value <= p.hi:  # finite already: the profile's numbers are (inputs.fields.Real)
            raise InputError(source, field, f"{value:g} {p.unit} is outside its physical bounds [{p.lo:g}, {p.hi:g}]")


def as_on_bench(plant, bench):
    """The plant the bench simulates: ``plant`` (the spec's) with the bench's measured figures in place.

    Parameters
    ----------
    plant : PlantParams or RotaryParams
        The spec's plant.
    bench : BenchProfile
        Its ``measured_plant`` figures replace the spec's (none: ``plant`` itself).

    Returns
    -------
    PlantParams or RotaryParams
    """
    measured = getattr(bench, "measured_plant", None)
    return replace(plant, **measured) if measured else plant


def scaled_measured(bench, factors: dict[str, float]):
    """The bench with its measured figures scaled as a sweep scales the spec's (a sweep's row puts
    the plant off by a factor: the bench's own figure, where it has one, is put off by the same)."""
    hit = {k: v * factors[k] for k, v in bench.measured_plant.items() if k in factors}
    return bench.model_copy(update={"measured_plant": {**bench.measured_plant, **hit}}) if hit else bench


def measured_words(plant, bench) -> list[str]:
    """One phrase per measured figure that differs from the spec's, e.g. ``D_p = 5e-05 (spec 0.0005)``."""
    return [f"{k} = {v:g} (spec {getattr(plant, k):g})" for k, v in getattr(bench, "measured_plant", {}).items()
            if getattr(plant, k) != v]
