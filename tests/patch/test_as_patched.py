"""A patch judged as patched: the wired law (the netlist read back, pots as dialled) closed around
the design model beside the design's own, and the wired law against the design's, cause by cause.
The oracles are python-control (margins, frequency responses) and scipy (a bounded maximisation)."""

import json
import re
import warnings

import control
import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from patchgen.design.controller import Controller
from patchgen.design.lti import load_design
from patchgen.patch.as_patched import REPORT_W, as_patched, without_leaks
from patchgen.patch.build import build_patch
from patchgen.patch.law_error import difference, law_error, relative
from patchgen.patch.readback import wired_law
from patchgen.profiles.machine import load_machine
from tests.patch.test_compensator_patch import _dial_tolerance, _wired_si

M = load_machine("gp6")


def _design(name, **patch):
    d = load_design(name)
    if not patch:
        return d
    return load_design(d.spec.model_copy(update={"patch": d.spec.patch.model_copy(update=patch)}))


@pytest.fixture(scope="module")
def case2():
    """thesis-case2 as shipped (up to four units) and held to three, where only its residualised
    law fits: (design, netlist, judged) each."""
    out = {}
    for units in (4, 3):
        d = _design("thesis-case2", max_units=units)
        net = build_patch(d, M)
        out[units] = (d, net, as_patched(d, net, M))
    return out


def _wired_ss(net):
    """The read-back law in SI as python-control has it (sensor constants and K_U from the netlist)."""
    law = wired_law(net)
    ks = np.diag([s.volts_per_unit for s in net.sensors])
    KU = net.output.K_U_N_per_V
    return control.ss(law.Ac, law.Bc @ ks, KU * law.Cc, KU * law.Dc @ ks)


def _plant_ss(d):
    """The design model without its integral states (they are the controller's), y = s, theta, s_dot."""
    mdl = d.model
    keep = [i for i, s in enumerate(mdl.states) if not s.startswith("int_")]
    return control.ss(mdl.A[np.ix_(keep, keep)], mdl.B[keep], mdl.C[:, keep], 0)


def control_margins(L):
    """(lower GM dB or None, upper GM dB or None, PM deg) of the loop L closed as L / (1 + L), from
    python-control's every crossing: the gain limits nearest 1 on either side."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gm, pm, _, _, _, _ = control.stability_margins(L, returnall=True)
        assert np.max(control.feedback(L, 1).poles().real) < 0
    gm = np.atleast_1d(gm)
    lower = [g for g in gm if g < 1]
    upper = [g for g in gm if g > 1]
    db = lambda g: 20 * np.log10(g)  # noqa: E731
    return (db(max(lower)) if lower else None, db(min(upper)) if upper else None, float(np.min(np.abs(pm))))


def _sys_response(sys, w):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return np.array([sys(1j * wk)[0] for wk in w])


@pytest.mark.parametrize("units, want", [(4, (-9.3076, 18.3284, 52.831)), (3, (-12.109, None, 14.864))])
def test_margins_as_patched_are_python_controls_on_the_read_back_law(case2, units, want):
    d, net, j = case2[units]
    lower, upper, pm = control_margins(-control.series(_plant_ss(d), _wired_ss(net)))
    m = j.patched.margins
    assert m.lower_gm_db == pytest.approx(lower, abs=1e-6)
    assert (m.upper_gm_db is None) == (upper is None)
    if upper is not None:
        assert m.upper_gm_db == pytest.approx(upper, abs=1e-6)
    assert m.pm_deg == pytest.approx(pm, abs=1e-6)
    # the figures, for the record: four units keep the design's loop, three lose it
    assert (m.lower_gm_db, m.pm_deg) == (pytest.approx(want[0], abs=1e-3), pytest.approx(want[2], abs=1e-3))
    # as designed: the design's own loop (python-control on its controller)
    ctl = d.controller
    dl, du, dpm = control_margins(-control.series(_plant_ss(d), control.ss(ctl.Ac, ctl.Bc, ctl.Cc, ctl.Dc)))
    dm = j.designed.margins
    assert (dm.lower_gm_db, dm.upper_gm_db, dm.pm_deg) == (pytest.approx(dl, abs=1e-6), pytest.approx(du, abs=1e-6),
                                                          pytest.approx(dpm, abs=1e-6))
    assert (dl, du, dpm) == (pytest.approx(-9.353, abs=1e-3), pytest.approx(18.323, abs=1e-3),
                             pytest.approx(52.781, abs=1e-3))
    # the closed loop's poles: python-control's
    got = np.sort_complex(j.patched.poles)
    ref = np.sort_complex(control.feedback(-control.series(_plant_ss(d), _wired_ss(net)), 1).poles())
    np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9)


def test_the_residualised_law_shows_its_difference_and_names_its_cause(case2):
    """Three units: the -76 +/- 76j pair residualised. The wired law against the design's is
    python-control's response of the one against the other's; nearly all of it is the mode."""
    d, net, j = case2[3]
    ctl = d.controller
    w = np.array(REPORT_W)
    G = _sys_response(_wired_ss(net), w)
    D = _sys_response(control.ss(ctl.Ac, ctl.Bc, ctl.Cc, ctl.Dc), w)
    want = np.linalg.norm(G - D, axis=1) / np.linalg.norm(D, axis=1)
    np.testing.assert_allclose([e for _, e in j.law.at], want, rtol=1e-8)
    # the figures: 9 % at 10 rad/s, 50 % at 30, 76 % at 100
    assert want[2:] == pytest.approx([0.0886, 0.5046, 0.7619], abs=5e-4)
    causes = {c.kind: c for c in j.causes}
    assert set(causes) == {"leaks", "modes", "left_out", "dial"}
    modes = causes["modes"]
    assert "residualised" in modes.what and "-76.31 ± 75.99j" in modes.what
    for (_, e_all), (_, e_mode), (_, e_dial) in zip(j.law.at[2:], modes.error.at[2:], causes["dial"].error.at[2:]):
        assert abs(e_all - e_mode) <= e_dial + 1e-9  # the rest is the dial's (triangle inequality)
    assert causes["dial"].error.peak[1] < 0.005 and causes["leaks"].error.peak[1] < 1e-6
    assert "int_s 2e-05 1/s" in causes["leaks"].what and "theta -> int" in causes["left_out"].what
    # the whole patch, four units: the design's law within the dial; no mode lost
    d4, net4, j4 = case2[4]
    c4 = {c.kind: c for c in j4.causes}
    assert "every mode of the design's" in c4["modes"].what and c4["modes"].error.peak[1] < 1e-6
    assert j4.law.peak[1] < 0.005


@pytest.mark.parametrize("name", ["thesis-ch5", "bench-recommended", "thesis-case2"])
def test_a_patch_with_no_mode_lost_wires_the_design_law_within_half_a_dial_step_per_pot(name):
    d = load_design(name)
    net = build_patch(d, M)
    j = as_patched(d, net, M)
    w = np.geomspace(*j.law.band, 61)
    design = _sys_response(control.ss(d.controller.Ac, d.controller.Bc, d.controller.Cc, d.controller.Dc), w)
    leak = relative(difference(without_leaks(d.controller), d.controller), d.controller, w)
    off = np.abs(_wired_si(net, w) - design)
    # first order in each pot's half step (summed), twice for the second order and the dial's own
    # rounding; the leaks the patch leaves out (1e-5 1/s) on top: below 1e-6 of the response here
    assert leak.max() < 1e-6
    assert np.all(off <= 2 * _dial_tolerance(net, w) + 1e-6 * np.abs(design))
    assert j.law.peak[1] < 0.005


def _resonant(depth: float) -> tuple[Controller, Controller]:
    """A law of two inputs R = [1/(s+1), 2/(s+3)], and E = [depth s/(s^2 + s + 100), 0]: a
    narrow peak of |E|/|R| near 10 rad/s."""
    R = Controller(("a", "b"), np.diag([-1.0, -3.0]), np.eye(2), np.array([[1.0, 2.0]]), np.zeros((1, 2)))
    E = Controller(("p", "q"), np.array([[0.0, 1.0], [-100.0, -1.0]]), np.array([[0.0, 0.0], [1.0, 0.0]]),
                   np.array([[0.0, depth]]), np.zeros((1, 2)))
    return R, E


def test_the_largest_error_over_a_band_is_scipys_maximum_not_a_grid_point():
    depth = 0.3
    R, E = _resonant(depth)
    G = difference(R, Controller(E.states, E.Ac, E.Bc, -E.Cc, -E.Dc))  # R + E
    band = (0.1, 1000.0)
    got = law_error(G, R, R, band, (10.0,))

    def ratio(w):  # the same two laws in closed form
        s = 1j * np.asarray(w, float)
        return np.abs(depth * s / (s * s + s + 100.0)) / np.hypot(np.abs(1 / (s + 1)), np.abs(2 / (s + 3)))

    assert got.at[0][1] == pytest.approx(float(ratio(10.0)), rel=1e-12)
    grid = np.geomspace(*band, 2_000_001)
    k = int(np.argmax(ratio(grid)))
    best = minimize_scalar(lambda lw: -float(ratio(np.exp(lw))), bounds=(np.log(grid[k - 1]), np.log(grid[k + 1])),
                           method="bounded", options={"xatol": 1e-12})
    assert got.peak[1] == pytest.approx(-best.fun, rel=1e-9)
    assert got.peak[0] == pytest.approx(np.exp(best.x), rel=1e-5)
    assert got.peak[1] >= ratio(grid).max() * (1 - 1e-12)
    # the start grid alone (64 points) misses the top of so narrow a peak
    assert ratio(np.geomspace(*band, 64)).max() < 0.9 * got.peak[1]


def test_a_pole_no_gain_moves_is_set_beside_the_margins_not_in_them():
    """thesis-ch5 wires a pure integral of theta: the plant's conserved quantity leaves a closed-loop
    pole at 0 that no loop gain moves. The margins are those of the rest: the loop with the
    design's leak (1e-5 1/s) on that integrator, for python-control, within what the leak moves."""
    d = load_design("thesis-ch5")
    net = build_patch(d, M)
    j = as_patched(d, net, M)
    assert len(j.patched.fixed) == 1 and abs(j.patched.fixed[0]) < 1e-9
    assert j.patched.margins.stable and j.keeps_margin
    law = wired_law(net)
    integ = [i for i, s in enumerate(law.states) if net.amp(s).carries.quantity == "int_theta"]
    leaky = _wired_ss(net)
    A = leaky.A.copy()
    A[integ, integ] = -1e-5
    lower, upper, pm = control_margins(-control.series(_plant_ss(d), control.ss(A, leaky.B, leaky.C, leaky.D)))
    m = j.patched.margins
    assert (m.lower_gm_db, m.upper_gm_db, m.pm_deg) == (pytest.approx(lower, abs=1e-3), pytest.approx(upper, abs=1e-3),
                                                      pytest.approx(pm, abs=1e-3))


def test_margins_json_has_both_loops_and_the_causes(case2):
    from patchgen.render.margins_view import margins_json

    d, net, j = case2[3]
    doc = json.loads(margins_json(j, net.design))
    assert doc["schema"] == "patchgen.margins/1" and doc["design"] == "thesis-case2"
    assert [lp["law"] for lp in doc["loops"]] == ["as designed (kalman)", "as patched"]
    assert doc["loops"][1]["margins"]["pm_deg"] == pytest.approx(14.864, abs=1e-3)
    assert doc["keeps_pm_share"] is False and doc["keep_pm_share"] == 0.8
    assert [c["cause"] for c in doc["causes"]] == ["leaks", "modes", "left_out", "dial"]
    assert re.search(r"residualised", doc["causes"][1]["what"])
    assert len(doc["loops"][1]["poles"]) == 5 + 4  # plant and actuator, and the law's four states
