"""Loop margins do not depend on the realisation: the same loop under random similarity transforms,
in badly scaled companion forms and in other units of time has the same margins, against closed
forms and python-control. Stability is judged at the loop's own scale: a slow loop is stable, a
closed-loop pole on the axis never is.

Tolerances: 1e-6 relative on gains, frequencies and phase margins (at least 1e-6 deg): a transform
of condition number 1e4 perturbs the loop by ~1e-12, a double pole's frequencies by its root.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest

import patchgen
from patchgen.design.margins import Margins, loop_margins
from patchgen.inputs.resources import shipped
from tests.design.realisations import companion, observer_companion, similar

RTOL = 1e-6
PM_ATOL_DEG = 1e-6
SCALES = [1e-10, 1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4, 1e7]  # rad/s: a loop's own frequency
# 2a^3/(s+a)^3: |T| = 1 where (w/a)^2 = 2^(2/3) - 1; T = -1/4 at w = sqrt(3) a, where (s + a)^3 turns by 180 deg
CUBE_WGC = math.sqrt(2 ** (2 / 3) - 1)
CUBE_PM = 180.0 - 3 * math.degrees(math.atan(CUBE_WGC))


def _tf(num, den):
    ss = control.tf2ss(control.tf(num, den))
    return ss.A, ss.B, ss.C


def _cube(a: float):
    return [2 * a**3], np.poly([-a] * 3)


def _assert_same(got: Margins, want: Margins, w_scale: float = 1.0) -> None:
    """got equals want, its frequencies w_scale times want's and its delay margin 1/w_scale times."""
    assert got.stable == want.stable
    for key in ("lower_gm", "upper_gm", "pm_deg", "pm_freq", "delay_margin_s"):
        g, w = getattr(got, key), getattr(want, key)
        assert (g is None) == (w is None), key
        if w is None:
            continue
        if key == "pm_deg":
            assert g == pytest.approx(w, rel=RTOL, abs=PM_ATOL_DEG), key
        else:
            factor = {"pm_freq": w_scale, "delay_margin_s": 1 / w_scale}.get(key, 1.0)
            assert g == pytest.approx(w * factor, rel=RTOL), key
    for key in ("gain_crossovers", "phase_crossovers"):
        g, w = getattr(got, key), getattr(want, key)
        assert len(g) == len(w), key
        np.testing.assert_allclose(g, np.multiply(w, w_scale), rtol=RTOL, err_msg=key)


# every loop of test_margins.py (num, den), a few with a feed-through, and random stable ones
LOOPS = [
    ([10], np.poly([-1, -2, -3])), ([2], [1, -1]), ([0.5], [1, -1]), ([1], [1, 0]),
    ([1], np.poly([0, -1, -1])), ([4], np.poly([0, -1, -2])), ([1e7], [1, 1e-7]), ([1e-6], np.poly([-1, -2])),
    ([1, 0.1], np.poly([0, 0, -1])), ([1], [1, 1]), ([1, 3, 1], np.poly([-0.5, -2, -4])),
    ([3, 1], np.poly([-0.2, -1 + 2j, -1 - 2j])),
] + [([np.random.default_rng(s).uniform(1, 50)], np.poly(-np.random.default_rng(s).uniform(0.2, 5.0, 3)))
     for s in range(5)]


@pytest.mark.parametrize("num, den", LOOPS)
@pytest.mark.parametrize("cond", [1e3, 1e4])
def test_every_test_loop_keeps_its_margins_under_similarity(num, den, cond):
    A, B, C = _tf(num, den)
    want = loop_margins(A, B, C)
    for seed in range(3):
        _assert_same(loop_margins(*similar(A, B, C, cond, seed)), want)


@pytest.mark.parametrize("num, den", LOOPS)
@pytest.mark.parametrize("scale", [1e-6, 1e7])
def test_every_test_loop_keeps_its_margins_in_companion_form_and_other_units_of_time(num, den, scale):
    """T(s / scale) in both companion forms has T's margins at scale times its frequencies; its
    coefficients then span up to 1e-18 to 1e21."""
    want = loop_margins(*_tf(num, den))
    n = len(den) - 1
    num_s = np.asarray(num, float) * scale ** (n - len(num) + 1 + np.arange(len(num)))
    den_s = np.asarray(den, float) * scale ** np.arange(n + 1)
    for form in (companion, observer_companion):
        _assert_same(loop_margins(*form(num_s, den_s)), want, w_scale=scale)


@pytest.mark.filterwarnings("ignore:Badly conditioned filter coefficients")  # tf2ss at a = 1e-10: it is so
@pytest.mark.parametrize("a", SCALES)
@pytest.mark.parametrize("form", [companion, observer_companion, _tf])
def test_two_a_cubed_over_s_plus_a_cubed_at_every_scale(a, form):
    """Upper gain limit 4 at sqrt(3) a, phase margin 67.6 deg at 0.766 a, in the realisation and in
    a = 1's realisation transformed (condition number 1e3) and put in units of 1/a. (A dense transform
    of the badly scaled form itself would be another loop: its roundoff, 1e-16 of the largest
    coefficient, swamps the smallest, a^3.)"""
    At, Bt, Ct = similar(*form(*_cube(1.0)), 1e3, seed=1)
    for A, B, C in (form(*_cube(a)), (a * At, a * Bt, Ct)):
        m = loop_margins(A, B, C)
        assert m.stable and m.lower_gm is None
        assert m.upper_gm == pytest.approx(4.0, rel=RTOL)
        np.testing.assert_allclose(m.phase_crossovers, [math.sqrt(3) * a], rtol=RTOL)
        np.testing.assert_allclose(m.gain_crossovers, [CUBE_WGC * a], rtol=RTOL)
        assert m.pm_deg == pytest.approx(CUBE_PM, abs=PM_ATOL_DEG)
        assert m.delay_margin_s == pytest.approx(math.radians(CUBE_PM) / (CUBE_WGC * a), rel=RTOL)


def test_two_over_s_plus_one_cubed_agrees_with_python_control():
    """The closed forms above are python-control's margins of the well-scaled loop (a = 1)."""
    gm, pm, _, wpc, wgc, _ = control.stability_margins(control.tf(*_cube(1.0)))
    assert gm == pytest.approx(4.0, rel=RTOL) and wpc == pytest.approx(math.sqrt(3), rel=RTOL)
    assert pm == pytest.approx(CUBE_PM, abs=1e-5) and wgc == pytest.approx(CUBE_WGC, rel=RTOL)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("a", [1e-6, 1e7])
def test_random_loops_far_from_one_rad_per_second_agree_with_python_control(seed, a):
    """A random stable loop T(s / a) has python-control's margins of T at a times its frequencies."""
    rng = np.random.default_rng(seed)
    num, den = [rng.uniform(1, 50)], np.poly(-rng.uniform(0.2, 5.0, 3))
    gm, pm, _, wpc, wgc, _ = control.stability_margins(control.tf(num, den))
    m = loop_margins(*companion(np.asarray(num) * a**3, den * a ** np.arange(4)))
    assert m.stable == bool(np.all(np.roots(np.polyadd(den, num)).real < 0))
    if m.stable and np.isfinite(gm):
        assert m.upper_gm == pytest.approx(gm, rel=RTOL) and m.phase_crossovers == pytest.approx([wpc * a], rel=RTOL)
    if m.stable and np.isfinite(pm):
        assert m.pm_deg == pytest.approx(pm, abs=1e-5) and m.pm_freq == pytest.approx(wgc * a, rel=RTOL)


def _shipped_loops():
    return [(n, law) for n in shipped("design") for law in ("lqr", "compensator")
            if law == "lqr" or patchgen.load_spec(n).estimator.kind != "none"]


@pytest.mark.parametrize("name, law", _shipped_loops())
def test_shipped_loops_keep_their_margins_under_similarity(name, law):
    """Condition number 1e2: their slowest closed-loop poles lie 1e-8 of their fastest from the axis,
    which a worse transform would leave within roundoff of it."""
    d = patchgen.load_design(name)
    L = patchgen.loop_ss(d, law)
    want = d.lqr_margins if law == "lqr" else d.lqg_margins
    _assert_same(loop_margins(L.A, L.B, L.C, L.D), want)
    for seed in range(3):
        _assert_same(loop_margins(*similar(L.A, L.B, L.C, 1e2, seed), L.D), want)


@pytest.mark.parametrize("realisation", ["given", "two-state", "similar"])
def test_one_over_s_plus_one_touches_unity_only_at_dc(realisation):
    """|T(jw)| = 1/sqrt(1 + w^2) touches 1 at w = 0 and never crosses it: no gain crossover, so no
    phase margin to report, in a one-state realisation, a two-state one ((s + 2)/((s + 1)(s + 2)))
    and that one transformed."""
    A, B, C = _tf([1], [1, 1]) if realisation == "given" else _tf([1, 2], np.poly([-1, -2]))
    if realisation == "similar":
        A, B, C = similar(A, B, C, 1e3, seed=3)
    m = loop_margins(A, B, C)
    assert m.stable and m.gain_crossovers == [] and m.pm_deg is None and m.delay_margin_s is None
    assert m.lower_gm is None and m.upper_gm is None and m.phase_crossovers == []


@pytest.mark.parametrize("k", [1e-3, 0.5, 1.0, 1.001, 2.0, 1e3])
def test_k_over_s_plus_one_is_stable_at_every_gain(k):
    """k/(s + 1): the closed loop s + 1 + k is stable for every k > 0, so no gain limit; for k > 1
    |T| crosses 1 at sqrt(k^2 - 1), where the phase margin is 180 - atan(w) deg."""
    m = loop_margins(*_tf([k], [1, 1]))
    assert m.stable and m.lower_gm is None and m.upper_gm is None
    if k > 1:
        w = math.sqrt(k * k - 1)
        assert m.gain_crossovers == pytest.approx([w], rel=RTOL)
        assert m.pm_deg == pytest.approx(180 - math.degrees(math.atan(w)), abs=PM_ATOL_DEG)
    else:
        assert m.gain_crossovers == []


@pytest.mark.parametrize("a", [1e-10, 1e-6, 1e7])
def test_a_slow_or_fast_loop_is_stable_at_its_own_scale(a):
    """a/(s + a) closes at s = -2a; the LQR loop of test_margins in units of 1/a keeps its margins."""
    m = loop_margins([[-a]], [[1.0]], [[a]])
    assert m.stable and m.gain_crossovers == [] and m.upper_gm is None
    A = np.array([[0.0, 1.0], [2.0, -0.1]])
    B = np.array([[0.0], [1.0]])
    K, _, _ = control.lqr(A, B, np.diag([10.0, 1.0]), [[1.0]])
    _assert_same(loop_margins(a * A, a * B, K), loop_margins(A, B, K), w_scale=a)


# loops closed with a pole on the axis: at +-j sqrt(11) (the third-order loop at its gain limit),
# at 0 (-1/(s + 1)), at +-j (1/s^2), and at 0 from an integrator that feedback cannot move
ON_AXIS = {
    "at-gain-limit": _tf([60], np.poly([-1, -2, -3])),
    "pole-at-zero": _tf([-1], [1, 1]),
    "double-integrator": _tf([1], [1, 0, 0]),
    "hidden-integrator": (np.diag([0.0, -1.0]), np.array([[0.0], [1.0]]), np.array([[1.0, 1.0]])),
}


@pytest.mark.parametrize("name", ON_AXIS)
@pytest.mark.parametrize("scale", [1e-10, 1.0, 1e7])
def test_a_closed_loop_pole_on_the_axis_is_never_stable(name, scale):
    A, B, C = ON_AXIS[name]
    for realisation in [(A, B, C)] + [similar(A, B, C, cond, seed) for cond in (1e3, 1e4) for seed in range(3)]:
        Ar, Br, Cr = realisation
        m = loop_margins(scale * Ar, scale * Br, Cr)
        assert not m.stable and m.pm_deg is None and m.upper_gm is None and m.lower_gm is None
