"""The rotary (Furuta) pendulum: its linear model for a QUBE-Servo 2 against the one Quanser's
workbook writes in closed form, its linear model against its nonlinear equations differentiated,
the energy its equations conserve without friction or drive, the stability of its equilibria over
random plants, the compiled form against numpy's, and an LQR gain for the QUBE by two routes."""

from __future__ import annotations

import dataclasses
import math

import control
import numpy as np
import pytest
import scipy.linalg as sla
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from patchgen.plant.qube_servo2 import ENCODER_STEP_RAD, QUBE_SERVO_2, VOLTAGE_LIMIT_V
from patchgen.plant.rotary_compiled import N_ROTARY_COEF, ROTARY_VECTOR, rotary_rhs, rotary_vector
from patchgen.plant.rotary_compiled import rotary_accel as _accel
from patchgen.plant.rotary_compiled import rotary_coefficients as _coefficients
from patchgen.plant.rotary_equations import RotaryParams, fallen, linear_matrices, nonlinear_rhs, wound_up
from patchgen.plant.rotary_pendulum import FROM_ROD, PARAMETER_NAMES, PARAMETERS, REQUIRED, STATE_NAMES

# The QUBE-Servo 2's published figures (user manual; workbook script qube2_rotpen_param.m), written
# again here so that the model below is built from them and not from the package's constant
RM, KT, KM = 8.4, 0.042, 0.042
MR, LR, DR = 0.095, 0.085, 0.0015
MP, LP, DP = 0.024, 0.129, 0.0005
G = 9.81
FLIP = np.diag([1.0, -1.0, 1.0, -1.0])  # Quanser's pendulum angle is -theta (its B_4 is positive)


def quanser_linear_model(J_r: float) -> tuple[np.ndarray, np.ndarray]:
    """The workbook's linear model in closed form, (arm, pendulum angle, their rates) in Quanser's
    signs: J_r the arm's inertia about the motor's axis, J_p the pendulum's about its centre, its
    centre at L_p / 2; then the motor, tau = k_t (V_m - k_m alpha') / R_m, folded in."""
    J_p = MP * LP ** 2 / 12.0
    J_T = J_p * MP * LR ** 2 + J_r * J_p + J_r * MP * LP ** 2 / 4.0
    A = np.array([
        [0.0, 0.0, J_T, 0.0],
        [0.0, 0.0, 0.0, J_T],
        [0.0, MP ** 2 * LP ** 2 * LR * G / 4.0, -(J_p + MP * LP ** 2 / 4.0) * DR, -MP * LP * LR * DP / 2.0],
        [0.0, MP * LP * G * (J_r + MP * LR ** 2) / 2.0, -MP * LP * LR * DR / 2.0, -(J_r + MP * LR ** 2) * DP],
    ]) / J_T
    B = np.array([[0.0], [0.0], [J_p + MP * LP ** 2 / 4.0], [MP * LP * LR / 2.0]]) / J_T
    A[:, 2] -= KT * KM / RM * B[:, 0]
    return A, KT / RM * B


@pytest.mark.parametrize("arm", ["end", "centre"])
def test_the_qube_s_linear_model_is_the_workbook_s(arm):
    """The arm pivoted at its end (QUBE_SERVO_2's assumption: m_r L_r^2 / 3 about the axis), and at
    its centre (the workbook script's m_r L_r^2 / 12), each against the workbook's closed form."""
    plant = QUBE_SERVO_2 if arm == "end" else RotaryParams(**{**QUBE_SERVO_2.__dict__, "l_r": 0.0})
    A_q, B_q = quanser_linear_model(MR * LR ** 2 / 3.0 if arm == "end" else MR * LR ** 2 / 12.0)
    A, B = linear_matrices(plant)
    for got, want in ((A, FLIP @ A_q @ FLIP), (B, FLIP @ B_q)):
        nz = want != 0
        assert np.array_equal(got != 0, nz)
        np.testing.assert_allclose(got[nz], want[nz], rtol=1e-6, atol=0)
    assert B[2, 0] > 0 > B[3, 0]  # a positive voltage turns the arm in +alpha; the pendulum lags behind


AT_UPRIGHT = [QUBE_SERVO_2, RotaryParams(**{**QUBE_SERVO_2.__dict__, "l_r": 0.0, "J_p": 2e-5}),
              RotaryParams(m_r=0.3, L_r=0.2, m_p=0.1, L_p=0.4, D_r=0.01, D_p=0.002, R_m=2.6, k_t=0.03, k_m=0.03,
                           l_p=0.25, J_r=1e-3)]


@pytest.mark.parametrize("plant", AT_UPRIGHT, ids=["qube", "centre-arm", "heavier"])
def test_the_linear_model_is_the_nonlinear_one_differentiated(plant):
    """Central differences at upright, eps = 1e-6: the truncation error eps^2 |f'''| / 6 is a few
    1e-12 of the largest entry (it falls a hundredfold with eps tenfold), the rounding error far
    less (each difference is of terms of size |A| eps, rounded to 1e-16 of that); 1e-10 of the
    largest entry bounds both with a margin of thirty."""
    A, B = linear_matrices(plant)
    eps = 1e-6
    num = np.column_stack([(nonlinear_rhs(eps * e, 0.0, plant) - nonlinear_rhs(-eps * e, 0.0, plant)) / (2 * eps)
                           for e in np.eye(4)])
    np.testing.assert_allclose(A, num, rtol=0, atol=1e-10 * np.abs(A).max())
    dB = (nonlinear_rhs(np.zeros(4), eps, plant) - nonlinear_rhs(np.zeros(4), -eps, plant)) / (2 * eps)
    np.testing.assert_allclose(B[:, 0], dB, rtol=0, atol=1e-10 * np.abs(B).max())


# ---- random plants: bench-sized, within PARAMETERS' bounds ------------------------------------

def _log(lo: float, hi: float):
    return st.floats(math.log(lo), math.log(hi)).map(math.exp)


@st.composite
def plants(draw, damped: bool = True, driven: bool = True) -> RotaryParams:
    """A rotary pendulum of 5 g to 1 kg links a few cm to half a metre long, each centre of mass
    and inertia a rod's or one put off it (a centre anywhere along the arm, in the pendulum's outer
    two thirds; an inertia from a fifth to twice a rod's)."""
    m_r, L_r = draw(_log(0.01, 1.0)), draw(_log(0.03, 0.5))
    m_p, L_p = draw(_log(0.005, 0.5)), draw(_log(0.05, 0.6))
    extra = {}
    if not draw(st.booleans()):  # not uniform rods
        extra = {"l_r": draw(st.floats(0.0, 1.0)) * L_r, "J_r": draw(st.floats(0.2, 2.0)) * m_r * L_r ** 2 / 12,
                 "l_p": draw(st.floats(1 / 3, 1.0)) * L_p, "J_p": draw(st.floats(0.2, 2.0)) * m_p * L_p ** 2 / 12}
    return RotaryParams(m_r=m_r, L_r=L_r, m_p=m_p, L_p=L_p,
                        D_r=draw(_log(1e-5, 1e-2)) if damped else 0.0,
                        D_p=draw(_log(1e-6, 5e-3)) if damped else 0.0,
                        R_m=draw(_log(1.0, 20.0)), k_t=draw(_log(5e-3, 0.1)) if driven else 0.0,
                        k_m=draw(_log(5e-3, 0.1)), g=draw(st.floats(1.6, 25.0)), **extra)


def energies(p: RotaryParams, x) -> tuple[float, float]:
    """(T, V) from the links' motion in space, not from the mass matrix: the arm turning about the
    vertical axis z; the pendulum's centre at L_r e_r + l_p (sin theta e_t + cos theta z), turning
    at alpha' z - theta' e_r, a slender rod (inertia J_p across it, none along it). Analytic in x,
    so that a complex step differentiates it."""
    a, th, ad, thd = x
    l_r, J_r, l_p, J_p = p.arm_com(), p.arm_inertia(), p.pendulum_com(), p.pendulum_inertia()
    e_r, e_t, z = np.array([np.cos(a), np.sin(a), 0.0]), np.array([-np.sin(a), np.cos(a), 0.0]), np.eye(3)[2]
    along = np.sin(th) * e_t + np.cos(th) * z  # the pendulum's axis, pivot to tip
    v = ad * (p.L_r * e_t - l_p * np.sin(th) * e_r) + thd * l_p * (np.cos(th) * e_t - np.sin(th) * z)
    w = ad * z - thd * e_r
    w_across = w - (w @ along) * along
    T = 0.5 * (J_r + p.m_r * l_r ** 2) * ad ** 2 + 0.5 * p.m_p * (v @ v) + 0.5 * J_p * (w_across @ w_across)
    return T, p.m_p * p.g * l_p * np.cos(th)


# the complex step (1e-30j) of rates near 1e-300 underflows: below this a power is no figure at all
UNDERFLOW_FLOOR = 1e-280


def energy(p: RotaryParams, x) -> float:
    """T + V (energies)."""
    return sum(energies(p, x))


@settings(max_examples=15, deadline=None)
@given(plants(damped=False, driven=False), st.floats(-3.0, 3.0), st.floats(-5.0, 5.0), st.floats(-5.0, 5.0))
def test_without_friction_or_drive_the_energy_is_conserved(plant, th, ad, thd):
    """No damping, no motor (k_t = 0: no torque and no back-EMF), 3 s of an accurate solve: the
    drift is measured against the initial kinetic energy plus m_p g l_p, the potential's swing."""
    x0 = np.array([0.0, th, ad, thd])
    sol = solve_ivp(lambda t, x: nonlinear_rhs(x, 0.0, plant), (0.0, 3.0), x0, method="DOP853",
                    rtol=1e-11, atol=1e-11, dense_output=True)
    assert sol.success
    T0, _ = energies(plant, x0)
    e0 = energy(plant, x0)
    drift = max(abs(energy(plant, sol.sol(t)) - e0) for t in np.linspace(0.0, 3.0, 31))
    assert drift < 1e-6 * (T0 + plant.m_p * plant.g * plant.pendulum_com())


@settings(max_examples=60, deadline=None)
@given(plants())
def test_upright_has_exactly_one_unstable_pole_and_it_is_real(plant):
    A, _ = linear_matrices(plant)
    eig = np.linalg.eigvals(A)
    unstable = eig[eig.real > 1e-9 * np.abs(eig).max()]
    assert len(unstable) == 1 and unstable[0].imag == 0.0


@settings(max_examples=60, deadline=None)
@given(plants())
def test_hanging_is_stable_with_damping(plant):
    """Nothing pulls the arm back to alpha = 0, so alpha's column is zero and its pole is 0; the
    rest (the pendulum's swing and the arm's rate) decay."""
    A, _ = linear_matrices(plant, math.pi)
    assert (A[:, 0] == 0).all()
    assert (np.linalg.eigvals(A[1:, 1:]).real < 0).all()


@settings(max_examples=60, deadline=None)
@given(plants(), st.floats(-math.pi, math.pi), st.floats(-10.0, 10.0), st.floats(-20.0, 20.0),
       st.floats(-10.0, 10.0))
def test_the_power_balance_holds(plant, th, ad, thd, V_m):
    """dE/dt along the equations (by a complex step on ``energies``) is the motor's power less
    what damping takes: tau alpha' - D_r alpha'^2 - D_p theta'^2. Measured against the rates times
    the sizes of the torques the equations balance (motor, damping, weight, inertial)."""
    x = np.array([0.2, th, ad, thd])
    f = nonlinear_rhs(x, V_m, plant)
    dT, dV = (e.imag / 1e-30 for e in energies(plant, x + 1e-30j * f))
    tau = plant.k_t * (V_m - plant.k_m * ad) / plant.R_m
    want = tau * ad - plant.D_r * ad ** 2 - plant.D_p * thd ** 2
    l_r, l_p = plant.arm_com(), plant.pendulum_com()
    inertia = (plant.arm_inertia() + plant.m_r * l_r ** 2 + plant.m_p * plant.L_r ** 2 + plant.pendulum_inertia()
               + plant.m_p * l_p ** 2)
    torques = (abs(tau) + plant.D_r * abs(ad) + plant.D_p * abs(thd) + plant.m_p * plant.g * l_p
               + inertia * (ad ** 2 + thd ** 2))
    assert dT + dV == pytest.approx(want, abs=1e-9 * (abs(ad) + abs(thd)) * torques + UNDERFLOW_FLOOR)


def _random_plant(rng) -> RotaryParams:
    """Any plant within PARAMETERS' bounds, drawn on a log scale; a rod's figures half the time."""
    out = {}
    for p in PARAMETERS:
        if p.name in ("g", "alpha_limit") or (p.name in FROM_ROD and rng.random() < 0.5):
            continue
        out[p.name] = float(math.exp(rng.uniform(math.log(max(p.lo, 1e-4)), math.log(p.hi))))
    return RotaryParams(**out)


@pytest.mark.parametrize("seed", range(4))
def test_compiled_equals_numpy(seed):
    rng = np.random.default_rng(seed)
    for plant in [QUBE_SERVO_2] + [_random_plant(rng) for _ in range(24)]:
        v = rotary_vector(plant)
        for _ in range(8):
            x = np.array([rng.uniform(-10, 10), rng.uniform(-7, 7), rng.uniform(-30, 30), rng.uniform(-30, 30)])
            V_m = rng.uniform(-12, 12)
            want = nonlinear_rhs(x, V_m, plant)
            got = np.array(rotary_rhs(v, x[1], x[2], x[3], V_m))
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=0)


def test_states_side_by_side_are_each_state_s():
    rng = np.random.default_rng(7)
    X, V = rng.uniform(-3, 3, (4, 5)), rng.uniform(-10, 10, 5)
    want = np.column_stack([nonlinear_rhs(X[:, i], V[i], QUBE_SERVO_2) for i in range(5)])
    np.testing.assert_array_equal(nonlinear_rhs(X, V, QUBE_SERVO_2), want)


# ---- the QUBE-Servo 2: an LQR gain by two routes -----------------------------------------------

def test_an_lqr_gain_for_the_qube_is_an_independent_riccati_solve():
    """python-control's lqr (without slycot it calls scipy's Riccati solver too) against K = R^-1
    B' P from scipy's solve_continuous_are, and both against the stable invariant subspace of the
    Hamiltonian matrix, which shares no code with either. The weights check the model, they are
    no design."""
    A, B = linear_matrices(QUBE_SERVO_2)
    Q, R = np.diag([5.0, 1.0, 1.0, 1.0]), np.array([[1.0]])
    K_control, _, _ = control.lqr(A, B, Q, R)
    P = sla.solve_continuous_are(A, B, Q, R)
    K = np.linalg.solve(R, B.T @ P)
    np.testing.assert_allclose(K_control, K, rtol=1e-8)
    H = np.block([[A, -B @ np.linalg.solve(R, B.T)], [-Q, -A.T]])
    w, V = np.linalg.eig(H)
    X = V[:, np.argsort(w.real)[:4]]
    S = np.real(X[4:] @ np.linalg.inv(X[:4]))
    np.testing.assert_allclose(np.linalg.solve(R, B.T @ (S + S.T) / 2), K, rtol=1e-8)
    assert (np.linalg.eigvals(A - B @ K).real < 0).all()


# ---- the description ---------------------------------------------------------------------------

def test_the_parameters_are_the_plant_model_s():
    """RotaryParams is PARAMETERS: the same names in the same order, the required ones without a
    default, the rest with the stated one (None for a rod's figure)."""
    fields = RotaryParams.__dataclass_fields__
    assert tuple(fields) == PARAMETER_NAMES
    for p in PARAMETERS:
        has_default = fields[p.name].default is not dataclasses.MISSING
        assert has_default == (p.name not in REQUIRED)
        if has_default:
            assert fields[p.name].default == p.default
    assert STATE_NAMES == ("alpha", "theta", "alpha_dot", "theta_dot")
    assert set(ROTARY_VECTOR) <= set(PARAMETER_NAMES)
    v = rotary_vector(QUBE_SERVO_2)
    assert v[ROTARY_VECTOR.index("J_p")] == QUBE_SERVO_2.pendulum_inertia() and v[0] == QUBE_SERVO_2.m_r


def test_the_qube_s_figures():
    q = QUBE_SERVO_2
    assert (q.arm_com(), q.pendulum_com()) == (0.085 / 2, 0.129 / 2)
    assert q.arm_inertia() == pytest.approx(0.095 * 0.085 ** 2 / 12, rel=1e-15)
    assert q.pendulum_inertia() == pytest.approx(0.024 * 0.129 ** 2 / 12, rel=1e-15)
    assert q.back_emf_damping() == pytest.approx(0.042 ** 2 / 8.4, rel=1e-15)
    assert ENCODER_STEP_RAD == pytest.approx(math.radians(360 / 2048), rel=1e-15) and VOLTAGE_LIMIT_V == 10.0
    for p in PARAMETERS:
        value = getattr(q, p.name)
        assert value is None or p.lo <= value <= p.hi, p.name


def test_the_events_that_end_a_run():
    x = np.array([[0.1, -3.3, 0.0], [0.2, 0.6, -0.7], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    assert fallen(x, math.radians(30)).tolist() == [False, True, True]
    assert wound_up(x, math.pi).tolist() == [False, True, False]
    assert not fallen(np.zeros(4), 0.5) and not wound_up(np.zeros(4), QUBE_SERVO_2.alpha_limit)


def test_only_an_equilibrium_is_linearised():
    with pytest.raises(ValueError, match="no equilibrium"):
        linear_matrices(QUBE_SERVO_2, 0.3)


# ---- the lanes' form: per-plant constants, a torque on the arm and a force at the tip ------------

def _lanes_accel(plant: RotaryParams, x, V_m: float, torque: float, tip: float) -> np.ndarray:
    q = np.empty((N_ROTARY_COEF, 1))
    _coefficients(rotary_vector(plant), q[:, 0])
    add, thdd = _accel(q, 0, math.sin(x[1]), math.cos(x[1]), x[2], x[3], V_m, torque, tip)
    return np.array([x[2], x[3], add, thdd])


@pytest.mark.parametrize("seed", range(3))
def test_the_lanes_form_is_the_equations(seed):
    """Without a torque or a tip force, the kernel's form equals nonlinear_rhs to rounding (the
    constants are folded first, so not bit for bit: to 1e-12 of the accelerations' scale)."""
    rng = np.random.default_rng(seed)
    for plant in [QUBE_SERVO_2] + [_random_plant(rng) for _ in range(24)]:
        for _ in range(8):
            x = np.array([rng.uniform(-10, 10), rng.uniform(-7, 7), rng.uniform(-30, 30), rng.uniform(-30, 30)])
            V_m = rng.uniform(-12, 12)
            want = nonlinear_rhs(x, V_m, plant)
            got = _lanes_accel(plant, x, V_m, 0.0, 0.0)
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())


@settings(max_examples=60, deadline=None)
@given(plants(), st.floats(-math.pi, math.pi), st.floats(-10.0, 10.0), st.floats(-20.0, 20.0),
       st.floats(-10.0, 10.0), st.floats(-0.05, 0.05), st.floats(-1.0, 1.0))
def test_a_torque_and_a_tip_force_do_the_work_they_should(plant, th, ad, thd, V_m, torque, tip):
    """dE/dt with the lanes' form is the motor's and damping's power plus torque alpha' plus the tip
    force times the tip's speed along it: L_r alpha' + L_p cos(theta) theta', from where the tip is
    (the arm's end, then L_p along the pendulum), not from the equations."""
    x = np.array([0.2, th, ad, thd])
    f = _lanes_accel(plant, x, V_m, torque, tip)
    dT, dV = (e.imag / 1e-30 for e in energies(plant, x + 1e-30j * f))
    tau = plant.k_t * (V_m - plant.k_m * ad) / plant.R_m
    speed = plant.L_r * ad + plant.L_p * math.cos(th) * thd
    want = tau * ad - plant.D_r * ad ** 2 - plant.D_p * thd ** 2 + torque * ad + tip * speed
    l_r, l_p = plant.arm_com(), plant.pendulum_com()
    inertia = (plant.arm_inertia() + plant.m_r * l_r ** 2 + plant.m_p * plant.L_r ** 2 + plant.pendulum_inertia()
               + plant.m_p * l_p ** 2)
    torques = (abs(tau) + abs(torque) + abs(tip) * (plant.L_r + plant.L_p) + plant.D_r * abs(ad)
               + plant.D_p * abs(thd) + plant.m_p * plant.g * l_p + inertia * (ad ** 2 + thd ** 2))
    assert dT + dV == pytest.approx(want, abs=1e-9 * (abs(ad) + abs(thd)) * torques + UNDERFLOW_FLOOR)


@pytest.mark.parametrize("seed", range(3))
def test_the_spice_form_is_the_lanes_form(seed):
    """The deck's expressions (patchgen.plant.rotary_behavioural, evaluated as Python) equal the
    kernel's form, a torque and a tip force among the inputs, to rounding."""
    from patchgen.plant.rotary_behavioural import rotary_accelerations

    rng = np.random.default_rng(seed)
    for plant in [QUBE_SERVO_2] + [_random_plant(rng) for _ in range(12)]:
        add_expr, thdd_expr = rotary_accelerations(plant, repr, "th", "ad", "thd", "V", "T", "F")
        for _ in range(6):
            x = np.array([0.0, rng.uniform(-7, 7), rng.uniform(-30, 30), rng.uniform(-30, 30)])
            V_m, torque, tip = rng.uniform(-12, 12), rng.uniform(-0.05, 0.05), rng.uniform(-1, 1)
            names = {"sin": math.sin, "cos": math.cos, "th": x[1], "ad": x[2], "thd": x[3], "V": V_m, "T": torque,
                     "F": tip}
            got = [eval(e, {"__builtins__": {}}, names) for e in (add_expr, thdd_expr)]  # noqa: S307 - the plant's own
            want = _lanes_accel(plant, x, V_m, torque, tip)[2:]
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())
