"""The design engine against the numbers printed in the thesis (section 4.5.1) and in
conventions.md (reproduced with python-control 0.10.2)."""

import numpy as np
import pytest

from patchgen.design.lqg import design
from patchgen.inputs.spec import load_spec
from patchgen.profiles.bench import load_bench
from tests.conftest import design_path


@pytest.fixture(scope="module")
def case1():
    return design(load_spec(design_path("thesis-case1")))


@pytest.fixture(scope="module")
def noint():
    return design(load_spec(design_path("thesis-case1-noint")))


def test_case1_model_matches_printed_A_B(case1):
    A, B = case1.model.A, case1.model.B[:, 0]
    # section 4.5.1 prints A to 4 decimals
    assert A[2, 1] == pytest.approx(-0.8946, abs=5e-5)
    assert A[2, 2] == pytest.approx(-0.7256, abs=5e-5)
    assert A[2, 3] == pytest.approx(0.0007, abs=5e-5)
    assert A[3, 1] == pytest.approx(24.9454, abs=5e-5)
    assert A[3, 2] == pytest.approx(1.6915, abs=5e-5)
    assert A[3, 3] == pytest.approx(-0.0183, abs=5e-5)
    assert A[4, 4] == -2e-5 and A[5, 5] == -1e-5
    assert B[2] == pytest.approx(0.2815, abs=5e-5) and B[3] == pytest.approx(-0.6563, abs=5e-5)


def test_case1_open_loop_poles(case1):
    p = np.sort(case1.open_loop_poles.real)
    np.testing.assert_allclose(p, np.sort([0.0, 4.9588, -5.0388, -0.6639, -0.00002, -0.00001]), atol=5e-5)


def test_case1_lqr_gain_is_printed_G_read_as_K(case1):
    # printed G = [-39.8530 -249.4119 -44.8988 -60.0125 -15.8106 ~0]; conventions.md: it is K in u = -K x
    np.testing.assert_allclose(case1.K[0, :5], [-39.8530, -249.4119, -44.8988, -60.0125, -15.8106], atol=6e-5)
    assert abs(case1.K[0, 5]) < 1e-6


def test_case1_closed_loop_poles(case1):
    got = case1.closed_loop_poles
    want = np.array([-22.2917, -1.7309 + 1.2205j, -1.7309 - 1.2205j, -0.8667 + 0.5163j, -0.8667 - 0.5163j, -0.00001])
    for w in want:
        assert np.min(np.abs(got - w)) < 1e-4


def test_case1_lqr_margins(case1):
    m = case1.lqr_margins
    assert m.lower_gm == pytest.approx(0.2757, abs=5e-5)
    assert m.lower_gm_db == pytest.approx(-11.19, abs=5e-3)
    assert m.upper_gm is None and m.upper_gm_db is None
    assert m.pm_deg == pytest.approx(79.12, abs=5e-3)


def test_noint_gain_and_margins(noint):
    np.testing.assert_allclose(noint.K[0], [-15.8114, -209.0301, -31.0045, -52.9470], atol=6e-5)
    assert noint.lqr_margins.lower_gm_db == pytest.approx(-11.47, abs=5e-3)
    assert noint.lqr_margins.pm_deg == pytest.approx(80.14, abs=5e-3)


def test_plant_zeros(case1):
    np.testing.assert_allclose(np.sort(case1.zeros["s/F_U"].real), [-4.7896, 4.7729], atol=5e-5)
    np.testing.assert_allclose(np.sort(case1.zeros["s_dot/F_U"].real), [-4.7896, 0.0, 4.7729], atol=5e-5)


def test_kalman_gain_at_rho_1():
    from patchgen.design.ltr import kalman_gain

    spec = load_spec(design_path("thesis-case1"))
    d = design(spec)
    L = kalman_gain(spec, d.model, 1.0)
    printed = [[0.3081, -0.2708, 0.0880], [-0.2708, 9.6765, -1.5053],
               [0.0880, -1.5053, 0.2821], [-1.3313, 47.9871, -7.4821]]
    np.testing.assert_allclose(L, printed, atol=6e-5)


def test_lqg_margins_before_recovery(case1):
    # thesis: "GM = 1.029 dB, PM = 5.671 deg"; conventions.md: 1.03 dB / 5.7 deg
    m = case1.estimator.margins_rho1
    assert m.upper_gm_db == pytest.approx(1.03, abs=5e-3)
    assert m.pm_deg == pytest.approx(5.7, abs=0.05)


def test_ltr_recovers_lqr_margins(case1):
    lqr, lqg = case1.lqr_margins, case1.lqg_margins
    assert case1.estimator.rho == 1e7
    assert abs(lqg.lower_gm_db - lqr.lower_gm_db) < 1.0
    assert abs(lqg.pm_deg - lqr.pm_deg) < 5.0


def test_case2_actuator_column_is_ten_B():
    d = design(load_spec(design_path("thesis-case2")))
    A = d.model.A
    ia = d.model.index("actuator")
    # thesis case 2 prints 2.8153 and -6.5625 in the actuator column and B = [1 0 ...]
    assert A[2, ia] == pytest.approx(2.8153, abs=5e-4)
    assert A[3, ia] == pytest.approx(-6.5625, abs=5e-3)
    assert A[ia, ia] == -10.0 and d.model.B[ia, 0] == 1.0
    assert np.max(d.closed_loop_poles.real) < 0


def test_ch5_wired_signals_above_unity():
    # section 5.3: the wired gains for theta and s_dot exceed unity (x10 inputs), the others do not
    spec = load_spec(design_path("thesis-ch5"))
    d = design(spec, default_rolloff_s=0.01)
    ks = {"s": 5.0, "theta": 4.19, "s_dot": 0.5941, "theta_dot": 4.19, "int_theta": 4.19}
    wired = {s: abs(d.gain(s)) / (ks[s] * spec.actuator.K_U) for s in ks}
    assert {s for s, v in wired.items() if v > 1} == {"theta", "s_dot"}
    assert wired["int_theta"] < 0.001  # below the dial: the thesis set the minimum, 0.001


def test_case2_ltr_recovers_most_lqr_margins():
    # thesis 4.5.2: "Loop Transfer Recovery recovers most of the original LQR stability margins"
    # with the same rho as case 1 (the shipped spec's choice; see its comments)
    d = design(load_spec(design_path("thesis-case2")))
    assert d.estimator.rho == 1e7
    lqr, lqg = d.lqr_margins, d.lqg_margins
    assert lqg.stable and lqg.pm_deg > 0.75 * lqr.pm_deg
    assert abs(lqg.lower_gm_db - lqr.lower_gm_db) < 2.0
    # rho = 1 leaves the loop nearly unrobust, as the thesis found for every case
    assert d.estimator.margins_rho1.pm_deg < 10


def test_a_noise_shaped_estimator_needs_the_bench():
    """The design stage reads no file: a filtered differentiator without its bench is refused,
    and with a bench its predicted force error comes from that bench's noise."""
    spec = load_spec(design_path("bench-recommended"))
    with pytest.raises(ValueError, match="bench profile"):
        design(spec)
    bench = load_bench(spec.bench, spec.path)
    d = design(spec, bench)
    assert d.estimator.kind == "filtered_differentiator" and d.estimator.chosen_from_noise
    assert d.estimator.rolloff_s == pytest.approx(0.00631)  # the shipped sheet's roll-off
    quiet = bench.model_copy(update={"sensors": bench.sensors.model_copy(
        update={"noise_V_rms": {k: v / 100 for k, v in bench.sensors.noise_V_rms.items()}})})
    # the figure the roll-off was chosen by is the given bench's: a hundredth of the noise, a tenth of the error
    assert design(spec, quiet).estimator.force_error_rms_N < d.estimator.force_error_rms_N / 10
