"""Loop margins on loops whose margins are known in closed form, and against python-control; every
loop as given and under random similarity transforms (condition number 1e3 and 1e4), which must not
change the answer."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from patchgen.design.margins import loop_margins
from tests.design.realisations import similar


@pytest.fixture(params=[None, 1e3, 1e4], ids=["as-given", "similar-1e3", "similar-1e4"])
def realise(request):
    """The loop (A, B, C) as given, or under a random similarity transform of that condition number;
    its rtol is what the answer then carries (1e-9 as given, 1e-6 transformed: the transform's
    roundoff, ~1e-16 times the condition number squared, moves a double pole's frequencies by its
    square root)."""
    cond = request.param
    make = lambda A, B, C: (A, B, C) if cond is None else similar(A, B, C, cond, seed=7)
    make.rtol = 1e-9 if cond is None else 1e-6
    return make


@pytest.fixture
def abc(realise):
    """(A, B, C) of num/den in python-control's realisation, realised by `realise`."""
    def make(num, den):
        ss = control.tf2ss(control.tf(num, den))
        return realise(ss.A, ss.B, ss.C)
    make.rtol = realise.rtol
    return make


def test_third_order_loop_gain_and_phase_margins(abc):
    # L = 10/((s+1)(s+2)(s+3)): s^3 + 6 s^2 + 11 s + 6 + k is marginal at k = 60, w = sqrt(11)
    m = loop_margins(*abc([10], np.polymul(np.polymul([1, 1], [1, 2]), [1, 3])))
    assert m.stable and m.lower_gm is None
    assert m.upper_gm == pytest.approx(6.0, rel=1e-6)
    assert m.phase_crossovers == pytest.approx([math.sqrt(11)], rel=1e-6)
    gm, pm, _, wpc, wp, _ = control.stability_margins(control.tf([10], np.polymul(np.polymul([1, 1], [1, 2]),
                                                                                 [1, 3])))
    assert m.upper_gm == pytest.approx(gm, rel=1e-6) and wpc == pytest.approx(math.sqrt(11), rel=1e-6)
    assert m.pm_deg == pytest.approx(pm, abs=1e-4)
    assert m.pm_freq == pytest.approx(wp, rel=1e-6)
    assert m.delay_margin_s == pytest.approx(math.radians(pm) / wp, rel=1e-5)


def test_open_loop_unstable_loop_has_a_lower_gain_margin(abc):
    # L = 2/(s - 1): closed loop s + 1 is stable; it stays stable while the gain exceeds 1/2
    m = loop_margins(*abc([2], [1, -1]))
    assert m.stable
    assert m.lower_gm == pytest.approx(0.5, rel=1e-6) and m.upper_gm is None
    assert m.lower_gm_db == pytest.approx(20 * math.log10(0.5), rel=1e-6)
    # |L(jw)| = 1 at w = sqrt(3), where the phase is -120 deg: PM = 60 deg
    assert m.gain_crossovers == pytest.approx([math.sqrt(3)], rel=1e-6)
    assert m.pm_deg == pytest.approx(60.0, abs=1e-4)


def test_an_unstable_closed_loop_is_reported_so(abc):
    # L = 0.5/(s - 1): the closed loop s - 0.5 is unstable
    m = loop_margins(*abc([0.5], [1, -1]))
    assert not m.stable
    assert m.pm_deg is None


def test_lqr_loop_keeps_its_guaranteed_margins(realise):
    # any LQR loop: PM >= 60 deg, upper GM infinite, lower GM <= 1/2 (Kalman's inequality)
    A = np.array([[0.0, 1.0], [2.0, -0.1]])
    B = np.array([[0.0], [1.0]])
    K, _, _ = control.lqr(A, B, np.diag([10.0, 1.0]), [[1.0]])
    m = loop_margins(*realise(A, B, K))
    assert m.stable and m.upper_gm is None
    assert m.pm_deg >= 60.0 - 1e-6
    assert m.lower_gm is not None and m.lower_gm <= 0.5 + 1e-9


def test_half_cost_check_leaves_gain_limits_out(abc):
    m = loop_margins(*abc([10], np.polymul(np.polymul([1, 1], [1, 2]), [1, 3])), gain_limits=False)
    assert m.upper_gm is None and m.lower_gm is None and m.phase_crossovers == []
    assert m.stable and m.pm_deg == pytest.approx(
        control.stability_margins(control.tf([10], np.polymul(np.polymul([1, 1], [1, 2]), [1, 3])))[1], abs=1e-4)


@pytest.mark.parametrize("num, den, lower, upper, pm, pm_w", [
    ([1], [1, 0], None, None, 90.0, 1.0),                                     # 1/s: PM 90 deg at 1 rad/s
    ([2], [1, -1], 0.5, None, 60.0, math.sqrt(3)),                            # 2/(s-1)
    ([1], np.polymul([1, 0], np.polymul([1, 1], [1, 1])), None, 2.0, None, None),  # 1/(s(s+1)^2): GM 2 at 1
    ([4], np.polymul([1, 0], np.polymul([1, 1], [1, 2])), None, 1.5, None, None),  # 4/(s(s+1)(s+2)): 1.5 at sqrt 2
])
def test_analytic_loops_even_on_round_frequencies(num, den, lower, upper, pm, pm_w, abc):
    """Crossings that fall exactly on 1 rad/s or sqrt(2) are found: no grid to fall between."""
    m = loop_margins(*abc(num, den))
    assert m.stable
    assert m.lower_gm == (None if lower is None else pytest.approx(lower, rel=abc.rtol))
    assert m.upper_gm == (None if upper is None else pytest.approx(upper, rel=abc.rtol))
    if pm is not None:
        assert m.pm_deg == pytest.approx(pm, abs=100 * abc.rtol) and m.pm_freq == pytest.approx(pm_w, rel=abc.rtol)


def test_delay_margin_of_two_over_s_minus_one(abc):
    m = loop_margins(*abc([2], [1, -1]))
    assert m.delay_margin_s == pytest.approx(math.radians(60) / math.sqrt(3), rel=abc.rtol)  # 0.6046 s
    assert round(m.delay_margin_s, 4) == 0.6046


def test_crossings_far_outside_any_grid_are_seen(abc):
    # 1e7/(s + 1e-7)... a loop crossing 0 dB at 1e7 rad/s and a pole at 1e-7 rad/s
    m = loop_margins(*abc([1e7], [1, 1e-7]))
    assert m.gain_crossovers == pytest.approx([math.sqrt(1e14 - 1e-14)], rel=1e-6)
    assert m.pm_deg == pytest.approx(90.0, abs=1e-4)


def test_a_tiny_gain_loop_has_no_crossover_and_no_spurious_one(abc):
    m = loop_margins(*abc([1e-6], np.polymul([1, 1], [1, 2])))
    assert m.stable and m.gain_crossovers == [] and m.pm_deg is None
    assert m.upper_gm is None and m.lower_gm is None


def test_a_double_integrator_with_a_zero_has_no_false_lower_margin(abc):
    # (s + 0.1)/(s^2 (s + 1)): the closed loop s^3 + s^2 + k s + 0.1 k is stable for every k > 0
    # (Routh: 0.9 k > 0 and 0.1 k > 0), so there is no gain limit either way
    A, B, C = abc([1, 0.1], np.polymul([1, 0, 0], [1, 1]))
    m = loop_margins(A, B, C)
    assert m.stable and m.lower_gm is None and m.upper_gm is None
    assert all(np.max(np.linalg.eigvals(A - k * B @ C).real) < 0 for k in (1e-3, 0.1, 10.0, 1e3))


@pytest.mark.parametrize("seed", range(20))
def test_random_stable_loops_agree_with_python_control(seed, abc):
    rng = np.random.default_rng(seed)
    poles = -rng.uniform(0.2, 5.0, 3)
    num = [rng.uniform(1, 50)]
    den = np.poly(poles)
    m = loop_margins(*abc(num, den))
    gm, pm, _, wpc, wgc, _ = control.stability_margins(control.tf(num, den))
    if m.stable and m.upper_gm is not None:
        assert m.upper_gm == pytest.approx(gm, rel=1e-6)
    if m.stable and m.pm_deg is not None and np.isfinite(pm):
        assert m.pm_deg == pytest.approx(pm, abs=1e-5)
