"""A lab without a velocity signal: the spec reads s and theta only (sensors.measured), the bench
states no s_dot, and the patch finds s_dot from s as it finds theta_dot from theta. The law is
checked against the state feedback with each rate from its position through the roll-off's
first-order differentiator, frequency by frequency; the patch has the two differentiators and
reads two sensors; the bench simulation holds; what cannot be built is one line."""

from __future__ import annotations

import numpy as np
import pytest

from patchgen.bench.simulate import simulate
from patchgen.design.lqg import design_on
from patchgen.design.model import plant_params
from patchgen.inputs.errors import InputError
from patchgen.inputs.scenario import load_scenario
from patchgen.inputs.spec import load_spec
from patchgen.patch.build import build_patch
from patchgen.profiles.bench import check_reads, load_bench
from patchgen.profiles.machine import load_machine
from tests.cli_run import run_patchgen

GP6 = load_machine("gp6")
IP02 = load_bench("quanser-ip02")
# the IP02's bench as a lab without its velocity filter has it: no s_dot signal at all
NO_VELOCITY = IP02.model_copy(update={"sensors": IP02.sensors.model_copy(
    update={"s_dot": None, "velocity_filter": {}, "noise_V_rms": {"s": 0.001, "theta": 0.001}})})


def _spec(kind: str = "filtered_differentiator"):
    spec = load_spec("quanser-ip02")
    sensors = spec.sensors.model_copy(update={"measured": ["s", "theta"], "labels": {}})
    return spec.model_copy(update={"sensors": sensors, "estimator": spec.estimator.model_copy(
        update={"kind": kind, "rolloff_s": 0.02 if kind == "differentiator" else None})})


@pytest.mark.parametrize("kind", ["differentiator", "filtered_differentiator"])
def test_the_law_is_state_feedback_with_both_rates_differentiated(kind):
    d = design_on(_spec(kind), GP6, NO_VELOCITY)
    assert d.model.measured == ("s", "theta") and set(d.estimator.states) == {"s_dot", "theta_dot"}
    ctl, roll = d.controller, d.estimator.rolloff_s
    K = d.K[0]
    idx = {s: d.model.index(s) for s in ("s", "theta", "s_dot", "theta_dot")}
    for w in (0.1, 1.0, 10.0, 100.0):
        jw = 1j * w
        dif = jw / (roll * jw + 1.0)  # a first-order differentiator with the roll-off
        want = -np.array([K[idx["s"]] + K[idx["s_dot"]] * dif, K[idx["theta"]] + K[idx["theta_dot"]] * dif])
        got = (ctl.Cc @ np.linalg.solve(jw * np.eye(len(ctl.Ac)) - ctl.Ac, ctl.Bc) + ctl.Dc)[0]
        np.testing.assert_allclose(got, want, rtol=1e-9)


def test_the_patch_reads_two_sensors_and_holds_on_the_bench():
    d = design_on(_spec(), GP6, NO_VELOCITY)
    net = build_patch(d, GP6)
    assert [s.quantity for s in net.sensors] == ["s", "theta"]
    assert sum(a.role == "differentiator" for a in net.amplifiers) == 2
    res = simulate(net, plant_params(d.spec), NO_VELOCITY, GP6, load_scenario("ip02-tap"), runs=8)
    assert res.distribution.fraction_held == 1.0 and res.distribution.fraction_overloaded == 0.0


def test_what_cannot_be_built_is_refused():
    spec = _spec()
    with pytest.raises(InputError, match="s_dot") as exc:  # the spec reads s_dot on a bench without it
        check_reads(NO_VELOCITY, load_spec("quanser-ip02").sensors.read(), "b.toml")
    assert exc.value.field == "sensors.s_dot"
    check_reads(NO_VELOCITY, spec.sensors.read(), "b.toml")  # reading s and theta alone: fine
    with pytest.raises(InputError, match="reduced observer is built for a measured s_dot"):
        design_on(_spec("reduced_observer"), GP6, NO_VELOCITY)


def test_a_spec_that_reads_no_position_is_one_line(tmp_path):
    text = (tmp_path / "spec.toml")
    src = load_spec("quanser-ip02").path
    from patchgen.inputs.resources import resolve
    body = resolve("design", src).read_text().replace('labels = {', 'measured = ["theta", "s_dot"]\nx = {')
    body = body.replace("\nx = {", "\n#")
    text.write_text(body)
    r = run_patchgen("patch", str(text), "-o", str(tmp_path / "o"))
    assert r.returncode == 2 and "sensors.measured" in r.stderr and "must include s" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
