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
    names = {"sin": math.sin, "cos": math.cos, "tanh": math.tanh, "th": th, "sd": sd, "thd": thd, "F": force, "T": tip}
    sdd = eval(sdd_expr, {"__builtins__": {}}, names)  # noqa: S307 - the plant's own expressions
    return sdd, eval(thdd_expr, {"__builtins__": {}}, {**names, "SDD": sdd})  # noqa: S307


@pytest.mark.parametrize("seed", range(4))
def test_numpy_compiled_and_spice_forms_agree(seed):
    rng = np.random.default_rng(seed)
    for _ in range(CASES // 4):
        plant = _plant(rng)
        # the cart moving (|s_dot| > 10 mm/s: SPICE's Coulomb friction is a smooth sign, 1 - 1e-43 off there)
        th, sd, thd = rng.uniform(-3, 3), rng.choice([-1.0, 1.0]) * rng.uniform(0.01, 2), rng.uniform(-10, 10)
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


def test_coulomb_friction_is_a_force_against_the_motion():
    """F_C on a moving cart is the force -F_C sign(s_dot) (every form); at rest it is none."""
    plant = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090, J=0.003, F_C=0.8)
    viscous = PlantParams(**{**plant.__dict__, "F_C": 0.0})
    for sd in (-0.3, 0.05, 0.0):
        x = np.array([0.0, 0.2, sd, -0.4])
        want = nonlinear_rhs(viscous, x, 3.0 - 0.8 * np.sign(sd))
        np.testing.assert_allclose(nonlinear_rhs(plant, x, 3.0), want, rtol=1e-12)
        np.testing.assert_allclose(plant_rhs(plant_vector(plant), 0.2, sd, -0.4, 3.0, 0.0)[2:], want[2:], rtol=1e-12)


@pytest.mark.parametrize("arm", [0.1, 0.3302, 0.6413])
def test_a_push_at_a_stated_point_is_its_generalised_forces(arm):
    """A push F at ``arm`` from the pivot, applied as the simulator does (a share on the cart, a
    share at l: push_shares), equals the generalised forces F on s and F arm cos(theta) on theta
    through the mass matrix."""
    from patchgen.plant.equations import push_shares
    plant = PlantParams(M=1.07, m=0.230, l=0.3302, g=9.81, b_VF=13.1, c=0.0024, d=0.6, J=0.0078826)
    M, m, l, F = plant.M, plant.m, plant.l, 0.7
    cart, at_l = push_shares(plant, arm)
    for th, sd, thd in ((0.05, 0.1, -0.3), (1.2, -0.4, 2.0), (-2.5, 0.0, 0.7)):
        got = plant_rhs(plant_vector(plant), th, sd, thd, 2.0 + cart * F, at_l * F)[2:]
        mass = np.array([[M + m, m * l * math.cos(th)], [m * l * math.cos(th), m * l * l + plant.J]])
        extra = np.linalg.solve(mass, [F, F * arm * math.cos(th)])
        base = nonlinear_rhs(plant, np.array([0.0, th, sd, thd]), 2.0)
        np.testing.assert_allclose(got, base[2:] + extra, rtol=1e-10, atol=1e-12)
