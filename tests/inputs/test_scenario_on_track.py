"""A scenario sized for any bench: the cart's offset (initial.s_track) and a step (size_track) as
fractions of the track length d, turned into metres for the plant the scenario meets."""

from __future__ import annotations

import pytest

from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import Scenario, check_on_track
from patchgen.inputs.spec import load_spec
from patchgen.inputs.validation import validate
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import load_bench
from patchgen.profiles.machine import load_machine

RELATIVE = {"duration_s": 6.0, "initial": {"s_track": 0.25, "theta_deg": 2.0},
            "disturbances": [{"kind": "step", "time_s": 2.0, "size_track": -0.125}], "noise": "off"}


def test_fractions_of_the_track_become_metres_on_each_track():
    sc = validate(Scenario, RELATIVE, "relative.toml")
    for d in (1.09, 0.814, 0.5):
        sized = sc.on_track(d)
        assert sized.initial.s == 0.25 * d and sized.initial.s_track is None
        assert sized.disturbances[0].size_m == -0.125 * d and sized.disturbances[0].size_track is None
        assert sized.initial.theta_deg == 2.0 and sized.duration_s == 6.0
    plain = validate(Scenario, {"duration_s": 1.0, "initial": {"s": 0.1}}, "plain.toml")
    assert plain.on_track(0.5) is plain


def test_a_relative_scenario_runs_as_its_metres_would():
    spec = load_spec("bench-recommended")
    machine, bench = load_machine("gp6"), load_bench("uw-1991")
    net = build_patch(design_on(spec, machine, bench), machine)
    plant = plant_params(spec)
    relative = validate(Scenario, RELATIVE, "relative.toml")
    metres = validate(Scenario, {**RELATIVE, "initial": {"s": 0.25 * plant.d, "theta_deg": 2.0},
                                 "disturbances": [{"kind": "step", "time_s": 2.0, "size_m": -0.125 * plant.d}]},
                      "metres.toml")
    a, b = (simulate(net, plant, bench, machine, sc) for sc in (relative, metres))
    assert a.runs == b.runs
    assert a.history["s"][0] == 0.25 * plant.d
    assert (a.history["s"] == b.history["s"]).all() and (a.history["s_ref"] == b.history["s_ref"]).all()
    assert a.history["s_ref"][-1] == pytest.approx(-0.125 * plant.d, rel=1e-12)  # the step, in metres of this track


@pytest.mark.parametrize("data, field", [
    ({"duration_s": 1.0, "initial": {"s_track": 0.6}}, "initial.s_track"),
    ({"duration_s": 1.0, "initial": {"s": 0.1, "s_track": 0.1}}, "initial.s_track"),
    ({"duration_s": 1.0, "disturbances": [{"kind": "step", "time_s": 0.5, "size_track": 0.1, "size_m": 0.1}]},
     "disturbances[0].size_m"),
    ({"duration_s": 1.0, "disturbances": [{"kind": "step", "time_s": 0.5, "size_track": 1.5}]},
     "disturbances[0].size_track"),
    ({"duration_s": 1.0, "disturbances": [{"kind": "force_impulse", "time_s": 0.5, "at": "cart", "duration_s": 0.1,
                                           "force_N": 1.0, "size_track": 0.1}]}, "disturbances[0].size_track"),
])
def test_a_fraction_it_cannot_take_is_one_line(data, field):
    with pytest.raises(InputError) as exc:
        validate(Scenario, data, "bad.toml")
    assert exc.value.line().startswith(f"bad.toml: {field}: ") and "\n" not in exc.value.line()


def test_half_the_track_is_at_the_switch():
    sc = validate(Scenario, {"duration_s": 1.0, "initial": {"s_track": -0.5}}, "edge.toml")
    with pytest.raises(InputError) as exc:
        check_on_track(sc, 0.814, "spec.toml")
    assert "-0.407 m is outside the track" in exc.value.line()
    check_on_track(validate(Scenario, {"duration_s": 1.0, "initial": {"s_track": 0.49}}, "in.toml"), 0.814, "s")
