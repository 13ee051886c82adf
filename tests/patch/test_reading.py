"""The one reading of a netlist, checked directly on the section 5.3 patch and small variants of it."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from patchgen.bench.circuit import compile_circuit, sensor_constants
from patchgen.inputs.errors import InputError
from patchgen.patch.netlist import Netlist
from patchgen.patch.reading import AlgebraicLoopError, read, stage_levels
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

    def split_input(d):  # A1 feeds A7 through a second input too (a coefficient split): still one path
        _amp(d, "A7")["inputs"].append({"source": "A1", "weight": 10, "jack": "x10b"})
    assert read(_net(split_input)).path_sign("A1") == 1


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


def _hand_built(extra_s2_input: str | None = None) -> Netlist:
    """theta -> S1 (x10 through P2 = 0.3) -> S2 (inverter) -> S3 -> u_c, and I1 integrating theta
    and S3 (x1 through P1 = 0.5) into S3: a feedback loop closed through the integrator."""
    def amp(aid, role, inputs):
        return {"id": aid, "role": role, "purpose": "", "ic_V": 0.0 if role == "integrator" else None,
                "carries": {"quantity": "x", "polarity": 1, "volts_per_unit": 1.0, "unit": "1"},
                "inputs": [{"source": s, "weight": w, "jack": f"x{w}{'abc'[k]}", "pot": p}
                           for k, (s, w, p) in enumerate(inputs)]}

    def pot(pid, source, amplifier, weight, setting):
        return {"id": pid, "source": source, "signal": source, "amplifier": amplifier, "jack": f"x{weight}a",
                "weight": weight, "coefficient": setting * weight, "realized": setting * weight,
                "setting": setting, "note": ""}

    s2_inputs = [("S1", 1, None)] + ([(extra_s2_input, 1, None)] if extra_s2_input else [])
    data = {**{k: v for k, v in FIXTURE.items() if k not in ("amplifiers", "pots", "sensors", "output")},
            "sensors": [FIXTURE["sensors"][1]],
            "amplifiers": [amp("I1", "integrator", [("theta", 1, None), ("S3", 1, "P1")]),
                           amp("S1", "summer", [("theta", 10, "P2")]),
                           amp("S2", "inverter", s2_inputs),
                           amp("S3", "summer", [("S2", 1, None), ("I1", 1, None)])],
            "pots": [pot("P1", "S3", "I1", 1, 0.5), pot("P2", "theta", "S1", 10, 0.3)],
            "output": {**FIXTURE["output"], "source": "S3"}}
    return Netlist.model_validate(data)


def test_a_hand_built_netlist_reads_as_worked_out_by_hand():
    r = read(_hand_built())
    assert r.sensors == ("theta",) and r.output == "S3"
    assert [(f.source, f.gain) for f in r.amplifiers["I1"].feeds] == [("theta", 1.0), ("S3", 0.5)]
    assert [(f.source, f.gain) for f in r.amplifiers["S1"].feeds] == [("theta", pytest.approx(3.0))]
    assert r.order == ("I1", "S1", "S2", "S3")  # the integrator's output is a state: first
    assert [r.amplifiers[a].stateful for a in r.order] == [True, False, False, False]
    # inversions to u_c: S3 one, S2 two, S1 three, I1 two (through S3; the loop back is no path)
    assert [r.path_sign(a) for a in ("S3", "S2", "S1", "I1")] == [-1, 1, -1, 1]
    # stages: S1 after theta, S2 after S1; the loop I1 <-> S3 broken at the integrator I1,
    # placed after theta; S3 after its latest source S2
    assert r.levels() == {"theta": 0, "S1": 1, "S2": 2, "I1": 1, "S3": 3}
    assert r.fed_by() == {"theta": ["I1", "S1"], "S3": ["I1"], "S1": ["S2"], "S2": ["S3"], "I1": ["S3"]}


def test_a_hand_built_ring_names_its_amplifiers():
    with pytest.raises(AlgebraicLoopError) as exc:
        read(_hand_built(extra_s2_input="S3"))
    assert exc.value.field == "amplifiers"
    assert "algebraic loop S2 -> S3 -> S2" in str(exc.value)
    read(_hand_built(extra_s2_input="I1"))  # through the integrator: no algebraic loop


def _two_second_integrator(data) -> None:
    _amp(data, "A1")["mode"] = {"name": "standard", "k0_per_s": 0.5, "jumper": None}


def _schema_2(data) -> None:
    """The netlist as schema 2 wrote it: no mode, the integrators at the netlist's time scale."""
    data["schema"] = "patchgen.netlist/2"
    data["time_scale_s"] = 2.0
    for a in data["amplifiers"]:
        a.pop("mode", None)


@pytest.mark.parametrize("edit", [_two_second_integrator, _schema_2], ids=["mode", "schema-2"])
def test_engine_and_deck_take_the_integrators_time_scale_from_the_reading(edit):
    """An integrator at k0 = 0.5 1/s (its mode, or a schema-2 netlist's time scale): the simulator
    integrates at 1/2 per second and the deck's feedback capacitor is 2 s over the x1 input
    resistor, not the profile's 1 uF; the drift, e_os/(R C) + i_b/C, is half the profile's 5 mV/s
    through that capacitor (the profile's own offset and bias), in the simulator and the deck alike."""
    from patchgen.bench.configure import engine_config
    from patchgen.bench.noise_drift import noise_and_drift
    from patchgen.inputs.scenario import Scenario

    net, gp6, uw = _net(edit), load_machine("gp6"), load_bench("uw-1991")
    assert read(net).amplifiers["A1"].T_s == 2.0
    c = compile_circuit(net, gp6, uw)
    assert c.param1[c.amp_ids.index("A1")] == 0.5
    scenario = Scenario(duration_s=1.0, noise="off")
    levels = noise_and_drift(["s", "theta", "s_dot"], uw, gp6, scenario)
    assert levels.drift_V_per_s == pytest.approx(0.005, rel=1e-12)
    plant = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)
    drift = engine_config(c, plant, uw, gp6, scenario)[0].wiring.drift
    assert drift[c.amp_ids.index("A1")] == pytest.approx(0.0025, rel=1e-12)
    deck = spice_deck(net, plant, uw, gp6, SpiceSettings(1.0, 0.01, (0, 0.1, 0, 0), noise_and_drift=levels)).text
    assert gp6.components.integrator_capacitor_F == 1e-6 and gp6.components.input_resistor_x1_ohm == 1e6
    assert "C_a1_f a1_sj a1_out 2e-06" in deck
    assert "V_a1_offset a1_plus 0 DC 0.002" in deck and "I_a1_bias a1_sj 0 DC 3e-09" in deck


def test_stage_levels_put_states_first_and_feed_through_after_its_latest_source():
    # a lag fed back from a summer after it stays in the first column; the summer follows its sources
    lv = stage_levels(["theta", "from U2.A6"], [("L1", "lag", ["theta", "S2"]), ("S1", "summer", ["L1", "theta"]),
                                                ("S2", "summer", ["S1", "from U2.A6"]), ("I1", "integrator", ["I1"])])
    assert lv == {"theta": 0, "from U2.A6": 0, "L1": 1, "I1": 1, "S1": 2, "S2": 3}
