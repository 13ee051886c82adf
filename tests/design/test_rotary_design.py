"""The rotary pendulum through the design: the shipped QUBE-Servo 2 design's linear model against
the one the workbook builds from the published figures, its LQR and Kalman gains against Riccati
solves that share no code with patchgen's, its loop margins against python-control, and the
spec's and bench's refusals of what the rotary pendulum does not take."""

from __future__ import annotations

import json

import control as ct
import numpy as np
import pytest
import scipy.linalg as sla

import patchgen
from patchgen.design.lqg import design_on
from patchgen.design.model import build_model, plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.spec import load_spec
from patchgen.pipeline.inputs import load_inputs
from patchgen.plant.plant_model import PLANT_MODELS, ROTARY
from patchgen.plant.qube_servo2 import QUBE_SERVO_2
from patchgen.profiles.bench import load_bench
from tests.conftest import ROOT, run_patchgen
from tests.plant.test_rotary import FLIP, LR, MR, quanser_linear_model

QUBE = "qube-servo-2"
SPEC_TEXT = (ROOT / "designs" / f"{QUBE}.toml").read_text()


def _hamiltonian_gain(A, B, Q, R) -> np.ndarray:
    """K = R^-1 B' P with P from the stable invariant subspace of the Hamiltonian matrix (no
    Riccati solver)."""
    n = len(A)
    H = np.block([[A, -B @ np.linalg.solve(R, B.T)], [-Q, -A.T]])
    w, V = np.linalg.eig(H)
    X = V[:, np.argsort(w.real)[:n]]
    P = np.real(X[n:] @ np.linalg.inv(X[:n]))
    return np.linalg.solve(R, B.T @ (P + P.T) / 2)


def _design(text: str, tmp_path, name: str = "spec.toml"):
    path = tmp_path / name
    path.write_text(text)
    return design_on(*load_inputs(str(path), plants=tuple(PLANT_MODELS)))


def test_the_shipped_plant_is_the_qube_s_published_figures():
    spec = load_spec(QUBE)
    assert spec.plant_model is ROTARY and spec.states() == ["alpha", "theta", "alpha_dot", "theta_dot"]
    assert plant_params(spec) == QUBE_SERVO_2


def test_the_design_model_is_the_one_built_from_the_published_figures():
    """A and B of the shipped design against the workbook's closed form from the user manual's
    figures (the arm pivoted at its end: m_r L_r^2 / 3 about the motor's axis), to 1e-6."""
    model = build_model(load_spec(QUBE))
    A_q, B_q = quanser_linear_model(MR * LR ** 2 / 3.0)
    for got, want in ((model.A, FLIP @ A_q @ FLIP), (model.B, FLIP @ B_q)):
        nz = want != 0
        assert np.array_equal(got != 0, nz)
        np.testing.assert_allclose(got[nz], want[nz], rtol=1e-6, atol=0)
    assert model.measured == ("alpha", "theta") and model.n_plant == 4


def test_the_lqr_gain_is_an_independent_riccati_solve():
    """The shipped design's K against the Hamiltonian's stable subspace for the workbook's model
    and weights Q = diag(5, 1, 1, 1), R = 1 V^-2; the closed loop is stable and the LQR's own
    guarantee holds at the plant input (phase margin at least 60 deg, gain down to 1/2)."""
    d = patchgen.load_design(QUBE)
    A_q, B_q = quanser_linear_model(MR * LR ** 2 / 3.0)
    A, B = FLIP @ A_q @ FLIP, FLIP @ B_q
    K = _hamiltonian_gain(A, B, np.diag([5.0, 1.0, 1.0, 1.0]), np.array([[1.0]]))
    np.testing.assert_allclose(d.K, K, rtol=1e-5)
    assert (np.linalg.eigvals(A - B @ K).real < 0).all()
    assert d.K[0, 1] < 0  # u = -K x: a pendulum leaning toward +alpha is chased with a positive voltage
    m = d.lqr_margins
    assert m.pm_deg >= 60.0 and m.lower_gm <= 0.5 and m.upper_gm is None  # none: no upper limit
    L = ct.ss(d.model.A, d.model.B, d.K, 0)
    _, pm, _, _ = ct.margin(L)
    assert m.pm_deg == pytest.approx(pm, abs=1e-4)


def test_the_patch_s_differentiators_keep_the_loop_stable_with_margins():
    d = patchgen.load_design(QUBE)
    assert d.estimator.kind == "filtered_differentiator" and d.estimator.states == ("theta_dot", "alpha_dot")
    assert 1e-3 <= d.estimator.rolloff_s <= 0.1
    closed = ct.feedback(patchgen.loop_ss(d, "compensator"), 1)
    assert (closed.poles().real < 0).all()
    assert d.lqg_margins.pm_deg > 20.0


KALMAN = """
[estimator]
kind = "kalman"
W = 1.0
V = [1e-6, 1e-6]
rho = 1.0
"""


def test_the_kalman_gain_is_an_independent_riccati_solve(tmp_path):
    """The filter for the encoders' angles, process noise through B: L against the dual Riccati
    equation solved by scipy and by the Hamiltonian, and against python-control's lqe."""
    text = SPEC_TEXT.split("[estimator]")[0] + KALMAN
    d = _design(text, tmp_path)
    Ae, Be, Ce = d.model.submodel(d.model.estimated)
    QN, RN = Be @ Be.T, np.diag([1e-6, 1e-6])
    P = sla.solve_continuous_are(Ae.T, Ce.T, QN, RN)
    L = P @ Ce.T @ np.linalg.inv(RN)
    np.testing.assert_allclose(d.estimator.L, L, rtol=1e-6, atol=1e-9 * np.abs(L).max())
    np.testing.assert_allclose(d.estimator.L, _hamiltonian_gain(Ae.T, Ce.T, QN, RN).T, rtol=1e-5)
    L_ct, _, poles = ct.lqe(Ae, np.eye(4), Ce, QN, RN)
    np.testing.assert_allclose(d.estimator.L, L_ct, rtol=1e-6, atol=1e-9 * np.abs(L).max())
    assert (np.linalg.eigvals(Ae - d.estimator.L @ Ce).real < 0).all()


def test_loop_transfer_recovery_brings_the_margins_back(tmp_path):
    text = SPEC_TEXT.split("[estimator]")[0] + KALMAN.replace("rho = 1.0", 'rho = "auto"')
    d = _design(text, tmp_path)
    assert d.estimator.rho > 1.0
    assert d.estimator.margins_rho1.pm_deg < d.lqg_margins.pm_deg
    closed = ct.feedback(patchgen.loop_ss(d, "compensator"), 1)
    assert (closed.poles().real < 0).all()


@pytest.mark.parametrize("change, field", [
    (('model = "gain"\nK_U = 1.0', 'model = "dc_motor"\nR_m = 8.4\nK_t = 0.042\nK_m = 0.042\nr_pinion = 0.01'),
     "actuator.model"),
    (("[estimator]", "[integrators]\nint_s = true\n\n[estimator]"), "integrators.int_s"),
    (('model = "rotary-pendulum"', 'model = "furuta"'), "plant.model"),
    (("alpha = 3.0\ntheta = 15.0", "alpha = 3.0\ns = 3.0\ntheta = 15.0"), "sensors.s"),
    (("m_r = 0.095", "m_r = 0.095\nM = 0.9"), "plant.M"),
    (("L_p = 0.129", "L_p = inf"), "plant.L_p"),
    (('kind = "filtered_differentiator"', 'kind = "reduced_observer"'), "estimator.kind"),
])
def test_what_the_rotary_spec_does_not_take_is_named(tmp_path, change, field):
    old, new = change
    assert old in SPEC_TEXT
    path = tmp_path / "spec.toml"
    path.write_text(SPEC_TEXT.replace(old, new, 1))
    with pytest.raises(InputError) as err:
        design_on(*load_inputs(str(path), plants=tuple(PLANT_MODELS)))
    assert err.value.field == field and str(path) in str(err.value)


def test_a_cart_spec_on_a_rotary_bench_and_back_is_refused(tmp_path):
    cart = (ROOT / "designs" / "bench-recommended.toml").read_text()
    path = tmp_path / "cart.toml"
    path.write_text(cart.replace('bench = "uw-1991"', 'bench = "qube-servo-2"'))
    with pytest.raises(InputError, match="is a rotary-pendulum bench") as err:
        load_inputs(str(path))
    assert err.value.field == "plant"
    rotary = tmp_path / "rotary.toml"
    rotary.write_text(SPEC_TEXT.replace('bench = "qube-servo-2"', 'bench = "uw-1991"'))
    with pytest.raises(InputError, match="is a cart-pendulum bench"):
        load_inputs(str(rotary), plants=tuple(PLANT_MODELS))


def test_the_qube_bench_profile():
    bench = load_bench(QUBE)
    assert bench.plant == ROTARY.name and bench.actuator.K_U == 1.0
    assert bench.actuator.force_limit_N == bench.actuator.V_limit == 10.0  # the plant's input is volts
    count = pytest.approx(2 * np.pi / 2048)
    assert bench.sensors.quanta() == {"alpha": count, "theta": count}
    assert bench.track.cut_at(1.0) is None


@pytest.mark.parametrize("old, new, field", [
    ('model = "gain"', 'model = "gain"\nforce_limit_N = 12.0', "actuator.force_limit_N"),
    ("[disturbance]", "[track]\nlimit_switches = true\n\n[disturbance]", "track"),
    ("alpha = 3.0", "alpha = 3.0\ns = 3.0", "sensors.s"),
    ('plant = "rotary-pendulum"', 'plant = "furuta"', "plant"),
])
def test_a_rotary_bench_refuses_a_cart_s_fields(tmp_path, old, new, field):
    text = (ROOT / "patchgen" / "profiles" / "benches" / f"{QUBE}.toml").read_text()
    assert old in text
    path = tmp_path / "bench.toml"
    path.write_text(text.replace(old, new, 1))
    with pytest.raises(InputError) as err:
        load_bench(str(path))
    assert err.value.field == field



def test_the_cli_designs_and_patches_the_qube(tmp_path):
    r = run_patchgen("design", QUBE, "--json")
    assert r.returncode == 0, r.stderr
    got = json.loads(r.stdout)
    assert got["states"] == ["alpha", "theta", "alpha_dot", "theta_dot"]
    assert got["control_law"] == "u = -K x (u: voltage on the arm's motor, V)"
    np.testing.assert_allclose(got["K"], patchgen.load_design(QUBE).K[0], rtol=1e-12)
    assert set(got["zeros"]) == {"alpha/V_m", "alpha_dot/V_m"}
    r = run_patchgen("patch", QUBE, "-o", str(tmp_path / "patch"))
    assert r.returncode == 0, r.stderr
    assert "the arm held at its centre" in (tmp_path / "patch" / "patch-sheet.md").read_text()
