"""The rigid pendulum (inertia J about its centre of mass, at l from the pivot): its equations
conserve the energy of the Lagrangian they come from, linearise to linear_matrices, and with J = 0
are the thesis's point mass (eq. 2.16-2.19, 2.28) to the last bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from patchgen.plant.equations import PlantParams, linear_matrices, nonlinear_rhs
from patchgen.plant.step import rk4_step
from patchgen.swingup.strategies import pendulum_energy

B1 = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)  # table B.1
# a long rod on a light cart: Quanser's IP02 with its long pendulum (cart and weight, no drive)
ROD = PlantParams(M=0.94, m=0.230, l=0.3302, g=9.81, b_VF=5.4, c=0.0024, d=0.814, J=0.230 * 0.6413**2 / 12)


def energy(p: PlantParams, x: np.ndarray) -> float:
    """T + V of the Lagrangian: T = (M + m) s'^2 / 2 + m l cos(theta) s' theta' + (J + m l^2) theta'^2 / 2,
    V = m g l cos(theta)."""
    _, th, sd, thd = x
    return (0.5 * (p.M + p.m) * sd**2 + p.m * p.l * math.cos(th) * sd * thd + 0.5 * (p.J + p.m * p.l**2) * thd**2
            + p.m * p.g * p.l * math.cos(th))


@pytest.mark.parametrize("J", [0.0, 1e-3, ROD.J, 0.05])
def test_without_friction_the_energy_is_conserved(J):
    p = PlantParams(**{**ROD.__dict__, "b_VF": 0.0, "c": 0.0, "J": J})
    x = np.array([0.0, 0.6, 0.3, -1.0])
    e0 = energy(p, x)
    angles = []
    for _ in range(4000):  # 4 s at 1 ms: RK4's error ~ h^4
        x = rk4_step(p, x, 0.0, 1e-3)
        angles.append(x[1])
    assert energy(p, x) == pytest.approx(e0, rel=1e-9)
    assert np.ptp(angles) > 1.0  # it swung, and the cart with it


@pytest.mark.parametrize("plant", [B1, ROD, PlantParams(**{**ROD.__dict__, "J": 0.02})], ids=["B1", "rod", "heavy"])
def test_the_linear_model_is_the_nonlinear_one_differentiated(plant):
    A, B = linear_matrices(plant)
    eps = 1e-6
    num = np.column_stack([(nonlinear_rhs(plant, eps * e, 0.0) - nonlinear_rhs(plant, -eps * e, 0.0)) / (2 * eps)
                           for e in np.eye(4)])
    np.testing.assert_allclose(A, num, rtol=1e-7, atol=1e-9 * np.abs(A).max())
    dB = (nonlinear_rhs(plant, np.zeros(4), eps) - nonlinear_rhs(plant, np.zeros(4), -eps)) / (2 * eps)
    np.testing.assert_allclose(B[:, 0], dB, rtol=1e-7, atol=1e-12)


def test_a_point_mass_is_the_thesis_s_to_the_last_bit():
    """Eq. 2.28 written as the thesis has it, term by term, against the rigid pendulum at J = 0."""
    M, m, l, g, b, c = B1.M, B1.m, B1.l, B1.g, B1.b_VF, B1.c
    A_thesis = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0],
                         [0.0, -m * g / M, -b / M, c / (M * l)],
                         [0.0, (M + m) * g / (M * l), b / (M * l), -(M + m) * c / (M * m * l * l)]])
    A, B = linear_matrices(B1)
    assert (A == A_thesis).all() and (B[:, 0] == [0.0, 0.0, 1.0 / M, -1.0 / (M * l)]).all()
    x = np.array([0.1, 0.4, -0.3, 1.2])
    sin, cos = math.sin(x[1]), math.cos(x[1])
    sdd = ((-b * x[2] + m * l * x[3] * x[3] * sin + (c / l) * x[3] * cos - m * g * sin * cos + 2.0)
           / ((M + m) - m * cos * cos))
    thdd = -c / (m * l * l) * x[3] + g / l * sin - cos * sdd / l
    assert (nonlinear_rhs(B1, x, 2.0) == [x[2], x[3], sdd, thdd]).all()


def test_swing_up_energy_counts_the_inertia():
    x = np.array([0.0, 2.0, 0.0, 3.0])
    assert pendulum_energy(ROD, x) == pytest.approx(0.5 * (ROD.J + ROD.m * ROD.l**2) * 9.0
                                                    + ROD.m * ROD.g * ROD.l * math.cos(2.0), rel=1e-14)
    assert ROD.swing_length() == pytest.approx(0.6413**2 / 12 / 0.3302 + 0.3302, rel=1e-14)
