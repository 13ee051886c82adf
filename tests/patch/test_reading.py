"""The one reading of a netlist, checked directly on the section 5.3 patch and small variants of it."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from patchgen.bench.circuit import compile_circuit, sensor_constants
from patchgen.inputs.errors import InputError
from patchgen.patch.netlist import Netlist
from patchgen.patch.reading import AlgebraicLoopError, read
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine
from patchgen.spice.deck import SpiceSettings, spice_deck

FIXTURE = json.loads((Path(__file__).parents[1] / "fixtures" / "thesis-ch5.netlist.json").read_text())


def _net(edit=None) -> Netlist:
    data = copy.deepcopy(FIXTURE)
    if edit:
        edit(data)
    return Netlist.model_validate(data)


def _amp(data, aid):
    return next(a for a in data["amplifiers"] if a["id"] == aid)


def test_gains_are_weight_times_pot_setting():
    r = read(_net())
    a6 = {f.source: f.gain for f in r.amplifiers["A6"].feeds}
    assert a6 == pytest.approx({"s": 0.226, "theta": 2.67, "s_dot": 2.71}, rel=1e-12)
    a7 = {f.source: f.gain for f in r.amplifiers["A7"].feeds}
    assert a7 == pytest.approx({"A5": 0.599, "A1": 0.001, "A6": 1.0}, rel=1e-12)


def test_states_first_then_each_feed_through_after_what_it_reads():
    r = read(_net())
    assert r.order[0] == "A1"  # the integrator: a state
    assert r.order.index("A5") < r.order.index("A7") and r.order.index("A6") < r.order.index("A7")
    assert set(r.order) == {"A1", "A5", "A6", "A7"} and r.output == "A7"


def test_path_sign_counts_the_inversions_to_the_output():
    r = read(_net())
    # A7 drives u_c directly: one inversion; A6 and A5 feed A7: two; A1 feeds A7: two
    assert r.path_sign("A7") == -1
    assert r.path_sign("A6") == 1 and r.path_sign("A5") == 1 and r.path_sign("A1") == 1

    def second_path(d):  # A6 also reaches A7 through A1: two paths, no single sign
        _amp(d, "A1")["inputs"].append({"source": "A6", "weight": 1, "jack": "x1b"})
    assert read(_net(second_path)).path_sign("A6") is None


def test_levels_place_each_amplifier_after_its_latest_source():
    lv = read(_net()).levels()
    assert lv["s"] == lv["theta"] == 0
    assert lv["A1"] == lv["A5"] == lv["A6"] == 1 and lv["A7"] == 2


def test_a_ring_of_feed_through_amplifiers_is_refused():
    def ring(d):
        _amp(d, "A6")["inputs"].append({"source": "A7", "weight": 1, "jack": "x1b"})
    with pytest.raises(AlgebraicLoopError, match="algebraic loop"):
        read(_net(ring))


@pytest.mark.parametrize("edit, field", [
    (lambda d: _amp(d, "A6")["inputs"][0].update(source="bogus"), "amplifiers[2].inputs[0].source"),
    (lambda d: _amp(d, "A6")["inputs"][0].update(pot="P9"), "amplifiers[2].inputs[0].pot"),
    (lambda d: d["output"].update(source="A9"), "output.source"),
    (lambda d: _amp(d, "A1").update(role="lag"), "amplifiers[0].tau_s"),
])
def test_what_a_netlist_gets_wrong_names_the_field(edit, field):
    with pytest.raises(InputError) as exc:
        read(_net(edit))
    assert exc.value.field == field


def test_a_differentiator_without_roll_off_takes_the_machines():
    def bare(d):
        _amp(d, "A5").update(rolloff_s=None, T_d_s=None)
    r = read(_net(bare), default_rolloff_s=0.02)
    assert r.amplifiers["A5"].rolloff_s == 0.02 and r.amplifiers["A5"].T_d_s == 1.0  # the time scale
    assert read(_net(bare)).amplifiers["A5"].rolloff_s is None


def test_engine_and_deck_take_the_sensor_constants_from_the_bench():
    """A netlist scaled with other sensor constants than the bench has meets the bench's sensors."""
    def rescaled(d):
        for s in d["sensors"]:
            s["volts_per_unit"] *= 3.0
    net, gp6, uw = _net(rescaled), load_machine("gp6"), load_bench("uw-1991")
    bench_k = [uw.sensors.s, uw.sensors.theta, uw.sensors.s_dot]
    assert [s.volts_per_unit for s in net.sensors] == pytest.approx([3 * k for k in bench_k])
    assert sensor_constants(net, uw) == pytest.approx(bench_k)
    assert compile_circuit(net, gp6, uw).sensor_gain == pytest.approx(bench_k)
    plant = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
    deck = spice_deck(net, plant, uw, gp6, SpiceSettings(duration_s=1.0, step_s=0.01, x0=(0, 0.1, 0, 0))).text
    for sid, k in zip(("s", "theta", "s_dot"), bench_k):
        line = next(ln for ln in deck.splitlines() if ln.startswith(f"B_sens_{sid} "))
        assert f"{float(k)!r}*v(" in line, line
        assert f"{3 * float(k)!r}*v(" not in line
