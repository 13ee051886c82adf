"""patchgen export --machine lucidac, checked by the LUCIDAC's client library (lucipy): its sanity
check, its simulator replaying patchgen's ideal run of the same patch on offset-10deg, and its
protocol emulator receiving the configuration over localhost as a real client sends it."""

from __future__ import annotations

import dataclasses
import json
import re
from importlib import resources

import numpy as np
import pytest
from scipy.signal import lsim

lucipy = pytest.importorskip("lucipy", reason="lucipy (pip install 'patchgen[lucidac]') checks the LUCIDAC export")

from patchgen.bench.simulate import simulate  # noqa: E402
from patchgen.design.lqg import design_on  # noqa: E402
from patchgen.lucidac.config import circuit  # noqa: E402
from patchgen.pipeline.export import ExportPlan, run_export  # noqa: E402
from patchgen.pipeline.inputs import load_inputs, scenario_for  # noqa: E402
from patchgen.render.lucidac_files import export_files  # noqa: E402

from .replay import Replay, replay  # noqa: E402

TOLERANCE = 0.01  # of each signal's peak (the criterion)
RECORD_S = 1e-3  # patchgen's record of its own run, at its default step (the difference's lag sets it: 6.3 ms)
# lucipy's check counts multipliers 0 and 1 as in use when identity elements (whose inputs are
# theirs, circuits.DefaultLUCIDAC.make) are: these notices, and only these, are expected
MULTIPLIER_NOTICE = "Multiplier"


@pytest.fixture(scope="module")
def exported():
    inputs = load_inputs("bench-recommended", machine="lucidac")
    report = run_export(inputs, ExportPlan(run_s=10.0, scenario="offset-10deg"))
    sc = scenario_for("offset-10deg", inputs.spec, 1, True).model_copy(update={"record_dt_s": RECORD_S})
    plant = design_on(inputs.spec, inputs.machine, inputs.bench).plant
    own = simulate(report.netlist, plant, inputs.bench, inputs.machine, sc, ideal=True).history
    return report, own


def _errors(lp, own, out) -> dict[str, tuple[float, float]]:
    """Per signal: largest difference / peak, and the peak (V); patchgen's amplifiers, u_c, and the
    elements the netlist does not have against what they stand for (sensor buffers, gain stages)."""
    ref = {e.name: own[e.name] for e in lp.elements if e.name in own}
    ref["u_c"] = own["u_c"]
    for e in lp.elements:
        if e.amp in lp.sensor_acl:  # a buffer: the sensor's volts through its lag 1/k0 (the netlist has none)
            volts = lp.sensor_volts_per_unit[e.amp] * own[e.amp]
            ref[e.name] = lsim(([1.0], [1.0 / e.k0_per_s, 1.0]), volts, own["t"], X0=[volts[0] * e.k0_per_s])[1]
        elif e.name not in own and " x" in e.amp:  # a gain stage: its source's volts
            ref[e.name] = own[e.amp.split(" x")[0]]
    return {k: (float(np.max(np.abs(out[k] - v)) / np.max(np.abs(v))), float(np.max(np.abs(v))))
            for k, v in ref.items()}


def test_lucipy_sanity_check_finds_no_error(exported):
    report, _ = exported
    warnings = circuit(report.lanes).sanity_check(also_print=False)
    assert warnings == list(report.warnings)
    assert warnings and all(w.split()[0 if w.startswith("Multiplier") else 1] == MULTIPLIER_NOTICE for w in warnings)
    for r in circuit(report.lanes).routes:
        assert r.sanity_list() == []
    ids = [e.index for e in report.lanes.elements if e.kind == "id"]
    assert {int(w.split("Multiplier ")[1][0]) for w in warnings} == {i // 2 for i in ids if i < 4}


def test_placement_of_bench_recommended(exported):
    report, _ = exported
    lp = report.lanes
    assert lp.sensor_acl == {"s": 0, "theta": 1, "s_dot": 2} and lp.output_acl == 3
    assert len(lp.lanes) <= 32
    assert all(abs(ln.coeff) <= 10 for ln in lp.lanes)
    out = [ln for ln in lp.lanes if ln.target.startswith("ACL_OUT")]
    assert len(out) == 1 and out[0].coeff == 1.0  # no upscaling behind the C block on a front-panel output
    theta = next(ln for ln in lp.lanes if ln.source == "ACL_IN 1")
    assert theta.coeff == 1.0 and lp.element(theta.target).carries == "theta_dot"  # theta minus its lag
    assert report.config["acl_select"][:3] == ["external"] * 3


def test_export_is_deterministic(exported):
    report, _ = exported
    again = run_export(load_inputs("bench-recommended", machine="lucidac"), report.plan)
    assert export_files(again) == export_files(report)
    assert json.loads(export_files(report)["lucidac-config.json"]) == report.config


def test_replay_agrees_with_patchgen(exported):
    report, own = exported
    out = replay(circuit(report.lanes), report.lanes, own)
    errors = _errors(report.lanes, own, out)
    assert set(errors) >= {"u_c", "I0", "I1", "ID0", "ID1"}
    for name, (err, peak) in errors.items():
        assert err < TOLERANCE, f"{name}: {err:.3%} of its peak {peak:.3g} V"
    assert 1.0 < errors["u_c"][1] < 10.0  # the lag starts settled on theta: no kick at t = 0, no overload


@pytest.mark.parametrize("source", ["I0", "s_dot", "s"])
def test_replay_fails_for_a_wrong_sign(exported, source):
    """One lane into u_c's element with its sign flipped: the lag of theta (measured 200 % of u_c's
    peak), s_dot's buffer (23 %) or s's, the smallest coefficient (0.107: 1.6 %)."""
    report, own = exported
    lp = report.lanes
    feeder = next(e.name for e in lp.elements if e.amp == source)
    k = next(i for i, ln in enumerate(lp.lanes) if ln.source == feeder and ln.target == "ID1")
    flipped = dataclasses.replace(lp.lanes[k], coeff=-lp.lanes[k].coeff)
    wrong = dataclasses.replace(lp, lanes=lp.lanes[:k] + (flipped,) + lp.lanes[k + 1:])
    err, _ = _errors(lp, own, replay(circuit(wrong), wrong, own))["u_c"]
    assert err > TOLERANCE


def test_replay_is_lucipys_simulation_where_lucipy_models_the_machine(exported):
    """With the front-panel inputs at 0 and the identity elements at 0 (lucipy 1.7's Mul_out), the
    subclass's right-hand side is lucipy's own."""
    report, _ = exported
    c = circuit(report.lanes)
    ours = Replay(c, lambda t: np.zeros(8), identities=False)
    theirs = lucipy.Simulation(c, realtime=True)
    x = np.linspace(-0.5, 0.5, 8)
    assert np.allclose(ours.rhs(0.0, x.copy()), theirs.rhs(0.0, x.copy()), rtol=1e-12, atol=1e-12)
    assert np.any(ours.rhs(0.0, x.copy()) != 0)


def test_emulator_accepts_and_runs_the_configuration(exported):
    report, _ = exported
    from lucipy.simulator import Emulation

    emu = Emulation(bind_port=0)
    proc = emu.serve_forking()
    try:
        hc = lucipy.LUCIDAC(emu.endpoint())
        assert hc.set_circuit(report.config) is None  # an error comes back as an exception or a message
        assert hc.get_circuit()["config"] == json.loads(json.dumps(report.config))
        hc.set_op_time(ms=5)
        data = hc.start_run().data()
        assert len(data) > 0 and all(len(row) == 1 for row in data)  # u_c's element on ADC 0
        hc.close()
    finally:
        proc.terminate()
        proc.join()


def test_the_export_says_how_the_patch_does_on_the_bench(exported, tmp_path):
    """The patch is predicted on the bench as patch's sheet predicts it: bench-recommended on the
    LUCIDAC holds every scenario on uw-1991. A patch that falls is not handed out unsaid: on a
    LUCIDAC whose integrators' offsets were ten times the profile's (10 mV), the lag of theta drifts
    the rate it gives, the cart runs to the track's end, and the command says so in one line."""
    from tests.cli_run import run_patchgen

    report, _ = exported
    pred = report.prediction
    assert pred is not None and [p.scenario for p in pred.predictions] == ["offset-10deg", "finger-push",
                                                                          "step-cart", "hold-120s"]
    assert report.summary()["prediction"] == pred.summary()
    assert pred.holds and all(p.fraction_held >= 0.95 for p in pred.predictions)
    assert all(lv.peak_share <= 1.0 for lv in pred.levels)  # no element past the reference
    r = run_patchgen("export", "bench-recommended", "--machine", "lucidac", "-o", tmp_path / "out")
    assert r.returncode == 0
    assert "predicted on the uw-1991 bench: held in every scenario" in r.stdout
    text = (resources.files("patchgen.profiles") / "machines" / "lucidac.toml").read_text()
    drifting = tmp_path / "lucidac-drifting.toml"
    drifting.write_text(re.sub(r"(?m)^integrator_offset_V = .*$", "integrator_offset_V = 0.01", text))
    r = run_patchgen("export", "bench-recommended", "--machine", drifting, "-o", tmp_path / "drifting")
    assert r.returncode == 0
    assert "Predicted to fail on the uw-1991 bench: held in " in r.stdout
