"""The rotary pendulum's energy swing-up (patchgen.swingup.rotary_energy): the energy's
expression against the equations, the law's sign, the hand-off, and a wrong hand-off failing.

The runs use the QUBE-Servo 2 with its pendulum's damping a tenth of the workbook's D_p
(QUBE_PLANT): with the workbook's 5e-4 N m s/rad the pendulum's free swing decays with a time
constant 2 J_2 / D_p of about 0.5 s, and within 10 V no pumping reaches upright
(test_the_workbook_damping_stalls_the_pump says so).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from patchgen.plant.qube_servo2 import QUBE_SERVO_2, VOLTAGE_LIMIT_V
from patchgen.plant.rotary_equations import inertias, nonlinear_rhs
from patchgen.swingup.rotary_energy import (
    HOLD_ANGLE_RAD,
    SWITCHING,
    EnergyGains,
    hanging,
    lqr_gain,
    pendulum_energy,
    pump_direction,
    simulate_swingup,
    turning_frame_energy,
    voltage_for,
    wrap,
)

QUBE_PLANT = QUBE_SERVO_2.scaled(D_p=0.1)
G = inertias(QUBE_SERVO_2).G
REACH_S = 1.5  # the energy law alone gets E_r within 10 % of 2G of E_0 this soon (0.87 s seen)
NEAR_E0 = 0.1 * 2.0 * G  # J: 10 % of the hanging depth


def test_energy_zero_upright_and_minus_2g_hanging():
    assert pendulum_energy(QUBE_SERVO_2, 0.0, 0.0) == 0.0
    assert pendulum_energy(QUBE_SERVO_2, math.pi, 0.0) == -2.0 * G


def _free(p):
    return p.scaled(k_t=0.0, D_r=0.0, D_p=0.0)


def test_energy_is_conserved_with_the_arm_held_by_its_own_inertia():
    # a million-fold heavier arm barely moves: the pendulum's energy alone is conserved
    p = _free(QUBE_SERVO_2.scaled(m_r=1e6))
    sol = solve_ivp(lambda _t, y: nonlinear_rhs(y, 0.0, p), (0.0, 3.0), [0.0, 2.0, 0.0, 1.0],
                    rtol=1e-11, atol=1e-12, dense_output=True)
    E = pendulum_energy(p, sol.y[1], sol.y[3])
    assert np.min(sol.y[1]) < math.pi < np.max(sol.y[1])  # it swung through the bottom
    assert np.max(np.abs(E - E[0])) < 1e-6 * abs(E[0])


def test_energy_plus_the_arms_terms_is_conserved_with_the_arm_free():
    p = _free(QUBE_SERVO_2)
    c = inertias(p)
    sol = solve_ivp(lambda _t, y: nonlinear_rhs(y, 0.0, p), (0.0, 3.0), [0.0, 2.0, 0.0, 1.0],
                    rtol=1e-11, atol=1e-12)
    _, th, ad, thd = sol.y
    total = (pendulum_energy(p, th, thd) + 0.5 * (c.J_0 + c.J_2 * np.sin(th) ** 2) * ad * ad
             + c.K * np.cos(th) * ad * thd)
    assert np.max(np.abs(ad)) > 1.0  # the arm did move
    assert np.max(np.abs(total - total[0])) < 1e-6 * abs(total[0])


def test_the_energy_law_pumps_up_and_flipped_it_does_not():
    up = simulate_swingup(QUBE_PLANT, VOLTAGE_LIMIT_V, t_end=3.0, handoff=False, hold_check=1.0)
    E_r = turning_frame_energy(QUBE_PLANT, up.x.T)  # the energy the law pumps
    windows = E_r[: int(REACH_S / 1e-3)].reshape(-1, 100).mean(axis=1)  # 0.1 s means
    reached = np.flatnonzero(np.abs(E_r) < NEAR_E0)
    assert reached.size and up.t[reached[0]] < REACH_S
    first = int(up.t[reached[0]] / 0.1)
    assert np.all(np.diff(windows[: first + 1]) > 0.0)  # rising, window by window, until there
    flipped = simulate_swingup(QUBE_PLANT, VOLTAGE_LIMIT_V, t_end=3.0, handoff=False, hold_check=1.0,
                               gains=EnergyGains(sign=-1.0))
    E_r = turning_frame_energy(QUBE_PLANT, flipped.x.T)
    assert np.max(E_r) < -1.9 * G
    assert np.mean(E_r[-1000:]) < -1.95 * G
    # spinning the arm, the flipped law lifts the pendulum towards horizontal, never nearer upright
    assert np.min(np.abs(wrap(flipped.x[:, 1]))) > math.radians(60.0)


def test_the_turning_frame_energy_is_the_pendulum_s_upright_and_changes_only_with_the_input():
    x = np.array([0.3, 0.0, 7.0, 0.0])  # upright at rest on an arm turning at 7 rad/s
    assert turning_frame_energy(QUBE_SERVO_2, x) == pendulum_energy(QUBE_SERVO_2, 0.0, 0.0) == 0.0
    # with the motor off and no damping, alpha'' is the pendulum's reaction alone: dE_r/dt is
    # -alpha'' times pump_direction (module docstring), checked by finite differences
    p = _free(QUBE_SERVO_2)
    y = np.array([0.0, 2.0, 3.0, 1.5])
    h, f = 1e-5, nonlinear_rhs(y, 0.0, p)
    dE = (turning_frame_energy(p, y + h * f) - turning_frame_energy(p, y - h * f)) / (2.0 * h)  # along the flow
    predicted = -nonlinear_rhs(y, 0.0, p)[2] * p.L_r * pump_direction(p, y)
    assert dE == pytest.approx(predicted, rel=1e-7)
    assert abs(predicted) > 1e-3 * G  # a real change, not two zeros


def test_the_voltage_gives_the_arm_the_asked_acceleration():
    x = np.array([0.2, 2.0, 3.0, -4.0])
    for a in (-5.0, 0.0, 5.0):
        alpha_ddot = nonlinear_rhs(x, voltage_for(QUBE_SERVO_2, a, x), QUBE_SERVO_2)[2]
        assert alpha_ddot * QUBE_SERVO_2.L_r == pytest.approx(a, abs=1e-9)


def test_the_workbook_damping_stalls_the_pump():
    run = simulate_swingup(QUBE_SERVO_2, VOLTAGE_LIMIT_V, t_end=4.0, hold_check=1.0)
    assert run.handoff_time is None
    assert np.min(np.abs(wrap(run.x[:, 1]))) > math.radians(60.0)  # never within 60 deg of upright


def _check_held(run):
    assert run.handoff_time is not None and run.held
    assert run.max_abs_alpha < QUBE_PLANT.alpha_limit
    assert run.max_abs_V <= VOLTAGE_LIMIT_V


def test_swing_up_and_hold_for_30_s():
    run = simulate_swingup(QUBE_PLANT, VOLTAGE_LIMIT_V, t_end=32.0, hold_check=30.0)
    _check_held(run)
    assert run.handoff_time < 2.0
    assert np.max(np.abs(wrap(run.x[run.t >= 2.0, 1]))) < HOLD_ANGLE_RAD


def test_swing_up_from_random_nudges():
    rng = np.random.default_rng(20000287)
    held = 0
    for _ in range(10):  # 10 s held each, to keep the test short
        x0 = hanging(rng.uniform(-0.1, 0.1), rng.uniform(-0.5, 0.5))
        run = simulate_swingup(QUBE_PLANT, VOLTAGE_LIMIT_V, x0=x0, t_end=12.0, hold_check=10.0)
        held += run.held and run.max_abs_alpha < QUBE_PLANT.alpha_limit and run.max_abs_V <= VOLTAGE_LIMIT_V
    assert held >= 9


def test_a_hand_off_with_k_flipped_fails_to_hold():
    run = simulate_swingup(QUBE_PLANT, VOLTAGE_LIMIT_V, t_end=6.0, hold_check=4.0, K=-lqr_gain(QUBE_PLANT))
    assert not run.held


def test_switching_table_is_data():
    assert len(SWITCHING) == 2 and SWITCHING[-1].condition == "otherwise"
    assert "LQR" in SWITCHING[0].law


@pytest.mark.parametrize("theta", [0.3, -0.3])
def test_lqr_gain_pushes_the_arm_under_a_leaning_pendulum(theta):
    # theta > 0 leans the way +alpha moves the arm's tip, so the catch drives +V
    V = -lqr_gain(QUBE_PLANT) @ np.array([0.0, theta, 0.0, 0.0])
    assert np.sign(V) == np.sign(theta)
