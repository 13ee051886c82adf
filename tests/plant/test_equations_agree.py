"""The plant's equations in their three forms agree: numpy (patchgen.plant.equations), compiled
(patchgen.plant.compiled, with a push at the tip) and the SPICE behavioural expressions
(patchgen.plant.behavioural, evaluated here as Python), on random plants and states; and a push
at the tip does the work of its generalised forces, checked against the numpy form with the
push's forces added by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from patchgen.plant.behavioural import accelerations
from patchgen.plant.cart_pendulum import PARAMETERS
from patchgen.plant.compiled import plant_rhs, plant_vector
from patchgen.plant.equations import PlantParams, nonlinear_rhs

CASES = 200


def _plant(rng) -> PlantParams:
    """A random plant within the bounds, each parameter drawn on a log scale (friction may be 0)."""
    out = {}
    for p in PARAMETERS:
        lo = max(p.lo, 1e-3)
        out[p.name] = 0.0 if p.lo == 0 and rng.random() < 0.2 else float(math.exp(rng.uniform(math.log(lo),
                                                                                              math.log(p.hi))))
    return PlantParams(**out)


def _spice(plant: PlantParams, th, sd, thd, force, tip) -> tuple[float, float]:
    sdd_expr, thdd_expr = accelerations(plant, repr, "th", "sd", "thd", "F", "T" if tip else "", "SDD")
    names = {"sin": math.sin, "cos": math.cos, "th": th, "sd": sd, "thd": thd, "F": force, "T": tip}
    sdd = eval(sdd_expr, {"__builtins__": {}}, names)  # noqa: S307 - the plant's own expressions
    return sdd, eval(thdd_expr, {"__builtins__": {}}, {**names, "SDD": sdd})  # noqa: S307


@pytest.mark.parametrize("seed", range(4))
def test_numpy_compiled_and_spice_forms_agree(seed):
    rng = np.random.default_rng(seed)
    for _ in range(CASES // 4):
        plant = _plant(rng)
        th, sd, thd = rng.uniform(-3, 3), rng.uniform(-2, 2), rng.uniform(-10, 10)
        force, tip = rng.uniform(-20, 20), rng.uniform(-2, 2) if rng.random() < 0.5 else 0.0
        # the push by hand: generalised forces tip on s and tip l cos(theta) on theta through the
        # mass matrix [[M + m, m l cos], [m l cos, J + m l^2]], added to the numpy form's
        M, m, l = plant.M, plant.m, plant.l
        base = nonlinear_rhs(plant, np.array([0.0, th, sd, thd]), force)
        mass = np.array([[M + m, m * l * math.cos(th)], [m * l * math.cos(th), m * l * l + plant.J]])
        extra = np.linalg.solve(mass, [tip, tip * l * math.cos(th)])
        want = (base[2] + extra[0], base[3] + extra[1])
        compiled = plant_rhs(plant_vector(plant), th, sd, thd, force, tip)[2:]
        spice = _spice(plant, th, sd, thd, force, tip)
        scale = max(1.0, abs(want[0]), abs(want[1]))
        for got in (compiled, spice):
            assert got == pytest.approx(want, rel=1e-9, abs=1e-9 * scale), (plant, th, sd, thd, force, tip)
