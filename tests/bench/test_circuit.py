"""Compiling a netlist into the simulator's arrays: order, gains, loops, bad references."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from patchgen.bench.circuit import DIFFERENTIATOR, INTEGRATOR, SUMMER, compile_circuit
from patchgen.inputs.errors import InputError
from patchgen.patch.netlist import Netlist, read_netlist
from patchgen.patch.reading import AlgebraicLoopError
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine

ROOT = Path(__file__).resolve().parents[2]
GP6 = load_machine("gp6")
UW = load_bench("uw-1991")


@pytest.fixture()
def data() -> dict:
    return read_netlist(ROOT / "tests/fixtures/thesis-ch5.netlist.json").model_dump(by_alias=True)


def _amp(data: dict, amp_id: str) -> dict:
    return next(a for a in data["amplifiers"] if a["id"] == amp_id)


def test_ch5_compiles_as_wired(data):
    c = compile_circuit(Netlist.model_validate(data), GP6, UW)
    assert c.sensor_ids == ("s", "theta", "s_dot")
    # integrator first (its output is a state), then feed-through amplifiers after their sources
    assert c.amp_ids[0] == "A1"
    assert c.amp_ids.index("A7") > max(c.amp_ids.index("A5"), c.amp_ids.index("A6"))
    assert c.output_index == c.signal_index("A7")
    j = c.amp_ids.index("A6")
    gains = dict(zip(c.in_src[c.in_ptr[j]:c.in_ptr[j + 1]], c.in_gain[c.in_ptr[j]:c.in_ptr[j + 1]]))
    # fixture pots: P1 0.226 on x1, P2 0.267 and P3 0.271 on x10
    assert gains == pytest.approx({c.signal_index("s"): 0.226, c.signal_index("theta"): 2.67,
                                   c.signal_index("s_dot"): 2.71})
    kinds = dict(zip(c.amp_ids, c.amp_kind))
    assert (kinds["A1"], kinds["A5"], kinds["A6"]) == (INTEGRATOR, DIFFERENTIATOR, SUMMER)
    k5 = c.amp_ids.index("A5")
    assert c.param1[k5] == pytest.approx(1.0 / 0.01) and c.param2[k5] == pytest.approx(100.0)


def test_order_does_not_depend_on_listing_order(data):
    data["amplifiers"].reverse()
    c = compile_circuit(Netlist.model_validate(data), GP6, UW)
    assert c.amp_ids.index("A7") > c.amp_ids.index("A6")


def test_missing_rolloff_takes_the_machine_default(data):
    _amp(data, "A5")["rolloff_s"] = None
    c = compile_circuit(Netlist.model_validate(data), GP6, UW)
    k5 = c.amp_ids.index("A5")
    assert c.param2[k5] == pytest.approx(1.0 / GP6.imperfections.differentiator_rolloff_s)


def test_algebraic_loop_is_refused(data):
    _amp(data, "A6")["inputs"].append({"source": "A7", "pot": None, "weight": 1, "jack": "x1b"})
    with pytest.raises(AlgebraicLoopError, match="algebraic loop A6 -> A7 -> A6|A7 -> A6 -> A7"):
        compile_circuit(Netlist.model_validate(data), GP6, UW)


def test_a_loop_through_an_integrator_is_fine(data):
    _amp(data, "A1")["inputs"].append({"source": "A7", "pot": None, "weight": 1, "jack": "x1b"})
    c = compile_circuit(Netlist.model_validate(data), GP6, UW)
    # the integrator stays first (a state), and now reads A7's output back at unit gain
    assert c.amp_ids[0] == "A1"
    j = c.amp_ids.index("A1")
    inputs = dict(zip(c.in_src[c.in_ptr[j]:c.in_ptr[j + 1]], c.in_gain[c.in_ptr[j]:c.in_ptr[j + 1]]))
    assert inputs == {c.signal_index("theta"): 1.0, c.signal_index("A7"): 1.0}


def test_unknown_source_names_the_field(data):
    _amp(data, "A7")["inputs"][0]["source"] = "A9"
    with pytest.raises(InputError) as exc:
        compile_circuit(Netlist.model_validate(data), GP6, UW)
    assert "inputs[0].source" in exc.value.field and "A9" in exc.value.message


def _patched(design: str, machine: str):
    from patchgen.patch.build import build_patch
    from tests.conftest import design_from_path, design_path

    d, m = design_from_path(design_path(design), machine)
    return d, m, build_patch(d, m)


def test_internal_rates_are_the_compensators_modes():
    """bench-lqg on THE ANALOG THING keeps all five states of its compensator, one of them at
    1259 1/s: the circuit's own modes are the eigenvalues of the design's A_c (a similarity), to
    the pots' quantisation (measured 0.11 % on the fastest), and the step resolves the fastest."""
    from patchgen.bench.configure import engine_config
    from patchgen.inputs.scenario import Scenario, load_scenario

    d, m, net = _patched("bench-lqg", "the-analog-thing")
    c = compile_circuit(net, m, UW)
    modes = np.sort(np.abs(np.linalg.eigvals(d.controller.Ac)))
    assert len(modes) == 5 and modes[-1] > 1000
    np.testing.assert_allclose(np.sort(c.internal_rates()), modes, rtol=5e-3)
    assert c.time_rates() == []  # no lag or differentiator element: only the modes show the fast one
    base = load_scenario(ROOT / "sims" / "hold-120s.toml")
    for ideal in (True, False):
        _, settings = engine_config(c, d.plant, UW, m, Scenario.model_validate(base.model_dump()), ideal=ideal)
        assert settings.dt_s <= 1.0 / modes[-1] * (1 + 1e-9)


def test_a_difference_has_its_lags_mode():
    """On the LUCIDAC the rate is theta minus its lag, an integrator closed through a summer: no
    element has the roll-off as its time constant, the circuit's mode does (1 / rolloff)."""
    d, m, net = _patched("bench-recommended", "lucidac")
    c = compile_circuit(net, m, UW)
    assert c.time_rates() == []
    rolloff = d.estimator.rolloff_s
    fast = max(c.internal_rates())
    assert fast == pytest.approx(1.0 / rolloff, rel=5e-3)
