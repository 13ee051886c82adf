"""patchgen sweep on the rotary pendulum: a row per parameter of the QUBE-Servo 2 a bench may have
wrong (and gravity), each row's gain the LQR of that perturbed plant by an independent solve, a
rod's figure left out perturbed as the rod's, and a cart's parameter refused."""

from __future__ import annotations

import json

import control as ct
import numpy as np
import pytest

from patchgen.plant.qube_servo2 import QUBE_SERVO_2
from patchgen.plant.rotary_equations import linear_matrices
from patchgen.plant.rotary_pendulum import UNCERTAIN
from tests.conftest import run_patchgen


def test_every_row_is_the_lqr_of_its_perturbed_plant():
    r = run_patchgen("sweep", "qube-servo-2", "--vary", "m_p,J_p,k_t", "--json")
    assert r.returncode == 0, r.stderr
    rows = {row["case"]: row for row in json.loads(r.stdout)}
    assert set(rows) == {"nominal", "m_p +10%", "m_p -10%", "J_p +10%", "J_p -10%", "k_t +10%", "k_t -10%",
                         "all +10%"}
    for case, factors in (("nominal", {}), ("m_p +10%", {"m_p": 1.1}), ("J_p -10%", {"J_p": 0.9}),
                          ("all +10%", {"m_p": 1.1, "J_p": 1.1, "k_t": 1.1})):
        A, B = linear_matrices(QUBE_SERVO_2.scaled(**factors))
        K, _, _ = ct.lqr(A, B, np.diag([5.0, 1.0, 1.0, 1.0]), np.array([[1.0]]))
        np.testing.assert_allclose(rows[case]["K"], K[0], rtol=1e-6, err_msg=case)
    assert rows["m_p +10%"]["K"] != rows["nominal"]["K"]


def test_a_rod_s_figure_left_out_is_perturbed_as_the_rod_s():
    scaled = QUBE_SERVO_2.scaled(J_p=1.1, l_r=0.9)
    assert QUBE_SERVO_2.J_p is None and scaled.J_p == pytest.approx(1.1 * QUBE_SERVO_2.pendulum_inertia(), rel=1e-15)
    assert scaled.l_r == pytest.approx(0.9 * QUBE_SERVO_2.L_r / 2, rel=1e-15)
    assert scaled.m_p == QUBE_SERVO_2.m_p  # only what is named


def test_the_default_rows_are_the_plant_s_uncertain_parameters_and_a_cart_s_is_refused():
    r = run_patchgen("sweep", "qube-servo-2", "--json")
    assert r.returncode == 0, r.stderr
    cases = [row["case"] for row in json.loads(r.stdout)]
    assert cases == ["nominal"] + [f"{n} {s}10%" for n in UNCERTAIN for s in "+-"] + ["all +10%"]
    bad = run_patchgen("sweep", "qube-servo-2", "--vary", "M")
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1 and "--vary" in bad.stderr
    assert "unknown parameter 'M'" in bad.stderr and "m_r" in bad.stderr
