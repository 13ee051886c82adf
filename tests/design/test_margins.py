"""Loop margins on loops whose margins are known in closed form, and against python-control."""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

from patchgen.design.margins import loop_margins


def _abc(num, den):
    ss = control.tf2ss(control.tf(num, den))
    return ss.A, ss.B, ss.C


def test_third_order_loop_gain_and_phase_margins():
    # L = 10/((s+1)(s+2)(s+3)): s^3 + 6 s^2 + 11 s + 6 + k is marginal at k = 60, w = sqrt(11)
    m = loop_margins(*_abc([10], np.polymul(np.polymul([1, 1], [1, 2]), [1, 3])))
    assert m.stable and m.lower_gm is None
    assert m.upper_gm == pytest.approx(6.0, rel=1e-6)
    assert m.phase_crossovers == pytest.approx([math.sqrt(11)], rel=1e-6)
    gm, pm, _, wpc, wp, _ = control.stability_margins(control.tf([10], np.polymul(np.polymul([1, 1], [1, 2]),
                                                                                 [1, 3])))
    assert m.upper_gm == pytest.approx(gm, rel=1e-6) and wpc == pytest.approx(math.sqrt(11), rel=1e-6)
    assert m.pm_deg == pytest.approx(pm, abs=1e-4)
    assert m.pm_freq == pytest.approx(wp, rel=1e-6)
    assert m.delay_margin_s == pytest.approx(math.radians(pm) / wp, rel=1e-5)


def test_open_loop_unstable_loop_has_a_lower_gain_margin():
    # L = 2/(s - 1): closed loop s + 1 is stable; it stays stable while the gain exceeds 1/2
    m = loop_margins(*_abc([2], [1, -1]))
    assert m.stable
    assert m.lower_gm == pytest.approx(0.5, rel=1e-6) and m.upper_gm is None
    assert m.lower_gm_db == pytest.approx(20 * math.log10(0.5), rel=1e-6)
    # |L(jw)| = 1 at w = sqrt(3), where the phase is -120 deg: PM = 60 deg
    assert m.gain_crossovers == pytest.approx([math.sqrt(3)], rel=1e-6)
    assert m.pm_deg == pytest.approx(60.0, abs=1e-4)


def test_an_unstable_closed_loop_is_reported_so():
    # L = 0.5/(s - 1): the closed loop s - 0.5 is unstable
    m = loop_margins(*_abc([0.5], [1, -1]))
    assert not m.stable
    assert m.pm_deg is None


def test_lqr_loop_keeps_its_guaranteed_margins():
    # any LQR loop: PM >= 60 deg, upper GM infinite, lower GM <= 1/2 (Kalman's inequality)
    A = np.array([[0.0, 1.0], [2.0, -0.1]])
    B = np.array([[0.0], [1.0]])
    K, _, _ = control.lqr(A, B, np.diag([10.0, 1.0]), [[1.0]])
    m = loop_margins(A, B, K)
    assert m.stable and m.upper_gm is None
    assert m.pm_deg >= 60.0 - 1e-6
    assert m.lower_gm is not None and m.lower_gm <= 0.5 + 1e-9


def test_half_cost_check_leaves_gain_limits_out():
    m = loop_margins(*_abc([10], np.polymul(np.polymul([1, 1], [1, 2]), [1, 3])), gain_limits=False)
    assert m.upper_gm is None and m.lower_gm is None and m.phase_crossovers == []
    assert m.stable and m.pm_deg == pytest.approx(
        control.stability_margins(control.tf([10], np.polymul(np.polymul([1, 1], [1, 2]), [1, 3])))[1], abs=1e-4)


@pytest.mark.parametrize("num, den, lower, upper, pm, pm_w", [
    ([1], [1, 0], None, None, 90.0, 1.0),                                     # 1/s: PM 90 deg at 1 rad/s
    ([2], [1, -1], 0.5, None, 60.0, math.sqrt(3)),                            # 2/(s-1)
    ([1], np.polymul([1, 0], np.polymul([1, 1], [1, 1])), None, 2.0, None, None),  # 1/(s(s+1)^2): GM 2 at 1
    ([4], np.polymul([1, 0], np.polymul([1, 1], [1, 2])), None, 1.5, None, None),  # 4/(s(s+1)(s+2)): 1.5 at sqrt 2
])
def test_analytic_loops_even_on_round_frequencies(num, den, lower, upper, pm, pm_w):
    """Crossings that fall exactly on 1 rad/s or sqrt(2) are found: no grid to fall between."""
    m = loop_margins(*_abc(num, den))
    assert m.stable
    assert m.lower_gm == (None if lower is None else pytest.approx(lower, rel=1e-9))
    assert m.upper_gm == (None if upper is None else pytest.approx(upper, rel=1e-9))
    if pm is not None:
        assert m.pm_deg == pytest.approx(pm, abs=1e-7) and m.pm_freq == pytest.approx(pm_w, rel=1e-9)


def test_delay_margin_of_two_over_s_minus_one():
    m = loop_margins(*_abc([2], [1, -1]))
    assert m.delay_margin_s == pytest.approx(math.radians(60) / math.sqrt(3), rel=1e-9)  # 0.6046 s
    assert round(m.delay_margin_s, 4) == 0.6046


def test_crossings_far_outside_any_grid_are_seen():
    # 1e7/(s + 1e-7)... a loop crossing 0 dB at 1e7 rad/s and a pole at 1e-7 rad/s
    m = loop_margins(*_abc([1e7], [1, 1e-7]))
    assert m.gain_crossovers == pytest.approx([math.sqrt(1e14 - 1e-14)], rel=1e-6)
    assert m.pm_deg == pytest.approx(90.0, abs=1e-4)


def test_a_tiny_gain_loop_has_no_crossover_and_no_spurious_one():
    m = loop_margins(*_abc([1e-6], np.polymul([1, 1], [1, 2])))
    assert m.stable and m.gain_crossovers == [] and m.pm_deg is None
    assert m.upper_gm is None and m.lower_gm is None


def test_a_double_integrator_with_a_zero_has_no_false_lower_margin():
    # (s + 0.1)/(s^2 (s + 1)): the closed loop s^3 + s^2 + k s + 0.1 k is stable for every k > 0
    # (Routh: 0.9 k > 0 and 0.1 k > 0), so there is no gain limit either way
    A, B, C = _abc([1, 0.1], np.polymul([1, 0, 0], [1, 1]))
    m = loop_margins(A, B, C)
    assert m.stable and m.lower_gm is None and m.upper_gm is None
    assert all(np.max(np.linalg.eigvals(A - k * B @ C).real) < 0 for k in (1e-3, 0.1, 10.0, 1e3))


@pytest.mark.parametrize("seed", range(20))
def test_random_stable_loops_agree_with_python_control(seed):
    rng = np.random.default_rng(seed)
    poles = -rng.uniform(0.2, 5.0, 3)
    num = [rng.uniform(1, 50)]
    den = np.poly(poles)
    m = loop_margins(*_abc(num, den))
    gm, pm, _, wpc, wgc, _ = control.stability_margins(control.tf(num, den))
    if m.stable and m.upper_gm is not None:
        assert m.upper_gm == pytest.approx(gm, rel=1e-6)
    if m.stable and m.pm_deg is not None and np.isfinite(pm):
        assert m.pm_deg == pytest.approx(pm, abs=1e-5)
