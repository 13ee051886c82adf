"""The Quanser IP02 as its makers model it: the shipped design's linear plant, in motor volts,
against one built here from Quanser's published figures by another route (the mass matrix of the
Lagrangian, inverted numerically), and its LQR gain with Quanser's weights against an independent
Riccati solve on that model."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from patchgen.design.lti import load_design, plant_ss

# Quanser's configuration scripts (config_ip02.m, config_sp.m, setup_ip02_sip.m); ../shared/labs.md
MC, WEIGHT, BEQ = 0.57, 0.37, 5.4  # cart, its extra weight (kg); viscous damping with it (N s/m)
RM, KT, KM, KG, JM, RMP = 2.6, 0.00767, 0.00767, 3.71, 3.9e-7, 6.35e-3
ETA_G = ETA_M = 1.0
MP, LP, LP_COM, BP = 0.230, 0.6413, 0.3302, 0.0024  # pendulum: mass, length, pivot to COM, damping
G = 9.81
Q_QUANSER, R_QUANSER = np.diag([35.0, 350.0, 0.1, 0.1]), np.array([[0.02]])  # R per motor volt squared


def quanser_model() -> tuple[np.ndarray, np.ndarray]:
    """x = (x_c, alpha, x_c', alpha'), input the motor voltage: M q'' + D q' + K q = F V."""
    jeq = MC + WEIGHT + ETA_G * KG ** 2 * JM / RMP ** 2  # the rotor, geared, as mass at the pinion
    jp = MP * LP ** 2 / 12.0  # a uniform rod about its centre
    mass = np.array([[jeq + MP, MP * LP_COM], [MP * LP_COM, jp + MP * LP_COM ** 2]])
    emf = ETA_G * KG ** 2 * ETA_M * KT * KM / (RM * RMP ** 2)
    damping = np.diag([BEQ + emf, BP])
    stiffness = np.array([[0.0, 0.0], [0.0, -MP * G * LP_COM]])
    force = np.array([[ETA_G * KG * ETA_M * KT / (RM * RMP)], [0.0]])
    inv = np.linalg.inv(mass)
    A = np.block([[np.zeros((2, 2)), np.eye(2)], [-inv @ stiffness, -inv @ damping]])
    B = np.vstack([np.zeros((2, 1)), inv @ force])
    return A, B


@pytest.fixture(scope="module")
def ip02():
    return load_design("quanser-ip02")


def test_the_linear_model_in_motor_volts_is_quanser_s(ip02):
    sys = plant_ss(ip02, ("s", "theta", "s_dot", "theta_dot"), input="V_m")
    A, B = quanser_model()
    assert sys.input_labels == ["V_m"]
    for got, want in ((sys.A, A), (sys.B, B)):
        nz = want != 0
        assert np.array_equal(got != 0, nz)
        np.testing.assert_allclose(got[nz], want[nz], rtol=1e-6, atol=0)
    # the same plant per newton and per command volt (the unity amplifier: a command volt is a motor volt)
    np.testing.assert_allclose(plant_ss(ip02, "s", input="u_c").B, sys.B, rtol=1e-12)
    per_newton = plant_ss(ip02, "s").B
    np.testing.assert_allclose(per_newton * ip02.spec.actuator.K_U, sys.B, rtol=1e-12)


def test_a_point_mass_copy_of_the_manual_is_a_third_off():
    """Why the pendulum's inertia is a field: the manual's mass and pivot-to-centre distance as a
    point mass give an A whose entries are up to 38 % off."""
    from patchgen.plant.equations import PlantParams, linear_matrices
    A, _ = quanser_model()
    point = PlantParams(M=MC + WEIGHT + ETA_G * KG ** 2 * JM / RMP ** 2, m=MP, l=LP_COM, g=G,
                        b_VF=BEQ + ETA_G * KG ** 2 * ETA_M * KT * KM / (RM * RMP ** 2), c=BP, d=0.6)
    Ap, _ = linear_matrices(point)
    nz = A != 0
    assert np.max(np.abs(Ap[nz] - A[nz]) / np.abs(A[nz])) > 0.35


def test_the_lqr_gain_with_quanser_s_weights_is_an_independent_riccati_solve(ip02):
    A, B = quanser_model()
    P = sla.solve_continuous_are(A, B, Q_QUANSER, R_QUANSER)
    K_volts = np.linalg.solve(R_QUANSER, B.T @ P)
    # the design's law is per newton (u = -K x); per motor volt it is K / a (a newtons per volt)
    a = ETA_G * KG * ETA_M * KT / (RM * RMP)
    np.testing.assert_allclose(ip02.K / a, K_volts, rtol=1e-6)
    # Riccati's own residual on the design's model, as a check that cannot agree by construction
    sys = plant_ss(ip02, ("s", "theta", "s_dot", "theta_dot"), input="V_m")
    Pd = sla.solve_continuous_are(sys.A, sys.B, Q_QUANSER, R_QUANSER)
    residual = sys.A.T @ Pd + Pd @ sys.A - Pd @ sys.B @ np.linalg.solve(R_QUANSER, sys.B.T @ Pd) + Q_QUANSER
    assert np.abs(residual).max() < 1e-9 * np.abs(Pd).max() * np.abs(sys.A).max()


def test_a_motor_s_voltage_is_refused_for_a_force_actuator():
    with pytest.raises(ValueError, match="not a dc_motor"):
        plant_ss(load_design("bench-recommended"), input="V_m")
