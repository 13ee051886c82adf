"""The Quanser IP02 bench as a patch meets it: recommend's choice holds in its own scenarios with
the velocity filter and the encoder counts in the simulation, the command's saturation at the
amplifier is reported and not counted as an overload, and the bench's linearisation (motor,
filter) is the one python-control builds from the same parts."""

from __future__ import annotations

import json

import control
import numpy as np
import pytest
from click.testing import CliRunner

from patchgen.bench.bench_linear import bench_plant
from patchgen.bench.circuit import compile_circuit
from patchgen.bench.configure import engine_config, harmless_overloads
from patchgen.bench.simulate import simulate
from patchgen.cli import cli
from patchgen.design.lti import load_design
from patchgen.design.model import plant_params
from patchgen.inputs.scenario import load_scenario
from patchgen.patch.build import build_patch
from patchgen.plant.drive import DCMotor
from patchgen.profiles.bench import bench_scenarios, load_bench
from patchgen.profiles.machine import load_machine

pytestmark = pytest.mark.heavy(10)  # seconds, roughly: see tests/conftest.py

BENCH = load_bench("quanser-ip02")
GP6 = load_machine("gp6")


@pytest.fixture(scope="module")
def recommended(tmp_path_factory):
    out = tmp_path_factory.mktemp("ip02")
    res = CliRunner().invoke(cli, ["recommend", "quanser-ip02", "-o", str(out), "--json"])
    assert res.exit_code == 0, res.output
    return out, json.loads((out / "recommendation.json").read_text())


def test_recommend_chooses_a_patch_that_holds_every_ip02_scenario(recommended):
    out, rec = recommended
    assert {s["name"] for s in rec["scenarios"]} == set(bench_scenarios(BENCH))  # the bench's own four
    best = next(c for c in rec["candidates"] if c["realisation"] == rec["chosen"])
    assert best["bench_loop"] == "stable" and best["decision"] == "holds"
    for sc in best["scenarios"]:
        assert sc["fraction_held"] >= 0.95 and sc["interval_95"][0] >= 0.95 and sc["overloaded"] == 0
        assert 0 <= sc["at_actuator_limit"] <= sc["runs"]
    # the spec's own stiff patch asks past the rails from a 5 deg release: it is not the one chosen
    own = [c for c in rec["candidates"] if c.get("decision") and ";" not in c["realisation"]]
    assert own and all(c["decision"] == "fails" for c in own)
    # their command sits at the amplifier's limit from the release: reported, beside their overloads
    release = [s for c in own for s in c["scenarios"] if s["scenario"] == "ip02-release-5deg"]
    assert release and all(s["at_actuator_limit"] > 0 for s in release)
    assert (out / "recommended.toml").exists()


def test_the_bench_simulation_has_the_counts_the_filter_and_the_motor():
    d = load_design("quanser-ip02")
    net = build_patch(d, GP6)
    cfg, settings = engine_config(compile_circuit(net, GP6, BENCH), plant_params(d.spec), BENCH, GP6,
                                  load_scenario("ip02-tap"))
    q = dict(zip((s.quantity for s in net.sensors), cfg.sensors.quantum))
    assert q["theta"] == pytest.approx(2 * np.pi / 4096) and q["s"] == pytest.approx(1 / 43956.0)
    assert q["s_dot"] == q["s"]  # the filter reads the cart's encoder
    s_dot = [s.quantity for s in net.sensors].index("s_dot")
    assert cfg.sensors.filt[s_dot] == 0 and cfg.sensors.wn[s_dot] == pytest.approx(62.832)
    motor = DCMotor(R_m=2.6, K_t=0.00767, K_m=0.00767, K_g=3.71, J_m=3.9e-7, r_pinion=6.35e-3)
    assert cfg.plant[0] == pytest.approx(0.94 + motor.referred_mass(), rel=1e-12)  # the rotor on the cart
    assert "back-EMF" in settings.actuator and "amplifier limit +/-10 V" in settings.actuator


def test_saturation_at_the_amplifier_is_reported_not_counted_as_an_overload():
    """The spec's own patch (Quanser's weights) released from 5 deg asks 16 V of the 10 V amplifier:
    the command sits at the limit (reported); the law's partial summer past the rails is an
    overload. The command's summer alone past the rails is not one."""
    d = load_design("quanser-ip02")
    net = build_patch(d, GP6)
    circuit = compile_circuit(net, GP6, BENCH)
    cfg, _ = engine_config(circuit, plant_params(d.spec), BENCH, GP6, load_scenario("ip02-release-5deg"))
    command = harmless_overloads(circuit, cfg)
    assert command == (circuit.amp_ids[circuit.output_index - circuit.n_sensors],)
    res = simulate(net, plant_params(d.spec), BENCH, GP6, load_scenario("ip02-release-5deg"), runs=3)
    for r in res.runs:
        assert r.actuator_limit_time_s > 0
        assert r.overloads and command[0] not in {o.amplifier for o in r.overloads}
    assert res.distribution.fraction_at_actuator_limit == 1.0
    # a lag actuator keeps a state past its input's clip: there the command's excursion stays an overload
    uw = load_bench("uw-1991")
    cfg_uw, _ = engine_config(compile_circuit(net, GP6, uw), plant_params(d.spec), uw, GP6,
                              load_scenario("ip02-tap"))
    assert harmless_overloads(compile_circuit(net, GP6, uw), cfg_uw) == ()
    # an amplifier that gives the motor more than the rails ask is not limited within them
    act = BENCH.actuator.model_dump(exclude={"force_limit_N"}) | {"V_limit": 25.0}
    loud = BENCH.model_copy(update={"actuator": type(BENCH.actuator).model_validate(act)})
    assert loud.actuator.force_limit_N == pytest.approx(BENCH.actuator.K_U * 25.0)
    cfg_loud, _ = engine_config(circuit, plant_params(d.spec), loud, GP6, load_scenario("ip02-tap"))
    assert harmless_overloads(circuit, cfg_loud) == ()


def test_the_linearised_bench_is_the_parts_in_series():
    """u_c -> the driven plant -> (s, theta, and s_dot through wn^2 s / (s^2 + 2 zeta wn s + wn^2)),
    each times its sensor constant: built with python-control from the same figures."""
    d = load_design("quanser-ip02")
    net = build_patch(d, GP6)
    bp = bench_plant(net, plant_params(d.spec), BENCH)
    ours = control.ss(bp.A, bp.B, bp.C, np.zeros((bp.C.shape[0], 1)))
    G = control.ss(*[m for m in (plant_ss_matrices(d))])
    wn, ze = 62.832, 0.9
    filt = control.tf([wn ** 2, 0], [1, 2 * ze * wn, wn ** 2])
    gains = {"s": 10.0, "theta": 20.0, "s_dot": 5.0}
    for r, sensor in enumerate(net.sensors):
        q = sensor.quantity
        want = (filt * G[0, 0] if q == "s_dot" else G[["s", "theta"].index(q), 0]) * gains[q]
        for w in (0.3, 3.0, 30.0, 300.0):
            a, b = ours[r, 0](1j * w), want(1j * w)
            assert abs(a - b) <= 1e-9 * abs(b), (q, w)


def plant_ss_matrices(d):
    """s and theta per command volt of the design's driven plant (the motor's, folded in)."""
    from patchgen.design.lti import plant_ss
    sys = plant_ss(d, ("s", "theta"), input="u_c")
    return sys.A, sys.B, sys.C, sys.D


def test_the_watchdog_ends_a_run_before_the_rail_does():
    """The IP02's scripts cut the motor at |s| > 0.3 m on a 0.814 m rail: a run ends there."""
    d = load_design("quanser-ip02")
    assert d.spec.plant.d == pytest.approx(0.814) and BENCH.track.cut_at(d.spec.plant.d) == pytest.approx(0.3)
    net = build_patch(d, GP6)
    cfg, settings = engine_config(compile_circuit(net, GP6, BENCH), plant_params(d.spec), BENCH, GP6,
                                  load_scenario("ip02-tap"))
    assert cfg.plant[6] == pytest.approx(0.3) and settings.watchdog_m == 0.3
    far = load_scenario("ip02-tap").model_copy(update={"initial": load_scenario("ip02-tap").initial.model_copy(
        update={"s": 0.31})})
    res = simulate(net, plant_params(d.spec), BENCH, GP6, far, runs=2)
    assert all(r.limit_switch_tripped and r.trip_time_s < 0.01 for r in res.runs)
    no_dog = BENCH.model_copy(update={"track": BENCH.track.model_copy(update={"watchdog_m": None})})
    assert no_dog.track.cut_at(0.814) == pytest.approx(0.407)
    for r in simulate(net, plant_params(d.spec), no_dog, GP6, far, runs=2).runs:  # not cut where it starts
        assert not r.limit_switch_tripped or r.trip_time_s > 0.1
