"""Integrator time scales: each integrator on the slowest mode that carries it, recorded in the
netlist, told on the sheet, and taken at that k0 by the read-back, the simulator and the deck."""

import numpy as np
import pytest

from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config
from patchgen.bench.noise_drift import noise_and_drift
from patchgen.inputs.errors import ResourceError
from patchgen.inputs.scenario import Scenario
from patchgen.patch.build import build_patch
from patchgen.patch.netlist import Mode, wire_list
from patchgen.patch.reading import read
from patchgen.patch.realization import realize
from patchgen.plant.equations import PlantParams
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import IntegratorMode, load_machine
from patchgen.render.patchfiles import patch_files
from patchgen.spice.deck import SpiceSettings, spice_deck
from tests.conftest import design_from_path, design_path
from tests.patch.test_patch_roundtrip import check_roundtrip

THAT = load_machine("the-analog-thing")
SLOW = Mode(name="SLOW", k0_per_s=10.0, jumper="SLOW")
PLANT = PlantParams(M=3.552, m=0.324, l=0.429, g=9.807, b_VF=2.5775, c=0.001, d=1.090)


def _with_modes(machine, *modes: IntegratorMode):
    """``machine`` with these integrator modes (its time scale the slowest's, as a profile derives it)."""
    return machine.model_copy(update={"integrator_modes": list(modes),
                                      "time_scale_s": 1.0 / min(m.k0_per_s for m in modes)})


def test_the_analog_thing_profile_states_its_documented_rates():
    # the-analog-thing.org wiki, Integrator: k0 = 1/(1 MOhm x 1 nF) = 1000 1/s; SLOW to OUT: 100 times slower
    assert {m.name: m.k0_per_s for m in THAT.integrator_modes} == {"SLOW": 10.0, "standard": 1000.0}
    c = THAT.components
    assert 1.0 / (c.input_resistor_x1_ohm * c.integrator_capacitor_F) == pytest.approx(1000.0, rel=1e-12)
    assert c.input_resistor_x1_ohm / c.input_resistor_x10_ohm == pytest.approx(10.0, rel=1e-12)
    assert THAT.time_scale_s == pytest.approx(0.1, rel=1e-15)  # the slowest mode: the scale a law is built at
    # drift e_os/(R C) + i_b/C with C = T/R: 100 times faster in the standard mode
    assert THAT.integrator_drift_V_per_s() == pytest.approx(0.001 * 10 + 1e-9 * 10 * 1e6, rel=1e-12)
    assert THAT.integrator_drift_V_per_s(1e-3) == pytest.approx(100 * THAT.integrator_drift_V_per_s(), rel=1e-12)
    gp6 = load_machine("gp6")
    assert [(m.name, m.k0_per_s, m.jumper) for m in gp6.integrator_modes] == [("standard", 1.0, None)]
    assert gp6.integrator_drift_V_per_s() == pytest.approx(0.005, rel=1e-12)


@pytest.mark.parametrize("name", ["thesis-ch5", "bench-recommended"])
def test_the_analog_thing_integrators_take_slow_and_run_at_the_design_rate(name):
    d, gp6 = design_from_path(design_path(name))
    net = build_patch(d, THAT)
    ints = [a for a in net.amplifiers if a.role == "integrator"]
    assert ints and all(a.mode == SLOW for a in ints)
    wires = wire_list(net)
    for a in ints:  # the SLOW cord on the wire list, once per integrator
        assert wires.count((f"{a.id} SLOW", f"{a.id} out (SLOW: k0 10 1/s)")) == 1
    # the same rates as the GP-6's 1 s integrators: k0 x weight x setting, per second, per input
    rates = {blk.name: {t.signal: t.coeff for t in blk.terms} for blk in realize(d, gp6).blocks
             if blk.kind == "integrate"}
    for a in ints:
        block = rates[a.carries.quantity]
        for p in (p for p in net.pots if p.amplifier == a.id):
            src = p.signal.lstrip("-")
            want = abs(block[src if src in block else a.carries.quantity])
            assert abs(p.weight * p.setting * SLOW.k0_per_s - want) <= p.weight * THAT.pot_resolution / 2 * 10 + 1e-12
    # read back at k0 = 10: the design's law, each pot within half a dial step of its coefficient
    check_roundtrip(d, net, THAT.pot_resolution)
    assert read(net).amplifiers[ints[0].id].T_s == pytest.approx(0.1, rel=1e-15)
    for p in net.pots:
        if not any(p.signal.lstrip("-") in n and "minimum" in n for n in net.notes):
            assert abs(p.realized - p.coefficient) <= p.weight * THAT.pot_resolution / 2 + 1e-12
    # the sheet tells the technician where SLOW goes
    md = patch_files(d, THAT, net)["patch-sheet.md"]
    assert "integrators at k0 10 1/s (SLOW patched to OUT)" in md.splitlines()[2]
    for a in ints:
        row = next(r for r in md.splitlines() if r.startswith(f"| **{a.id}** | integrator |"))
        assert "SLOW patched to OUT: k0 10 1/s" in row
        assert f"| {a.id} SLOW | {a.id} out (SLOW: k0 10 1/s) |" in md


def test_simulator_and_deck_integrate_and_drift_at_the_mode():
    d, _ = design_from_path(design_path("thesis-ch5"))
    net, uw = build_patch(d, THAT), load_bench("uw-1991")
    i1 = next(a.id for a in net.amplifiers if a.role == "integrator")
    c = compile_circuit(net, THAT, uw)
    assert c.param1[c.amp_ids.index(i1)] == pytest.approx(10.0, rel=1e-15)
    scenario = Scenario(duration_s=1.0, noise="off")
    levels = noise_and_drift(["s", "theta", "s_dot"], uw, THAT, scenario)
    drift = engine_config(c, PLANT, uw, THAT, scenario)[0].wiring.drift
    assert drift[c.amp_ids.index(i1)] == pytest.approx(0.02, rel=1e-12)  # 1 mV/(1 MOhm 100 nF) + 1 nA/100 nF
    deck = spice_deck(net, PLANT, uw, THAT, SpiceSettings(1.0, 0.01, (0, 0.1, 0, 0), noise_and_drift=levels)).text
    n = i1.lower()
    cap = next(float(x.split()[-1]) for x in deck.splitlines() if x.startswith(f"C_{n}_f {n}_sj {n}_out "))
    assert cap == pytest.approx(1e-7, rel=1e-12)  # 1 nF with SLOW's 99 nF: T = 0.1 s on 1 MOhm
    assert f"V_{n}_offset {n}_plus 0 DC 0.001" in deck and f"I_{n}_bias {n}_sj 0 DC 1e-09" in deck


def test_a_block_too_fast_for_the_slow_mode_takes_the_next():
    # SLOW at 0.01 1/s would need 100 on theta's input for the integral of theta (1 1/s): the
    # standard mode at 2 1/s carries it through a pot at 0.5
    d, _ = design_from_path(design_path("thesis-ch5"))
    m = _with_modes(THAT, IntegratorMode(name="SLOW", k0_per_s=0.01, jumper="SLOW"),
                    IntegratorMode(name="standard", k0_per_s=2.0))
    net = build_patch(d, m)
    a = next(a for a in net.amplifiers if a.role == "integrator")
    assert a.mode == Mode(name="standard", k0_per_s=2.0, jumper=None)
    p = next(p for p in net.pots if p.amplifier == a.id)
    assert (p.weight, p.setting) == (1, 0.5)
    assert not any(src.endswith("SLOW") for src, _ in wire_list(net))
    check_roundtrip(d, net, m.pot_resolution)


@pytest.mark.parametrize("seed", range(6))
def test_any_set_of_modes_wires_the_same_law(seed):
    """Random rates for two modes: the slowest that carries every coefficient of the block is the
    one chosen, and the law read back at its k0 is the design's."""
    rng = np.random.default_rng(seed)
    d, _ = design_from_path(design_path("bench-recommended"))
    k0 = sorted(10 ** rng.uniform(-1.5, 2.5, size=2))
    m = _with_modes(THAT, IntegratorMode(name="SLOW", k0_per_s=float(k0[0]), jumper="SLOW"),
                    IntegratorMode(name="standard", k0_per_s=float(k0[1])))
    try:
        net = build_patch(d, m)
    except ResourceError as exc:  # the lag's rates beyond the faster mode too: said in one line
        assert "\n" not in exc.line() and "integrator rate" in exc.line()
        return
    base = {b.name: max(abs(t.coeff) for t in b.terms) for b in realize(d, m).blocks if b.kind == "integrate"}
    for a in (a for a in net.amplifiers if a.role == "integrator"):
        fits = [x for x in k0 if base[a.carries.quantity] * k0[0] / x <= 10 + 1e-12]
        assert a.mode.k0_per_s == pytest.approx(fits[0] if fits else k0[-1], rel=1e-15)
    check_roundtrip(d, net, m.pot_resolution)


def test_no_mode_fast_enough_is_one_line_naming_the_rate():
    d, gp6 = design_from_path(design_path("thesis-ch5"))
    slow = _with_modes(gp6, IntegratorMode(name="standard", k0_per_s=1e-3))
    with pytest.raises(ResourceError) as exc:
        build_patch(d, slow)
    line = exc.value.line()
    assert "\n" not in line
    assert "an integrator rate of 1 1/s" in line and "k0 0.001 1/s, reaches 0.01 1/s" in line


def test_a_lag_too_fast_for_slow_is_an_integrator_on_the_standard_mode(tmp_path):
    """A 5 ms actuator model: on the GP-6 (1 s) its feedback pot would need 200, so it is a summer
    with an external capacitor; on THE ANALOG THING the standard 1000 1/s mode carries it as an
    integrator with its output fed back through a pot at 0.2 (1/(k0 tau)), no external part."""
    text = (design_path("bench-recommended")).read_text().replace("tau = 0.2 ", "tau = 0.005 ")
    spec = tmp_path / "fast-lag.toml"
    spec.write_text(text)
    d, gp6 = design_from_path(spec)
    assert d.spec.actuator.tau == 0.005
    on_gp6 = build_patch(d, gp6)
    assert next(a for a in on_gp6.amplifiers if a.carries.quantity == "actuator").role == "lag"
    assert any(p.kind == "capacitor" for p in on_gp6.parts)
    net = build_patch(d, THAT)
    a = next(a for a in net.amplifiers if a.carries.quantity == "actuator")
    assert a.role == "integrator" and a.mode == Mode(name="standard", k0_per_s=1000.0, jumper=None)
    own = next(p for p in net.pots if p.amplifier == a.id and p.source == a.id)
    assert own.weight * own.setting == pytest.approx(1 / (1000.0 * 0.005), abs=THAT.pot_resolution / 2)
    assert not any(p.amplifier == a.id for p in net.parts)
    check_roundtrip(d, net, THAT.pot_resolution)
