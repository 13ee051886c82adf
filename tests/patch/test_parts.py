"""External parts: every element a patch needs beyond the machine's own, with its value, a stock
fit and where it goes; a lag built from an integrator and a pot where it can be."""

import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import Netlist, wire_list
from patchgen.patch.parts import E12, E96, capacitor_fit, parts_for, resistor_fit
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.spice.deck import SpiceSettings, spice_deck
from tests.conftest import ROOT

GP6 = load_machine("gp6")


def _patch(name, machine=GP6, **estimator):
    spec = load_spec(name)
    if estimator:
        spec = spec.model_copy(update={"estimator": spec.estimator.model_copy(update=estimator)})
    d = design_on(spec, machine, load_bench(spec.bench))
    return d, build_patch(d, machine, "auto" if estimator.get("kind") == "reduced_observer" else None)


def test_bench_recommended_differentiator_parts():
    """The filtered differentiator A5: T_d = 1 s from a 1 uF capacitor with the 1 MOhm feedback, and
    a series resistor of rolloff / C = 6.31 kOhm (the design's 0.00631 s roll-off), fitted as 6.34 k."""
    d, net = _patch("bench-recommended")
    c, r = net.parts
    assert (c.id, c.kind, c.amplifier, c.jack) == ("C1", "capacitor", "A5", "x1a")
    assert c.value == pytest.approx(1.0 * 1.0 / GP6.components.feedback_resistor_ohm, rel=1e-12)
    assert (r.id, r.kind, r.jack) == ("R1", "resistor", "x1a")
    assert r.value == pytest.approx(d.estimator.rolloff_s / c.value, rel=1e-12)
    assert r.fit == "6.34 kΩ (E96)" and c.fit == "1 µF (E12)"
    assert (c.tolerance, r.tolerance) == (0.05, 0.01)
    # the wire list routes the cord through both parts, and the deck builds them at their values
    wires = wire_list(net)
    assert ("theta sensor", "C1 (1 µF (E12))") in wires and ("C1", "R1 (6.34 kΩ (E96))") in wires
    deck = spice_deck(net, plant_params(d.spec), load_bench("uw-1991"), GP6, SpiceSettings(1.0, 0.01, (0, 0.1, 0, 0)))
    assert "C_a5_x1a sens_theta a5_x1a_m 1e-06" in deck.text
    assert f"R_a5_x1a_s a5_x1a_m a5_sj {r.value:.6g}"[:34] in deck.text


def test_bench_recommended_lag_is_an_integrator_with_a_dial_time_constant():
    """The actuator model's 0.2 s lag: no external part; an integrator whose own output comes back
    through a pot at T/tau / 10 = 0.5 on a x10 input, and its input scaled by T/tau = 5."""
    d, net = _patch("bench-recommended")
    a1 = next(a for a in net.amplifiers if a.carries.quantity == "actuator")
    assert a1.role == "integrator" and not [p for p in net.parts if p.amplifier == a1.id]
    own = next(i for i in a1.inputs if i.source == a1.id)
    pot = net.pot(own.pot)
    assert (own.weight, pot.setting, pot.realized) == (10, 0.5, -5.0)
    tau = net.time_scale_s / (own.weight * pot.setting)
    assert tau == pytest.approx(d.spec.actuator.tau, rel=1e-12)
    # its input from u_c (through an inverter) carries T/tau = 5 too: the lag's DC gain is 1
    other = next(i for i in a1.inputs if i.source != a1.id)
    assert net.pot(other.pot).realized == pytest.approx(5.0, rel=1e-12)


def test_a_fast_lag_is_a_summer_with_a_listed_capacitor():
    """The reduced observer's lags (1/p = 71 ms: T/tau = 14 is more than a x10 input gives) stay
    lags: a summer with C = tau / R_f across its feedback, listed with its stock fit."""
    d, net = _patch("bench-recommended", kind="reduced_observer")
    lags = [a for a in net.amplifiers if a.role == "lag"]
    assert lags
    for a in lags:
        (c,) = [p for p in net.parts if p.amplifier == a.id]
        assert c.kind == "capacitor" and c.jack is None
        assert c.value == pytest.approx(a.tau_s / GP6.components.feedback_resistor_ohm, rel=1e-12)
        assert abs(c.fit_value / c.value - 1) <= 0.01  # two E12 capacitors in parallel fit within 1 %
        assert "across" in c.connection


def test_a_version_1_netlist_reads_and_gets_the_same_parts():
    data = json.loads((ROOT / "tests" / "fixtures" / "thesis-ch5.netlist.json").read_text())
    parts = data.pop("parts")
    old = Netlist.model_validate({**data, "schema": "patchgen.netlist/1"})
    assert [p.model_dump() for p in parts_for(old, GP6)] == parts


@given(st.floats(1e-12, 1e9))
def test_stock_fits_are_near_and_from_their_series(value):
    text, r = resistor_fit(value)
    assert abs(math.log(r / value)) <= 0.5 * math.log(1.031) + 1e-12  # E96 neighbours: at most 3.0 % apart
    m = r / 10 ** math.floor(math.log10(r) + 1e-9)
    assert any(math.isclose(m, e, rel_tol=1e-9) for e in E96) and text.endswith("(E96)")
    text, c = capacitor_fit(value)
    assert abs(math.log(c / value)) <= math.log(1.02)  # one E12 within 1 %, else two in parallel (measured: 1.7 %)
    if "in parallel" not in text:
        m = c / 10 ** math.floor(math.log10(c) + 1e-9)
        assert any(math.isclose(m, e, rel_tol=1e-9) for e in E12)


def test_a_two_unit_wire_list_keeps_each_units_cords_together():
    import re

    d, net = _patch("bench-recommended", kind="reduced_observer", rolloff_s=None)
    assert net.units == 2
    units = [int(m.group(1)) if (m := re.search(r"\bU(\d+)\.", to)) else 99 for _, to in wire_list(net)]
    assert units == sorted(units) and units[-1] == 99  # unit 1, unit 2, then the servo command
