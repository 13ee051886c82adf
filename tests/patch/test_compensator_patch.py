"""The compensator as one system: its split and reductions against python-control, and every
patched compensator read back from its netlist against the realised law, within the dial."""

import re
import warnings

import numpy as np
import pytest

from patchgen.design import compensator as comp
from patchgen.design.lti import compensator_ss, load_design
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import fits
from patchgen.patch.build import build_patch
from patchgen.patch.compensator_fit import laws, whole_law
from patchgen.patch.readback import wired_law
from patchgen.plant.plant_model import CART
from patchgen.profiles.machine import load_machine

W = np.logspace(-1, 2, 61)  # rad/s, the band the wiring must match
CASES = ("thesis-case1", "thesis-case2", "thesis-case3")
PATCHED = CASES + ("bench-lqg",)  # bench-lqg's fast mode and u_c are staged sums


def _ss_freqresp(sys, w):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        n = sys.nstates
        return np.array([(sys.C @ np.linalg.solve(1j * wk * np.eye(n) - sys.A, sys.B) + sys.D)[0] for wk in w])


@pytest.mark.parametrize("name", CASES)
def test_minimal_compensator_equals_python_controls(name):
    d = load_design(name)
    G = _ss_freqresp(compensator_ss(d), W)
    c = comp.compensator(d)
    # the integral states' leaks (1e-5 to 2e-5 1/s) become pure integrators: off by leak/w at most
    err = np.abs(c.freqresp(W) - G) / np.abs(G)
    assert err.max() < 3e-4
    # the integral states collapse into one integrator (their residue has rank one)
    assert c.order == d.controller.Ac.shape[0] - 1


def _wired_si(net, w):
    law = wired_law(net)
    ks = np.array([s.volts_per_unit for s in net.sensors])
    return law.freqresp(w) * net.output.K_U_N_per_V * ks


def _with_settings(net, settings):
    pots = [p.model_copy(update={"setting": s}) for p, s in zip(net.pots, settings)]
    return net.model_copy(update={"pots": pots})


def _dial_tolerance(net, w):
    """The response's spread when each pot moves by half a dial step (first order, summed)."""
    base = _wired_si(net, w)
    half = net.pot_resolution / 2
    tol = np.zeros_like(np.abs(base))
    for i, p in enumerate(net.pots):
        settings = [q.setting for q in net.pots]
        settings[i] = p.setting + half
        tol += np.abs(_wired_si(_with_settings(net, settings), w) - base)
    return tol


@pytest.fixture(scope="module", params=PATCHED)
def patched(request):
    d = load_design(request.param)
    m = load_machine(d.spec.machine)
    return d, m, build_patch(d, m)


def _full_law(d, m, net):
    """The law of the spec's full order the patch realises: with its fast modes kept (thesis case
    2 on four units) or residualised, told apart by the states its first note says it has."""
    states = int(re.search(r"(\d+) states", net.notes[0]).group(1))
    cands = [c for c in (whole_law(d, m), laws(d, m, "truncate")[0]) if c is not None]
    return next(law for order, _, law in cands if order == states)


def test_wiring_reads_back_as_the_realised_compensator(patched):
    d, m, net = patched
    assert net.units >= 1 and net.units <= d.spec.patch.max_units
    law = _full_law(d, m, net).freqresp(W)
    # every pot at its design coefficient: the wiring is the law (signs, weights, stages), but for
    # the coefficients below half a dial step that the allocator leaves out (named in the notes;
    # case 3's integral of theta, 6e-5 V/V, is the largest): 1e-4 of the response's peak
    exact = _with_settings(net, [abs(p.coefficient) / p.weight for p in net.pots])
    assert np.abs(_wired_si(exact, W) - law).max() <= 1e-4 * np.abs(law).max()
    # as dialled: within what half a dial step on every pot moves the response
    tol = _dial_tolerance(net, W)
    assert np.all(np.abs(_wired_si(net, W) - law) <= 2 * tol + 1e-9 * np.abs(law).max())


def test_a_mis_set_pot_is_caught(patched):
    d, m, net = patched
    law = _full_law(d, m, net).freqresp(W)
    tol = _dial_tolerance(net, W)
    settings = [p.setting for p in net.pots]
    i = int(np.argmax(settings))
    settings[i] = settings[i] * 0.8
    wrong = _wired_si(_with_settings(net, settings), W)
    assert np.any(np.abs(wrong - law) > 2 * tol + 1e-9 * np.abs(law).max())


def test_reduced_orders_keep_the_integral_part_and_dc_when_residualised():
    d = load_design("thesis-case1")
    c = comp.compensator(d)
    for order in range(c.order - 1, 0, -1):
        r = comp.reduced(c, order, "residualise")
        assert r.order == order
        np.testing.assert_allclose(r.R, c.R)
        # DC of the stable part preserved by singular perturbation
        dc = lambda x: x.D - x.C @ np.linalg.solve(x.A, x.B) if x.A.size else x.D  # noqa: E731
        np.testing.assert_allclose(dc(r), dc(c), rtol=1e-8, atol=1e-9)


def test_units_are_the_specs_choice():
    d = load_design("thesis-case1")
    m = load_machine("gp6")
    assert m.max_units < 3
    assert build_patch(d, m).units == 3  # beyond the profile's default, within the spec's max_units
    small = d.spec.model_copy(update={"patch": d.spec.patch.model_copy(update={"max_units": 2})})
    with pytest.raises(InputError) as exc:
        build_patch(load_design(small), m)
    assert "no realisation fits 2 unit(s)" in exc.value.line()


def test_bench_lqg_stages_its_fast_mode_and_holds_on_the_bench():
    """bench-lqg: its -25.7 rad/s mode and u_c need more than one x10 input, so each sums its terms
    at 1/g on a summer of its own (staged sums); on 3 units it holds every run of 40 per shipped
    scenario on the uw-1991 bench (dead zone, lag, noise, drift, random forces), where the loop
    transfer recovery design it replaces (W = 1, V = I, Gamma = B) held none."""
    from patchgen.bench.simulate import simulate
    from patchgen.design.model import plant_params
    from patchgen.inputs.resources import shipped, shipped_file
    from patchgen.inputs.scenario import load_scenario
    from patchgen.profiles.bench import load_bench

    d = load_design("bench-lqg")
    m = load_machine(d.spec.machine)
    net = build_patch(d, m)
    assert net.units == 3
    staged = [a for a in net.amplifiers if a.carries.quantity.removeprefix("partial ").endswith("_in")]
    assert {a.carries.quantity for a in staged} >= {"u_c_in"}
    assert d.lqg_margins.stable and d.lqg_margins.lower_gm < 0.42  # deep enough for the dead zone
    bench = load_bench(d.spec.bench)
    for name in shipped("scenario"):
        sc = load_scenario(shipped_file("scenario", name))
        if not fits(sc, CART):  # a rotary pendulum's (an arm's step or push)
            continue
        r = simulate(net, plant_params(d.spec), bench, m, sc, runs=40, keep_history=False)
        assert r.distribution.fraction_held == 1.0, name
